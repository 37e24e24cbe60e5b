"""The controller and ideal-compensator FMUs that `neurarm export controller` and `export
compensator --ideal` write, for 3- and 6-joint arms, under fmpy: they validate, their ports
are sized for the arm, and the task-space controller's reference output is the paper's curve
placed by the documented rule (centre (0.45 R, 0.10 R), scale R for reach R)."""
import subprocess

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from arm_files import arm_toml


@pytest.fixture(scope="module", params=[3, 6])
def arm(request, tmp_path_factory):
    n = request.param
    d = tmp_path_factory.mktemp(f"arm{n}")
    config = d / "arm.toml"
    config.write_text(arm_toml([2.0 - 0.2 * i for i in range(n)], coulomb=[0.5] * n, viscous=[0.2] * n, internal_step_s=2.5e-4))
    return n, config, d


def export(neurarm, out, *args):
    subprocess.run([neurarm, "export", *args, "-o", out], check=True)
    return out


def test_exported_controllers_validate_and_fit_the_arm(neurarm, arm):
    n, config, d = arm
    fmus = {
        "task": export(neurarm, d / "Task.fmu", "controller", "task-space", "-c", config),
        "joint": export(neurarm, d / "Joint.fmu", "controller", "joint", "-c", config),
        "ideal": export(neurarm, d / "Ideal.fmu", "compensator", "--ideal", "-c", config),
    }
    for name, fmu in fmus.items():
        assert validate_fmu(str(fmu)) == [], name
        names = {v.name for v in read_model_description(str(fmu)).modelVariables}
        assert f"q_{n}" in names and f"q_{n + 1}" not in names, (name, sorted(names))
    assert {f"tau_{n}", "x_ref", "reference_scale"} <= {v.name for v in read_model_description(str(fmus["task"])).modelVariables}


def test_task_space_reference_is_placed_by_the_reach(neurarm, arm):
    n, config, d = arm
    fmu = export(neurarm, d / "Task.fmu", "controller", "task-space", "-c", config)
    r = simulate_fmu(str(fmu), stop_time=6.0, output_interval=0.01, output=["x_ref", "y_ref"])
    reach = 0.25 * n  # arm_toml's links are 0.25 m long
    t = r["time"]
    x = 0.45 * reach + reach * 0.2 * (np.cos(t) + np.sin(2 * t))
    y = 0.10 * reach + reach * 0.15 * (np.sin(t) + np.cos(2 * t))
    assert np.abs(r["x_ref"] - x).max() < 1e-12 and np.abs(r["y_ref"] - y).max() < 1e-12
