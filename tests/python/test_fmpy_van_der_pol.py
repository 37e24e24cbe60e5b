"""The Van der Pol example FMU (examples/van-der-pol, written on neurarm-fmi-export, nothing to do with
robots) under fmpy: it validates; fmpy's own master runs it and the trajectory matches scipy's
solve_ivp of the same equation to 1e-6 at mu = 1; at mu = 0 it is x0 cos t; a tuned mu between
steps takes effect; a forced oscillator follows the forcing fmpy feeds it."""
import os
import pathlib
import subprocess

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu
from scipy.integrate import solve_ivp

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def fmu(tmp_path_factory):
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    tool = target / "release" / "van-der-pol-fmu"
    if not tool.exists():
        subprocess.run(["cargo", "build", "--release", "--locked", "-p", "van-der-pol"], cwd=ROOT, check=True)
    out = tmp_path_factory.mktemp("vdp") / "VanDerPol.fmu"
    subprocess.run([tool, out], check=True)
    return out


def reference(mu, x0, v0, t):
    f = lambda _, s: [s[1], mu * (1 - s[0] ** 2) * s[1] - s[0]]
    return solve_ivp(f, (t[0], t[-1]), [x0, v0], t_eval=t, rtol=1e-12, atol=1e-12, method="DOP853").y


def test_validates(fmu):
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    assert md.coSimulation.modelIdentifier == "VanDerPol"
    assert {v.name for v in md.modelVariables} == {"time", "u", "x", "v", "mu", "x0", "v0"}


def test_limit_cycle_matches_scipy(fmu):
    r = simulate_fmu(str(fmu), stop_time=20.0, output_interval=0.01, start_values={"mu": 1.0, "x0": 0.5, "v0": 0.0},
                     output=["x", "v"])
    x, v = reference(1.0, 0.5, 0.0, r["time"])
    assert np.abs(r["x"] - x).max() < 1e-6
    assert np.abs(r["v"] - v).max() < 1e-6
    # The limit cycle of mu = 1 has an amplitude of about 2.
    assert 1.9 < np.abs(r["x"][r["time"] > 10]).max() < 2.1


def test_without_damping_it_is_a_harmonic_oscillator(fmu):
    r = simulate_fmu(str(fmu), stop_time=10.0, output_interval=0.05, start_values={"mu": 0.0, "x0": 1.5}, output=["x"])
    assert np.abs(r["x"] - 1.5 * np.cos(r["time"])).max() < 1e-9


def test_forcing_enters_as_u(fmu):
    # x'' = -x + u with u = 1 from rest at 0: x = 1 - cos t.
    inputs = np.array([(0.0, 1.0), (20.0, 1.0)], dtype=[("time", np.float64), ("u", np.float64)])
    r = simulate_fmu(str(fmu), stop_time=5.0, output_interval=0.01, start_values={"mu": 0.0, "x0": 0.0}, input=inputs, output=["x"])
    assert np.abs(r["x"] - (1 - np.cos(r["time"]))).max() < 1e-9


def test_mu_is_tunable_between_steps(fmu, tmp_path):
    from fmpy import extract
    from fmpy.fmi2 import FMU2Slave
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu), str(tmp_path / "x")),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="vdp")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr["mu"], vr["x0"]], [0.0, 1.0])
    slave.exitInitializationMode()
    h, t = 0.01, 0.0
    for _ in range(300):
        slave.doStep(t, h)
        t += h
    x3, v3 = slave.getReal([vr["x"], vr["v"]])
    assert abs(x3 - np.cos(3.0)) < 1e-9
    slave.setReal([vr["mu"]], [2.0])
    for _ in range(200):
        slave.doStep(t, h)
        t += h
    x, v = reference(2.0, x3, v3, np.array([3.0, 5.0]))
    assert np.abs(np.array(slave.getReal([vr["x"], vr["v"]])) - [x[-1], v[-1]]).max() < 1e-6
    slave.terminate()
    slave.freeInstance()
