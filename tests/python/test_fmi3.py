"""FMI 3.0 twins of neurarm's FMUs under fmpy: every FMU of a quick paper run (arm, controllers,
NN, ideal and adaptive compensators) and its FMI 3.0 twin (`neurarm export fmi3`) validate, and
driven with the same random inputs for 200 steps of 1 ms they give the same value of every Float64
variable, by name, to 1e-12; `export --fmi 3` writes the same model description as the twin; and the
FMI 3.0 API refuses misuse with fmi3Error and a log entry naming the fmi3 function (wrong state,
unknown or mistyped value references, NaN, non-settable variables, damaged FMU states, a wrong
instantiation token, event mode)."""
import ctypes
import pathlib
import shutil
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

STEP = 1e-3
STEPS = 200


@pytest.fixture(scope="module")
def twins(neurarm, paper, tmp_path_factory):
    """(FMI 2.0 FMU, FMI 3.0 twin) for every FMU of the quick paper run."""
    out = tmp_path_factory.mktemp("fmi3")
    pairs = []
    for fmu in sorted((paper / "fmu").glob("*.fmu")):
        twin = out / fmu.name
        subprocess.run([neurarm, "export", "fmi3", fmu, "-o", twin], check=True, capture_output=True)
        pairs.append((fmu, twin))
    assert len(pairs) >= 10, f"the paper run wrote {len(pairs)} FMUs"
    return pairs


def test_the_paper_run_wrote_the_same_twins(twins, paper):
    written = sorted(p.name for p in (paper / "fmu" / "fmi3").glob("*.fmu"))
    assert written == [fmu.name for fmu, _ in twins]
    for fmu, twin in twins:
        ours = zipfile.ZipFile(twin).read("modelDescription.xml")
        assert zipfile.ZipFile(paper / "fmu" / "fmi3" / fmu.name).read("modelDescription.xml") == ours


def test_every_twin_validates_and_is_fmi3(twins):
    for fmu, twin in twins:
        assert validate_fmu(str(twin)) == [], twin.name
        md2, md3 = read_model_description(str(fmu)), read_model_description(str(twin))
        assert md3.fmiVersion == "3.0" and md2.fmiVersion == "2.0"
        assert md3.guid == md2.guid, "the instantiation token is the FMI 2.0 GUID"
        names2 = [(v.name, v.causality, v.variability, v.start, v.unit) for v in md2.modelVariables]
        names3 = [(v.name, v.causality, v.variability, v.start, v.unit) for v in md3.modelVariables]
        assert names3 == names2, twin.name
        assert [o.variable.name for o in md3.outputs] == [o.variable.name for o in md2.outputs]
        for o2, o3 in zip(md2.outputs, md3.outputs):
            assert [d.name for d in o3.dependencies] == [d.name for d in o2.dependencies]
        with zipfile.ZipFile(twin) as z:
            names = z.namelist()
        ident = md3.coSimulation.modelIdentifier
        assert f"binaries/x86_64-linux/{ident}.so" in names, names


def driven(md, slave, version, rng_seed):
    """Runs `slave` for STEPS steps with seeded random inputs; returns {name: values per step} of
    every real/Float64 variable."""
    rng = np.random.default_rng(rng_seed)
    reals = [v for v in md.modelVariables if v.type in ("Real", "Float64") and v.causality != "independent"]
    inputs = [v for v in reals if v.causality == "input"]
    names = [v.name for v in reals]
    vrs = [v.valueReference for v in reals]
    in_vrs = [v.valueReference for v in inputs]
    get = slave.getReal if version == 2 else slave.getFloat64
    put = slave.setReal if version == 2 else slave.setFloat64
    if version == 2:
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
    else:
        slave.instantiate()
        slave.enterInitializationMode(startTime=0.0)
    slave.exitInitializationMode()
    rows = []
    t = 0.0
    for _ in range(STEPS):
        if in_vrs:
            put(in_vrs, list(rng.uniform(-1.0, 1.0, len(in_vrs))))
        slave.doStep(t, STEP)
        t += STEP
        rows.append(get(vrs))
    slave.terminate()
    slave.freeInstance()
    return dict(zip(names, np.array(rows).T))


