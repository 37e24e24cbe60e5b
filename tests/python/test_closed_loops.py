"""The closed loops of `neurarm paper`, rerun without our master.

1. The NN-compensated tracking loop (Table 1, "sim NN") stepped by a loop written here with
   fmpy's FMU2Slave, Gauss–Seidel as textbook (set a unit's inputs from the others' current
   outputs, then step it; plant, compensator, controller in turn), reproduces the master's
   trajectory to 1e-9.
2. fmpy's `simulate_ssp` runs the loop's SSP file. It is not Gauss–Seidel: every unit steps from
   the values its connections held before the step, and connections pass values on only after all
   have stepped, starting from 0. So every connection delays by one communication step and
   direct feedthrough is never resolved (the compensator's torque reaches the arm two steps late).
   The same loop written here with that ordering reproduces fmpy's run, and the difference to the
   master is of first order in the step, as a one-step delay is.
"""
import csv
import fnmatch
import re
import subprocess
import tomllib

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.ssp.ssd import read_ssd
from fmpy.ssp.simulation import simulate_ssp

LOOP = "tracking_sim_nn"
ORDER = ["arm", "comp", "ctl"]  # plant first, then what reads it, the controller last


@pytest.fixture(scope="module")
def paper(neurarm, tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    subprocess.run([neurarm, "paper", "--quick", "-o", out], check=True)
    return out


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    data = np.array(rows[1:], dtype=float)
    return {name: data[:, k] for k, name in enumerate(rows[0])}


def master_run(neurarm, paper, tmp_path, stop=None, step=None):
    """The loop's system file run by `neurarm simulate`, optionally with another stop and step."""
    spec = (paper / "systems" / f"{LOOP}.toml").read_text()
    if stop is not None:
        spec = re.sub(r"^stop = .*$", f"stop = {stop!r}", spec, flags=re.M)
        spec = re.sub(r"^step = .*$", f"step = {step!r}", spec, flags=re.M)
    path = paper / "systems" / f"{tmp_path.name}.toml"  # FMU paths are relative to systems/
    path.write_text(spec)
    subprocess.run([neurarm, "simulate", path, "-o", tmp_path / "master.csv"], check=True)
    return read_csv(tmp_path / "master.csv")


class Unit:
    def __init__(self, name, fmu_path, parameters):
        self.name = name
        md = read_model_description(str(fmu_path))
        self.variables = {v.name: v for v in md.modelVariables}
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu_path)),
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        for k, v in parameters.items():
            assert self.variables[k].type == "Real", "the paper's loops set only Real parameters"
            self.fmu.setReal([self.variables[k].valueReference], [float(v)])
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def get(self, names):
        return self.fmu.getReal([self.variables[n].valueReference for n in names])

    def set(self, names, values):
        if names:
            self.fmu.setReal([self.variables[n].valueReference for n in names], list(values))


def expand(units, spec):
    """(from unit, output, to unit, input) per connection; '*' stands for the same text on both
    sides, and only outputs are sources."""
    links = []
    for c in spec["connection"]:
        (fu, fp), (tu, tp) = c["from"].split(".", 1), c["to"].split(".", 1)
        for name in units[fu].variables:
            if units[fu].variables[name].causality == "output" and fnmatch.fnmatchcase(name, fp):
                stem = name[fp.index("*"): len(name) - (len(fp) - fp.index("*") - 1)]
                links.append((fu, name, tu, tp.replace("*", stem)))
    return links


