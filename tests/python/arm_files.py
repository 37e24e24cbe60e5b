"""Writes neurarm input files (arm configuration TOML, torque CSV) from Python."""
import pathlib


def arm_toml(masses, length=0.25, coulomb=None, viscous=None, internal_step_s=1e-3) -> str:
    """A configuration of uniform rods of `length` [m] and `masses` [kg] in the horizontal
    plane, with symmetric Coulomb [N·m] + viscous [N·m·s/rad] friction (none if omitted)."""
    n = len(masses)
    coulomb = coulomb or [0.0] * n
    viscous = viscous or [0.0] * n
    text = "[arm]\ngravity_m_s2 = 9.81\nbase_angle_rad = 0.0\n"
    for m in masses:
        text += (f"\n[[arm.links]]\nlength_m = {length!r}\nmass_kg = {m!r}\n"
                 f"com_m = {length / 2!r}\ninertia_kgm2 = {m * length * length / 12.0!r}\n")
    for c, v in zip(coulomb, viscous):
        branch = (f"{{ coulomb_nm = {c!r}, static_nm = {c!r}, stribeck_velocity_rad_s = 1.0, "
                  f"viscous_nms_rad = {v!r} }}")
        text += f"\n[[arm.friction]]\npositive = {branch}\nnegative = {branch}\n"
    text += f"\n[integrator]\ninternal_step_s = {internal_step_s!r}\n"
    return text


def constant_torque_csv(path: pathlib.Path, tau, seconds: float, dt: float = 1e-3):
    lines = ["time," + ",".join(f"tau_{i + 1}" for i in range(len(tau)))]
    for k in range(int(round(seconds / dt)) + 1):
        lines.append(f"{k * dt!r}," + ",".join(repr(float(t)) for t in tau))
    path.write_text("\n".join(lines) + "\n")