def slave_of(fmu, md, into, version):
    folder = extract(str(fmu), str(into))
    cls = FMU2Slave if version == 2 else FMU3Slave
    return cls(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier, instanceName="twin")


def test_twins_give_the_same_values(twins, tmp_path):
    worst = 0.0
    for k, (fmu, twin) in enumerate(twins):
        md2, md3 = read_model_description(str(fmu)), read_model_description(str(twin))
        a = driven(md2, slave_of(fmu, md2, tmp_path / f"a{k}", 2), 2, k)
        b = driven(md3, slave_of(twin, md3, tmp_path / f"b{k}", 3), 3, k)
        assert a.keys() == b.keys()
        for name in a:
            scale = max(np.max(np.abs(a[name])), 1e-300)
            diff = np.max(np.abs(a[name] - b[name])) / scale
            worst = max(worst, diff)
            assert diff <= 1e-12, f"{fmu.name} {name}: FMI 3.0 differs by {diff:.3g} relative"
    print(f"largest relative difference FMI 3.0 vs FMI 2.0 over {len(twins)} FMUs: {worst:.3g}")


def test_fmpy_simulates_the_arm_twin_like_fmi2(twins):
    fmu, twin = next((f, t) for f, t in twins if f.stem == "PlanarArm")
    # torques beyond the joints' Coulomb friction, so the arm moves whatever its base angle
    start = {"tau_1": 3.0, "tau_2": -2.5}
    r2 = simulate_fmu(str(fmu), stop_time=0.5, step_size=STEP, output_interval=STEP, start_values=start)
    r3 = simulate_fmu(str(twin), stop_time=0.5, step_size=STEP, output_interval=STEP, start_values=start)
    assert r2.dtype.names == r3.dtype.names
    assert len(r2) == len(r3) > 400
    moved = False
    for name in r2.dtype.names:
        np.testing.assert_allclose(r3[name], r2[name], rtol=1e-12, atol=0, err_msg=name)
        moved |= name.startswith("q_") and np.ptp(r2[name]) > 1e-3
    assert moved, "the arm moves: the comparison is not of constants"


def test_direct_export_writes_the_twins_description(neurarm, tmp_path):
    subprocess.run([neurarm, "export", "arm", "-o", tmp_path / "A2.fmu", "--name", "Arm"], check=True, capture_output=True)
    subprocess.run([neurarm, "export", "arm", "--fmi", "3", "-o", tmp_path / "A3.fmu", "--name", "Arm"], check=True, capture_output=True)
    subprocess.run([neurarm, "export", "fmi3", tmp_path / "A2.fmu", "-o", tmp_path / "T3.fmu"], check=True, capture_output=True)
    direct = zipfile.ZipFile(tmp_path / "A3.fmu").read("modelDescription.xml")
    twin = zipfile.ZipFile(tmp_path / "T3.fmu").read("modelDescription.xml")
    assert direct == twin
    assert b'fmiVersion="3.0"' in direct
    assert validate_fmu(str(tmp_path / "A3.fmu")) == []


def test_twin_of_a_non_neurarm_fmu_is_refused(neurarm, tmp_path):
    bad = tmp_path / "bad.fmu"
    with zipfile.ZipFile(bad, "w") as z:
        z.writestr("modelDescription.xml", "<fmiModelDescription/>")
    r = subprocess.run([neurarm, "export", "fmi3", bad, "-o", tmp_path / "out.fmu"], capture_output=True, text=True)
    assert r.returncode != 0
    assert "not a neurarm FMU" in r.stderr
    assert not (tmp_path / "out.fmu").exists()


