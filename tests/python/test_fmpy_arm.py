"""The PlanarArm FMU under fmpy, an independent FMI master: it validates, and its simulation
equals neurarm's in-process simulation of the same arm under the same torques."""
import subprocess

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from arm_files import arm_toml

Q0 = [0.3, -0.5, 0.7, -0.2]
QD0 = [0.5, 0.0, -1.0, 0.0]
OUTPUTS = [f"q_{i}" for i in range(1, 5)] + [f"qd_{i}" for i in range(1, 5)] + ["x", "y", "xd", "yd"]


def export(neurarm, out, *args):
    subprocess.run([neurarm, "export", "arm", *args, "-o", out], check=True)
    return out


@pytest.fixture(scope="module")
def arm_fmu(neurarm, tmp_path_factory):
    out = tmp_path_factory.mktemp("fmu") / "PlanarArm.fmu"
    return export(neurarm, out, "--q0", ",".join(map(repr, Q0)), "--qd0", ",".join(map(repr, QD0)))


def test_fmpy_validate_finds_no_problem(neurarm, arm_fmu, tmp_path):
    assert validate_fmu(str(arm_fmu)) == []
    md = read_model_description(str(arm_fmu))
    assert md.coSimulation.modelIdentifier == "PlanarArm"
    assert len([v for v in md.modelVariables if v.causality == "output"]) == 20


def test_three_joint_config_validates(neurarm, tmp_path):
    config = tmp_path / "arm3.toml"
    config.write_text(arm_toml([2.0, 1.5, 1.0], coulomb=[1.0, 0.8, 0.4], viscous=[0.5, 0.4, 0.2], internal_step_s=2.5e-4))
    fmu = export(neurarm, tmp_path / "Arm3.fmu", "-c", config)
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    assert md.coSimulation.modelIdentifier == "Arm3"
    names = {v.name for v in md.modelVariables}
    assert "tau_3" in names and "tau_4" not in names
    result = simulate_fmu(str(fmu), stop_time=0.5, output_interval=1e-3, start_values={"q0_2": 0.4})
    assert result["q_2"][0] == 0.4


def torque_table(step, seconds=5.0):
    n = int(round(seconds / step))
    t = np.array([k * step for k in range(n + 1)])
    tau = np.stack([3.0 * np.sin(2.0 * t), -2.0 + np.cos(3.0 * t), 1.2 * np.sin(5.0 * t), 0.5 * np.cos(t)], axis=1)
    return t, tau


@pytest.mark.parametrize("step", [1e-3, 2e-3])
def test_fmpy_simulation_equals_in_process_rust(neurarm, arm_fmu, tmp_path, step):
    t, tau = torque_table(step)
    signals = np.zeros(len(t), dtype=[("time", np.float64)] + [(f"tau_{i}", np.float64) for i in range(1, 5)])
    signals["time"] = t
    for i in range(4):
        signals[f"tau_{i + 1}"] = tau[:, i]
    fmpy_result = simulate_fmu(str(arm_fmu), fmi_type="CoSimulation", stop_time=t[-1], output_interval=step,
                               input=signals, output=OUTPUTS)

    csv = tmp_path / "tau.csv"
    lines = ["time,tau_1,tau_2,tau_3,tau_4"] + [",".join(repr(float(v)) for v in (t[k], *tau[k])) for k in range(len(t))]
    csv.write_text("\n".join(lines) + "\n")
    out = tmp_path / "rust.csv"
    subprocess.run([neurarm, "simulate", "-t", csv, "--q0", ",".join(map(repr, Q0)), "--qd0", ",".join(map(repr, QD0)),
                    "-o", out], check=True)
    rust = np.genfromtxt(out, delimiter=",", names=True)

    assert len(fmpy_result) == len(rust) == len(t)
    assert np.array_equal(fmpy_result["time"], rust["time"])
    assert np.abs(rust["q_1"][-1] - Q0[0]) > 0.1, "the arm must move"
    worst = max(np.abs(fmpy_result[name] - rust[name]).max() for name in OUTPUTS)
    print(f"step {step}: largest |fmpy - rust| over {len(t)} points = {worst:.3e}")
    assert worst <= 1e-12, f"largest difference {worst}"
