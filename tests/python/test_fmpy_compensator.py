"""The NnCompensator FMU under fmpy: it validates; for 1000 random (q, qd) its outputs equal the
Rust forward pass (`neurarm eval`, angles wrapped into the gravity net's trained turn) to 1e-12; the enable switches change exactly their terms;
missing or corrupt weights make instantiation fail with the reason logged. With a periodic gravity net (link angles as (cos, sin))
the FMU equals a numpy forward pass written here from the weights file, unwrapped, and is 2π-periodic in every angle."""
import json
import pathlib
import shutil
import subprocess

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
from fmpy.validation import validate_fmu

J = 4


def write_csv(path, columns):
    names = list(columns)
    rows = np.stack([columns[n] for n in names], axis=1)
    lines = [",".join(names)] + [",".join(repr(float(v)) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def nets(neurarm, tmp_path_factory):
    """Four small friction nets and a 4-6-4 gravity net, trained quickly by the CLI."""
    d = tmp_path_factory.mktemp("nets")
    rng = np.random.default_rng(1)
    files = {}
    for j in range(1, J + 1):
        v = np.linspace(-5, 5, 101)
        write_csv(d / f"f{j}.csv", {f"qd_{j}": v, f"tau_{j}": (1.6 - 0.3 * j) * np.tanh(20 * v) + 0.2 * j * v})
        files[f"f{j}"] = d / f"f{j}.json"
        subprocess.run([neurarm, "train", "-d", d / f"f{j}.csv", "--inputs", f"qd_{j}", "--targets", f"tau_{j}",
                        "--hidden", "5", "--epochs", "40", "-o", files[f"f{j}"]], check=True)
    q = rng.uniform(0, 2 * np.pi, size=(300, J))
    g = {f"q_{i + 1}": q[:, i] for i in range(J)}
    g.update({f"tau_{i + 1}": np.cos(q[:, : i + 1].sum(axis=1)) * (4 - i) for i in range(J)})
    write_csv(d / "g.csv", g)
    files["g"] = d / "g.json"
    subprocess.run([neurarm, "train", "-d", d / "g.csv", "--inputs", ",".join(f"q_{i}" for i in range(1, J + 1)),
                    "--targets", ",".join(f"tau_{i}" for i in range(1, J + 1)), "--hidden", "6", "--epochs", "30",
                    "-o", files["g"]], check=True)
    return files


@pytest.fixture(scope="module")
def fmu(neurarm, nets, tmp_path_factory):
    out = tmp_path_factory.mktemp("fmu") / "NnCompensator.fmu"
    subprocess.run([neurarm, "export", "compensator", "--friction", ",".join(str(nets[f"f{j}"]) for j in range(1, J + 1)),
                    "--gravity", nets["g"], "-o", out], check=True)
    return out


def test_validates(fmu):
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    outputs = {u.variable.name: {d.name for d in u.dependencies} for u in md.outputs}
    assert outputs["tau_friction_2"] == {"qd_2"}
    assert outputs["tau_gravity_1"] == {f"q_{i}" for i in range(1, J + 1)}
    assert outputs["tau_comp_3"] == {f"q_{i}" for i in range(1, J + 1)} | {"qd_3"}


class Slave:
    def __init__(self, fmu_path, unzipped=None):
        self.md = read_model_description(str(fmu_path))
        self.dir = unzipped or extract(str(fmu_path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.log = []
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(lambda env, name, status, cat, msg: self.log.append(msg.decode()))
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir, modelIdentifier=self.md.coSimulation.modelIdentifier,
                               instanceName="test")

    def start(self):
        self.slave.instantiate(callbacks=self.callbacks)
        self.slave.setupExperiment(startTime=0.0)
        self.slave.enterInitializationMode()
        self.slave.exitInitializationMode()
        return self

    def outputs(self, q, qd, names):
        self.slave.setReal([self.vr[f"q_{i}"] for i in range(1, J + 1)] + [self.vr[f"qd_{i}"] for i in range(1, J + 1)], list(q) + list(qd))
        return np.array(self.slave.getReal([self.vr[n] for n in names]))


def rust_eval(neurarm, net, columns, tmp_path, name):
    write_csv(tmp_path / f"{name}.csv", columns)
    subprocess.run([neurarm, "eval", "-n", net, "-d", tmp_path / f"{name}.csv", "-o", tmp_path / f"{name}.out.csv"], check=True)
    return np.genfromtxt(tmp_path / f"{name}.out.csv", delimiter=",", names=True)


def test_outputs_equal_rust_forward_pass(neurarm, nets, fmu, tmp_path):
    rng = np.random.default_rng(7)
    q = rng.uniform(-1, 7, size=(1000, J))
    qd = rng.uniform(-6, 6, size=(1000, J))
    slave = Slave(fmu).start()
    names = [f"tau_friction_{i}" for i in range(1, J + 1)] + [f"tau_gravity_{i}" for i in range(1, J + 1)] + [f"tau_comp_{i}" for i in range(1, J + 1)]
    got = np.array([slave.outputs(q[s], qd[s], names) for s in range(1000)])
    friction = np.stack([rust_eval(neurarm, nets[f"f{j}"], {f"qd_{j}": qd[:, j - 1]}, tmp_path, f"f{j}")[f"tau_{j}"] for j in range(1, J + 1)], axis=1)
    # The FMU first brings each angle into the turn the gravity net was trained on (gravity is
    # 2π-periodic); here that wrap is done with numpy before the Rust forward pass.
    low = json.loads(pathlib.Path(nets["g"]).read_text())["input_scaling"]["min"]
    wrapped = np.stack([low[i] + np.mod(q[:, i] - low[i], 2 * np.pi) for i in range(J)], axis=1)
    assert (wrapped != q).any(axis=1).sum() > 100  # the draw reaches outside the trained turn
    g = rust_eval(neurarm, nets["g"], {f"q_{i}": wrapped[:, i - 1] for i in range(1, J + 1)}, tmp_path, "g")
    gravity = np.stack([g[f"tau_{i}"] for i in range(1, J + 1)], axis=1)
    assert np.abs(got[:, :J] - friction).max() <= 1e-12
    assert np.abs(got[:, J:2 * J] - gravity).max() <= 1e-12
    assert np.abs(got[:, 2 * J:] - (friction + gravity)).max() <= 1e-12
    assert np.abs(gravity).max() > 0.5 and np.abs(friction).max() > 0.5


def test_enable_switches_change_exactly_their_terms(fmu):
    rng = np.random.default_rng(8)
    slave = Slave(fmu).start()
    comp = [f"tau_comp_{i}" for i in range(1, J + 1)]
    fr = [f"tau_friction_{i}" for i in range(1, J + 1)]
    gr = [f"tau_gravity_{i}" for i in range(1, J + 1)]
    ef, eg = slave.vr["enable_friction"], slave.vr["enable_gravity"]
    for _ in range(20):
        q, qd = rng.uniform(0, 6, J), rng.uniform(-4, 4, J)
        both = slave.outputs(q, qd, fr + gr)
        slave.slave.setBoolean([ef, eg], [False, True])
        assert np.array_equal(slave.outputs(q, qd, comp), both[J:])
        assert np.array_equal(slave.outputs(q, qd, fr), np.zeros(J))
        slave.slave.setBoolean([ef, eg], [True, False])
        assert np.array_equal(slave.outputs(q, qd, comp), both[:J])
        slave.slave.setBoolean([ef, eg], [False, False])
        assert np.array_equal(slave.outputs(q, qd, comp), np.zeros(J))
        slave.slave.setBoolean([ef, eg], [True, True])
        assert np.array_equal(slave.outputs(q, qd, comp), both[:J] + both[J:])


@pytest.mark.parametrize("damage, reason", [
    ("missing", "friction_2.json: No such file"),
    ("corrupt", "friction_2.json"),
    ("wrong_size", "b2 has 2 values, expected 1"),
])
def test_bad_weights_make_instantiation_fail_with_reason(fmu, damage, reason):
    unzipped = extract(str(fmu))
    try:
        path = __import__("pathlib").Path(unzipped, "resources", "friction_2.json")
        if damage == "missing":
            path.unlink()
        elif damage == "corrupt":
            path.write_text(path.read_text()[:100])
        else:
            import json
            w = json.loads(path.read_text())
            w["b2"] = [0.0, 1.0]
            path.write_text(json.dumps(w))
        slave = Slave(fmu, unzipped)
        with pytest.raises(Exception):
            slave.slave.instantiate(callbacks=slave.callbacks)
        assert any(reason in m for m in slave.log), slave.log
    finally:
        shutil.rmtree(unzipped, ignore_errors=True)


def numpy_forward(weights, x):
    """The weights file's net on the rows of x (physical inputs), written from the file format alone."""
    encoding = weights.get("encoding", "raw")
    if encoding == "link_angles":
        phi = np.cumsum(x, axis=1)
        x = np.stack([f(phi[:, i]) for i in range(phi.shape[1]) for f in (np.cos, np.sin)], axis=1)
    elif encoding == "joint_angles":
        x = np.stack([f(x[:, i]) for i in range(x.shape[1]) for f in (np.cos, np.sin)], axis=1)
    lo, hi = np.array(weights["input_scaling"]["min"]), np.array(weights["input_scaling"]["max"])
    span = np.where(hi > lo, hi - lo, 2.0)
    xs = np.where(hi > lo, 2.0 * (x - lo) / span - 1.0, x)
    hidden = np.tanh(xs @ np.array(weights["iw"]).T + np.array(weights["b1"]))
    ys = hidden @ np.array(weights["lw"]).T + np.array(weights["b2"])
    lo, hi = np.array(weights["output_scaling"]["min"]), np.array(weights["output_scaling"]["max"])
    return np.where(hi > lo, (ys + 1.0) * (hi - lo) / 2.0 + lo, ys)


@pytest.fixture(scope="module")
def periodic_fmu(neurarm, tmp_path_factory):
    """A gravity-only compensator whose 4-8-4 net sees the link angles as (cos, sin)."""
    d = tmp_path_factory.mktemp("periodic")
    rng = np.random.default_rng(3)
    q = rng.uniform(0, 2 * np.pi, size=(400, J))
    g = {f"q_{i + 1}": q[:, i] for i in range(J)}
    g.update({f"tau_{i + 1}": np.cos(q[:, : i + 1].sum(axis=1)) * (4 - i) for i in range(J)})
    write_csv(d / "g.csv", g)
    net = d / "g.json"
    subprocess.run([neurarm, "train", "-d", d / "g.csv", "--inputs", ",".join(f"q_{i}" for i in range(1, J + 1)),
                    "--targets", ",".join(f"tau_{i}" for i in range(1, J + 1)), "--hidden", "8", "--epochs", "60",
                    "--encoding", "link-angles", "-o", net], check=True)
    out = d / "Periodic.fmu"
    subprocess.run([neurarm, "export", "compensator", "--gravity", net, "-o", out], check=True)
    return net, out


def test_periodic_gravity_net_equals_numpy_and_repeats_every_turn(neurarm, periodic_fmu, tmp_path):
    net, fmu_path = periodic_fmu
    weights = json.loads(net.read_text())
    assert weights["encoding"] == "link_angles" and len(weights["iw"][0]) == 2 * J
    assert validate_fmu(str(fmu_path)) == []
    rng = np.random.default_rng(11)
    q = rng.uniform(-20, 20, size=(500, J))
    slave = Slave(fmu_path).start()
    names = [f"tau_gravity_{i}" for i in range(1, J + 1)]
    got = np.array([slave.outputs(q[s], np.zeros(J), names) for s in range(len(q))])
    assert np.abs(got - numpy_forward(weights, q)).max() <= 1e-12
    g = rust_eval(neurarm, net, {f"q_{i}": q[:, i - 1] for i in range(1, J + 1)}, tmp_path, "periodic")
    assert np.abs(got - np.stack([g[f"tau_{i}"] for i in range(1, J + 1)], axis=1)).max() <= 1e-12
    for i in range(J):
        turned = q.copy()
        turned[:, i] += 2 * np.pi * rng.choice([-2, -1, 1, 3], size=len(q))
        again = np.array([slave.outputs(turned[s], np.zeros(J), names) for s in range(len(q))])
        assert np.abs(again - got).max() <= 1e-12, f"not 2π-periodic in q_{i + 1}"
    # The net learnt the targets (a cos of the link angles), not just something periodic.
    truth = np.stack([np.cos(q[:, : i + 1].sum(axis=1)) * (4 - i) for i in range(J)], axis=1)
    assert np.abs(got - truth).max() < 0.05


def test_log_speed_friction_net_equals_numpy_and_follows_the_step(neurarm, tmp_path):
    """A friction net on the log speed (what a paper run trains on a quiet joint) evaluated by
    the FMU equals a numpy forward pass of the file (0 at rest), and it learnt a Coulomb step at 2 mrad/s."""
    v = np.concatenate([-np.geomspace(5, 1e-3, 60), [0.0], np.geomspace(1e-3, 5, 60)])
    tau = np.where(v > 0, 1.2, np.where(v < 0, -0.9, 0.0)) + 0.4 * v
    write_csv(tmp_path / "f.csv", {"qd_1": v, "tau_1": tau})
    net = tmp_path / "f.json"
    subprocess.run([neurarm, "train", "-d", tmp_path / "f.csv", "--inputs", "qd_1", "--targets", "tau_1", "--hidden", "6",
                    "--epochs", "200", "--encoding", "log-speed", "-o", net], check=True)
    weights = json.loads(net.read_text())
    assert weights["encoding"] == "log_speed" and weights["kind"] == "friction"
    out = tmp_path / "LogSpeed.fmu"
    subprocess.run([neurarm, "export", "compensator", "--friction", net, "-o", out], check=True)
    assert validate_fmu(str(out)) == []
    md = read_model_description(str(out))
    vr = {x.name: x.valueReference for x in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(out)), modelIdentifier=md.coSimulation.modelIdentifier, instanceName="t")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    speeds = np.concatenate([np.random.default_rng(5).uniform(-6, 6, 300), [0.0, 2e-3, -2e-3, 1e-6, -1e-6]])
    got = []
    for s in speeds:
        slave.setReal([vr["qd_1"]], [s])
        got.append(slave.getReal([vr["tau_friction_1"]])[0])
    got = np.array(got)
    encoded = (np.sign(speeds) * np.log1p(np.abs(speeds) / 1e-3))[:, None]
    plain = dict(weights, encoding="raw")
    # at a speed of exactly 0 the compensator gives no friction torque, as the law (the net's
    # value there is an extrapolation: identification has no samples at rest)
    expected = np.where(speeds == 0.0, 0.0, numpy_forward(plain, encoded)[:, 0])
    assert np.abs(got - expected).max() <= 1e-12
    assert got[-5] == 0.0
    assert abs(got[-4] - 1.2) < 0.1 and abs(got[-3] + 0.9) < 0.1, got[-5:]
    slave.terminate()
    slave.freeInstance()
