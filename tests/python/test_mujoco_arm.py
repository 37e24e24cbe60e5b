"""neurarm's arm against MuJoCo, an independent rigid-body engine: the same 4-link arm, no
friction, the same RK4 at the same 1 ms step, so the trajectories must agree to round-off."""
import subprocess
import sys

import numpy as np

from arm_files import arm_toml, constant_torque_csv

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[2] / "benches" / "python"))
import mujoco_arm  # noqa: E402


def test_frictionless_trajectory_matches_mujoco(neurarm, tmp_path):
    config = tmp_path / "arm.toml"
    config.write_text(arm_toml(mujoco_arm.MASSES))
    torque = tmp_path / "tau.csv"
    constant_torque_csv(torque, mujoco_arm.TAU, seconds=1.0)
    ours_csv = tmp_path / "ours.csv"
    subprocess.run([neurarm, "simulate", "-c", config, "-t", torque,
                    "--q0", ",".join(map(repr, mujoco_arm.Q0)), "--qd0", ",".join(map(repr, mujoco_arm.QD0)),
                    "-o", ours_csv], check=True)
    ours = np.genfromtxt(ours_csv, delimiter=",", names=True)
    mj_csv = tmp_path / "mujoco.csv"
    mujoco_arm.trajectory(str(mj_csv), seconds=1.0)
    mj = np.loadtxt(mj_csv, delimiter=",", skiprows=1)
    assert len(ours) == len(mj) == 1001
    q = np.stack([ours[f"q_{i}"] for i in range(1, 5)], axis=1)
    qd = np.stack([ours[f"qd_{i}"] for i in range(1, 5)], axis=1)
    assert np.abs(q[-1] - np.array(mujoco_arm.Q0)).max() > 0.5, "the arm must actually move"
    assert np.abs(q - mj[:, 1:5]).max() < 1e-10
    assert np.abs(qd - mj[:, 5:9]).max() < 1e-9


def test_mujoco_model_is_the_arm_we_think():
    """Guards the comparison itself: MuJoCo's mass matrix equals Pinocchio's values in
    tests/data/dynamics-reference.json at every reference state."""
    import json
    import pathlib

    import mujoco
    reference = pathlib.Path(__file__).resolve().parents[2] / "crates" / "physics" / "tests" / "data" / "dynamics-reference.json"
    cases = json.loads(reference.read_text())["cases"]
    model, data = mujoco_arm.make(False)
    for case in cases:
        data.qpos[:] = case["q"]
        mujoco.mj_forward(model, data)
        h = np.zeros((4, 4))
        mujoco.mj_fullM(model, data, h)
        assert np.abs(h - np.array(case["mass_matrix"])).max() < 1e-12
