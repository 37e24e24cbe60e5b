"""The AdaptiveCompensator FMU under fmpy: it validates; its friction torques over 400 steps of
random velocities and learning signals equal the law written here in numpy from the weights
files and the documentation (Euler step of dw/dt = gain·φ·s − leakage·(w − w0), then the
projection onto the bound) to 1e-12; with adapt = false it is the NnCompensator exported from
the same nets, exactly; the adapted nets it writes at fmi2Terminate give the torques it ended with."""
import json
import subprocess

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.validation import validate_fmu

J = 2


def write_csv(path, columns):
    names = list(columns)
    rows = np.stack([columns[n] for n in names], axis=1)
    path.write_text("\n".join([",".join(names)] + [",".join(repr(float(v)) for v in row) for row in rows]) + "\n")


@pytest.fixture(scope="module")
def nets(neurarm, tmp_path_factory):
    d = tmp_path_factory.mktemp("nets")
    files = []
    for j in range(1, J + 1):
        v = np.linspace(-4, 4, 81)
        write_csv(d / f"f{j}.csv", {f"qd_{j}": v, f"tau_{j}": (1.2 - 0.3 * j) * np.tanh(15 * v) + 0.4 * v / j})
        out = d / f"f{j}.json"
        subprocess.run([neurarm, "train", "-d", d / f"f{j}.csv", "--inputs", f"qd_{j}", "--targets", f"tau_{j}",
                        "--hidden", "5", "--epochs", "40", "-o", out], check=True)
        files.append(out)
    return files


def export(neurarm, nets, path, adaptive):
    args = [neurarm, "export", "compensator", "--friction", ",".join(str(n) for n in nets), "-o", path]
    subprocess.run(args + (["--adaptive"] if adaptive else []), check=True)
    return path


class Slave:
    def __init__(self, fmu):
        self.md = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=extract(str(fmu)),
                               modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="t")
        self.slave.instantiate()

    def start(self, **parameters):
        self.slave.setupExperiment(startTime=0.0)
        for name, value in parameters.items():
            if isinstance(value, bool):
                self.slave.setBoolean([self.vr[name]], [value])
            elif isinstance(value, str):
                self.slave.setString([self.vr[name]], [value])
            else:
                self.slave.setReal([self.vr[name]], [value])
        self.slave.enterInitializationMode()
        self.slave.exitInitializationMode()
        return self

    def set(self, values):
        self.slave.setReal([self.vr[n] for n in values], list(values.values()))

    def get(self, names):
        return np.array(self.slave.getReal([self.vr[n] for n in names]))


class Law:
    """The documented law on one friction net, from its weights file."""

    def __init__(self, path):
        w = json.loads(path.read_text())
        self.iw = np.array(w["iw"])[:, 0]
        self.b1 = np.array(w["b1"])
        self.theta0 = np.concatenate([np.array(w["lw"])[0], w["b2"]])
        self.theta = self.theta0.copy()
        self.min_in, self.max_in = w["input_scaling"]["min"][0], w["input_scaling"]["max"][0]
        self.min_out, self.max_out = w["output_scaling"]["min"][0], w["output_scaling"]["max"][0]
        self.alpha = (self.max_out - self.min_out) / 2

    def phi(self, v):
        x = 2 * (v - self.min_in) / (self.max_in - self.min_in) - 1
        return np.concatenate([np.tanh(self.iw * x + self.b1), [1.0]])

    def torque(self, v):
        return (self.theta @ self.phi(v) + 1) * self.alpha + self.min_out

    def step(self, v, s, h, gain, leakage, bound):
        # In torque units w = alpha·theta: dw/dt = gain·phi·s − leakage·(w − w0).
        self.theta = self.theta + h * (gain / self.alpha * s * self.phi(v) - leakage * (self.theta - self.theta0))
        radius = bound / (self.alpha * np.sqrt(len(self.theta)))
        d = np.linalg.norm(self.theta - self.theta0)
        if d > radius:
            self.theta = self.theta0 + (self.theta - self.theta0) * radius / d


def test_validates(neurarm, nets, tmp_path):
    fmu = export(neurarm, nets, tmp_path / "Adaptive.fmu", True)
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    outputs = {u.variable.name: {d.name for d in u.dependencies} for u in md.outputs}
    assert outputs["tau_friction_1"] == {"qd_1"}, "the learning signal feeds no output directly"
    assert outputs["adapted_friction_2"] == set()


@pytest.mark.parametrize("bound", [10.0, 0.05])
def test_friction_torques_follow_the_documented_law(neurarm, nets, tmp_path, bound):
    fmu = export(neurarm, nets, tmp_path / "Adaptive.fmu", True)
    gain, leakage, h = 3.0, 0.5, 1e-3
    slave = Slave(fmu).start(gain_friction=gain, leakage=leakage, bound_friction=bound)
    laws = [Law(n) for n in nets]
    rng = np.random.default_rng(3)
    worst = 0.0
    for k in range(400):
        qd = rng.uniform(-3, 3, J)
        s = rng.uniform(-2, 2, J) + 1.0
        slave.set({**{f"qd_{j + 1}": qd[j] for j in range(J)}, **{f"s_{j + 1}": s[j] for j in range(J)}})
        slave.slave.doStep(k * h, h)
        got = slave.get([f"tau_friction_{j + 1}" for j in range(J)])
        for j, law in enumerate(laws):
            law.step(qd[j], s[j], h, gain, leakage, bound)
            worst = max(worst, abs(got[j] - law.torque(qd[j])))
    assert worst <= 1e-12
    moved = [abs(law.torque(0.7) - Law(n).torque(0.7)) for law, n in zip(laws, nets)]
    assert min(moved) > 1e-3, moved
    if bound < 1:
        assert max(moved) <= bound + 1e-12, "the projection bounds the change"


def test_with_adaptation_off_it_is_the_nn_compensator(neurarm, nets, tmp_path):
    adaptive = Slave(export(neurarm, nets, tmp_path / "Adaptive.fmu", True)).start(adapt=False)
    static = Slave(export(neurarm, nets, tmp_path / "Static.fmu", False)).start()
    rng = np.random.default_rng(4)
    names = [f"tau_comp_{j + 1}" for j in range(J)]
    for k in range(200):
        values = {f"qd_{j + 1}": rng.uniform(-4, 4) for j in range(J)}
        adaptive.set({**values, "s_1": 5.0, "s_2": -5.0})
        static.set(values)
        adaptive.slave.doStep(k * 1e-3, 1e-3)
        static.slave.doStep(k * 1e-3, 1e-3)
        assert list(adaptive.get(names)) == list(static.get(names))


def test_the_nets_written_at_terminate_give_the_torques_it_ended_with(neurarm, nets, tmp_path):
    folder = tmp_path / "adapted"
    slave = Slave(export(neurarm, nets, tmp_path / "Adaptive.fmu", True)).start(nets_folder=str(folder))
    for k in range(300):
        slave.set({"qd_1": np.sin(3e-3 * k), "qd_2": 1.5, "s_1": 1.0, "s_2": -1.0})
        slave.slave.doStep(k * 1e-3, 1e-3)
    slave.set({"qd_1": 0.4, "qd_2": -0.9})
    ended = slave.get(["tau_friction_1", "tau_friction_2"])
    slave.slave.terminate()
    written = [folder / "friction_1.json", folder / "friction_2.json"]
    rerun = Slave(export(neurarm, written, tmp_path / "Again.fmu", False)).start()
    rerun.set({"qd_1": 0.4, "qd_2": -0.9})
    assert list(rerun.get(["tau_friction_1", "tau_friction_2"])) == list(ended)
