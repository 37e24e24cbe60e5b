"""The default neurarm arm in MuJoCo: same links, masses, inertias and joint friction, RK4 at
dt = 1 ms, no contacts. Prints the time per step, and checks that MuJoCo's trajectory agrees
with neurarm's (frictionless, so both are plain RK4 of the same ODE).

Usage: mujoco_arm.py time [--friction] | mujoco_arm.py trajectory OUT.csv
"""
import json
import sys
import time

import mujoco
import numpy as np

LENGTHS = [0.25, 0.25, 0.25, 0.25]
MASSES = [2.0, 1.6, 1.2, 0.8]
COULOMB = [1.5, 1.2, 0.6, 0.3]  # N·m, neurarm's JointFriction::default_for_joint
VISCOUS = [0.8, 0.6, 0.3, 0.15]  # N·m·s/rad
Q0 = [0.3, -0.5, 0.7, -0.2]
QD0 = [1.0, -2.0, 1.5, 3.0]
TAU = [2.0, -1.0, 0.5, 0.2]


def arm_xml(friction: bool) -> str:
    body = ""
    for i, (l, m) in enumerate(zip(LENGTHS, MASSES)):
        izz = m * l * l / 12.0
        pos = "0 0 0" if i == 0 else f"{LENGTHS[i - 1]} 0 0"
        fr = f'damping="{VISCOUS[i]}" frictionloss="{COULOMB[i]}"' if friction else ""
        body += (
            f'<body name="link{i + 1}" pos="{pos}">'
            f'<joint name="j{i + 1}" type="hinge" axis="0 0 1" {fr}/>'
            f'<inertial pos="{l / 2} 0 0" mass="{m}" diaginertia="1e-9 {izz} {izz}"/>'
        )
    body += "</body>" * len(LENGTHS)
    motors = "".join(f'<motor joint="j{i + 1}" gear="1"/>' for i in range(len(LENGTHS)))
    return (
        '<mujoco><option integrator="RK4" timestep="0.001" gravity="0 0 -9.81">'
        '<flag contact="disable"/></option>'
        f"<worldbody>{body}</worldbody><actuator>{motors}</actuator></mujoco>"
    )


def make(friction: bool):
    model = mujoco.MjModel.from_xml_string(arm_xml(friction))
    data = mujoco.MjData(model)
    return model, data


def reset(model, data):
    mujoco.mj_resetData(model, data)
    data.qpos[:] = Q0
    data.qvel[:] = QD0
    data.ctrl[:] = TAU


def time_per_step(friction: bool, steps: int = 1000, repeats: int = 200) -> float:
    """Median seconds per mj_step over `repeats` runs of `steps` steps from the same start
    (the same regime as the Rust bench, which restarts every 1000 steps)."""
    model, data = make(friction)
    samples = []
    for _ in range(repeats):
        reset(model, data)
        t0 = time.perf_counter()
        mujoco.mj_step(model, data, nstep=steps)
        samples.append((time.perf_counter() - t0) / steps)
    return float(np.median(samples))


def states(steps: int, friction: bool = False):
    """q [rad] and q̇ [rad/s] at the start and after each of `steps` steps: rows of 8."""
    model, data = make(friction)
    reset(model, data)
    rows = [[*data.qpos, *data.qvel]]
    for _ in range(steps):
        mujoco.mj_step(model, data)
        rows.append([*data.qpos, *data.qvel])
    return np.array(rows)


def trajectory(path: str, seconds: float = 2.0):
    model, data = make(False)
    reset(model, data)
    rows = []
    for k in range(int(round(seconds / model.opt.timestep)) + 1):
        rows.append([data.time, *data.qpos, *data.qvel])
        mujoco.mj_step(model, data)
    np.savetxt(path, np.array(rows), delimiter=",", header="time,q1,q2,q3,q4,qd1,qd2,qd3,qd4", comments="")


if __name__ == "__main__":
    if sys.argv[1] == "time":
        friction = "--friction" in sys.argv
        print(json.dumps({"mujoco_version": mujoco.__version__, "friction": friction,
                          "seconds_per_step": time_per_step(friction)}))
    else:
        trajectory(sys.argv[2])