def python_loop(paper, delayed, stop, step):
    """The loop stepped here: Gauss–Seidel, or with fmpy's `simulate_ssp` ordering (`delayed`).
    Rows as the master records them: after each step, the recorded variables."""
    spec = tomllib.loads((paper / "systems" / f"{LOOP}.toml").read_text())
    base = paper / "systems"
    units = {f["name"]: Unit(f["name"], base / f["path"], f.get("parameters", {})) for f in spec["fmu"]}
    links = expand(units, spec)
    inputs = {u: [(fu, out, inp) for fu, out, tu, inp in links if tu == u] for u in units}
    record = spec["simulation"]["record"]
    held = {(fu, out): 0.0 for fu, out, _, _ in links}  # the delayed ordering's connection values

    def fresh_inputs(u):
        pairs = inputs[u]
        values = [units[fu].get([out])[0] for fu, out, _ in pairs]
        units[u].set([inp for _, _, inp in pairs], values)

    if not delayed:
        for u in ORDER:
            fresh_inputs(u)
    rows, time = [], 0.0
    for k in range(int(round(stop / step))):
        if delayed:
            for u in ORDER:
                units[u].set([inp for _, _, inp in inputs[u]], [held[(fu, out)] for fu, out, _ in inputs[u]])
                units[u].fmu.doStep(currentCommunicationPoint=time, communicationStepSize=step)
            for key in held:
                held[key] = units[key[0]].get([key[1]])[0]
            time += step  # as simulate_ssp counts time
        else:
            for u in ORDER:
                fresh_inputs(u)
                units[u].fmu.doStep(currentCommunicationPoint=k * step, communicationStepSize=step)
        rows.append([units[r.split(".")[0]].get([r.split(".", 1)[1]])[0] for r in record])
    for u in units.values():
        u.fmu.terminate()
        u.fmu.freeInstance()
    return {name: np.array([row[i] for row in rows]) for i, name in enumerate(record)}


def test_system_file_is_the_run_the_paper_recorded(neurarm, paper, tmp_path):
    master = master_run(neurarm, paper, tmp_path)
    recorded = read_csv(paper / "data" / f"{LOOP}.csv")  # every 10th step, '.' written as '_'
    for name, column in master.items():
        assert np.array_equal(column[::10], recorded[name.replace(".", "_")]), name


def test_fmu2slave_gauss_seidel_loop_reproduces_the_master(neurarm, paper, tmp_path):
    master = master_run(neurarm, paper, tmp_path)
    step = float(np.diff(master["time"][:2])[0])
    stop = master["time"][-1]
    ours = python_loop(paper, delayed=False, stop=stop, step=step)
    assert len(ours["arm.x"]) == len(master["arm.x"]) - 1
    for name, column in ours.items():
        worst = np.abs(column - master[name][1:]).max()
        assert worst <= 1e-9, f"{name}: {worst:.3e}"
    # The run is not trivial: the arm moved along the reference and friction was compensated.
    assert np.ptp(master["arm.x"]) > 0.5 and np.abs(master["ctl.error_x"]).max() < 5e-3


def fmpy_ssp(paper, stop, step):
    path = str(paper / f"{LOOP}.ssp")
    parameters = read_ssd(path).system.parameterBindings[0].parameterValues[0]
    result = simulate_ssp(path, start_time=0.0, stop_time=stop, step_size=step, parameter_set=parameters)
    return result[: int(round(stop / step))]  # simulate_ssp's summed time may add one step


def test_simulate_ssp_is_the_delayed_ordering_and_first_order_close(neurarm, paper, tmp_path):
    stop = 2.0
    # fmpy's run is the loop in the delayed ordering, to rounding.
    ssp = fmpy_ssp(paper, stop, 1e-3)
    delayed = python_loop(paper, delayed=True, stop=stop, step=1e-3)
    for name in ["arm.x", "arm.y", "arm.q_1", "arm.q_4", "ctl.tau_1", "ctl.tau_3"]:
        worst = np.abs(ssp[name] - delayed[name]).max()
        assert worst <= 1e-12, f"{name}: {worst:.3e}"
    # Against the master: the delay is an O(h) change of the loop, so the end-effector paths
    # differ by O(h) once the start (all connections at 0) has died out.
    gaps = {}
    for step in [1e-3, 5e-4, 2.5e-4]:
        ssp = fmpy_ssp(paper, stop, step)
        master = master_run(neurarm, paper, tmp_path, stop=stop, step=step)
        n = len(ssp)
        t = master["time"][1: n + 1]
        gap = np.hypot(ssp["arm.x"] - master["arm.x"][1: n + 1], ssp["arm.y"] - master["arm.y"][1: n + 1])
        gaps[step] = gap[t >= 0.25].max()
    print("max end-effector gap, simulate_ssp vs master [m]:", {k: f"{v:.3e}" for k, v in gaps.items()})
    assert gaps[1e-3] < 3e-3  # measured 1.8e-3 m: millimetres on a 0.7 m path
    assert 0.4 < gaps[2.5e-4] / gaps[5e-4] < 0.6  # first order: halving h halves it