class Logged:
    """An FMU3Slave of the arm twin whose log messages are kept."""

    def __init__(self, twin, into, token=None, event_mode=False, messages=None):
        md = read_model_description(str(twin))
        self.md = md
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        folder = extract(str(twin), str(into))
        self.slave = FMU3Slave(guid=token or md.guid, unzipDirectory=folder,
                               modelIdentifier=md.coSimulation.modelIdentifier, instanceName="misuse")
        self.messages = [] if messages is None else messages

        def log(env, status, category, message):
            self.messages.append((status, message.decode()))

        self.slave.instantiate(logMessage=log, eventModeUsed=event_mode)

    def refused(self, call, *args, naming):
        before = len(self.messages)
        with pytest.raises(Exception):
            call(*args)
        new = [m for s, m in self.messages[before:] if s >= 3]
        assert new, "refused without a log entry"
        assert any(naming in m for m in new), new
        return new[-1]


@pytest.fixture
def arm_twin(twins):
    return next(t for f, t in twins if f.stem == "PlanarArm")


def test_misuse_is_refused_with_a_reason(arm_twin, tmp_path):
    f = Logged(arm_twin, tmp_path / "m")
    s = f.slave
    q1, tau1, mass1 = f.vr["q_1"], f.vr["tau_1"], f.vr["mass_1"]
    f.refused(s.doStep, 0.0, STEP, naming="fmi3DoStep")
    f.refused(s.exitInitializationMode, naming="fmi3ExitInitializationMode")
    s.enterInitializationMode(startTime=0.0)
    s.exitInitializationMode()
    m = f.refused(s.getFloat64, [10_000], naming="fmi3GetFloat64")
    assert "unknown value reference 10000" in m
    m = f.refused(s.getInt32, [q1], naming="fmi3GetInt32")
    assert "'q_1'" in m and "Float64" in m
    m = f.refused(s.setFloat64, [tau1], [float("nan")], naming="fmi3SetFloat64")
    assert "not a finite number" in m
    f.refused(s.setFloat64, [q1], [0.5], naming="fmi3SetFloat64")  # an output
    f.refused(s.setFloat64, [mass1], [1.0], naming="fmi3SetFloat64")  # a fixed parameter after initialization
    f.refused(s.getFloat32, [q1], naming="fmi3GetFloat32")
    f.refused(s.doStep, 0.0, 0.0, naming="fmi3DoStep")
    f.refused(s.doStep, 1.0, STEP, naming="fmi3DoStep")
    f.refused(s.enterStepMode, naming="fmi3EnterStepMode")
    f.refused(s.enterEventMode, naming="fmi3EnterEventMode")

    # FMU states: restore one, serialise it, refuse a damaged copy
    s.setFloat64([tau1], [0.3])
    state = s.getFMUState()
    s.doStep(0.0, STEP)
    after_one = s.getFloat64([q1])[0]
    s.doStep(STEP, STEP)
    s.setFMUState(state)
    s.doStep(0.0, STEP)
    assert s.getFloat64([q1])[0] == after_one
    data = bytearray(s.serializeFMUState(state))
    data[len(data) // 2] ^= 0xFF
    m = f.refused(s.deserializeFMUState, bytes(data), naming="fmi3DeserializeFMUState")
    assert "checksum" in m
    restored = s.deserializeFMUState(s.serializeFMUState(state))
    s.setFMUState(restored)
    s.doStep(0.0, STEP)
    assert s.getFloat64([q1])[0] == after_one
    s.freeFMUState(restored)
    s.freeFMUState(state)

    # reset: back to instantiated, runs again from the start values
    s.reset()
    s.enterInitializationMode(startTime=0.0)
    s.exitInitializationMode()
    s.setFloat64([tau1], [0.3])
    s.doStep(0.0, STEP)
    assert s.getFloat64([q1])[0] == after_one
    s.terminate()
    f.refused(s.doStep, STEP, STEP, naming="fmi3DoStep")
    s.freeInstance()


def test_instantiation_refusals(arm_twin, tmp_path):
    messages = []
    with pytest.raises(Exception):
        Logged(arm_twin, tmp_path / "t", token="{00000000-0000-0000-0000-000000000000}", messages=messages)
    assert any("instantiation token" in m and "fmi3InstantiateCoSimulation" in m for _, m in messages), messages
    messages.clear()
    with pytest.raises(Exception):
        Logged(arm_twin, tmp_path / "e", event_mode=True, messages=messages)
    assert any("event mode" in m for _, m in messages), messages
