"""The closed loops of `neurarm paper` outside our master: run by `neurarm simulate` with another
step, and stepped here with fmpy's FMU2Slave in the orderings other engines use."""
import csv
import fnmatch
import re
import subprocess
import tomllib

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    data = np.array(rows[1:], dtype=float)
    return {name: data[:, k] for k, name in enumerate(rows[0])}


def loop_spec(paper, loop):
    return tomllib.loads((paper / "systems" / f"{loop}.toml").read_text())


def master_run(neurarm, paper, loop, tmp_path, stop=None, step=None, record=None):
    """The loop's system file run by `neurarm simulate`, optionally with another stop, step and
    recorded variables. Rows: the start, then one per step."""
    spec = (paper / "systems" / f"{loop}.toml").read_text()
    if stop is not None:
        spec = re.sub(r"^stop = .*$", f"stop = {stop!r}", spec, flags=re.M)
    if step is not None:
        spec = re.sub(r"^step = .*$", f"step = {step!r}", spec, flags=re.M)
    if record is not None:
        spec = re.sub(r"^record = .*$", "record = [" + ", ".join(f'"{r}"' for r in record) + "]", spec, flags=re.M)
    name = f"{tmp_path.name}-{loop}-{step}"
    path = paper / "systems" / f"{name}.toml"  # FMU paths are relative to systems/
    path.write_text(spec)
    out = tmp_path / f"{name}.csv"
    subprocess.run([neurarm, "simulate", path, "-o", out], check=True, capture_output=True)
    path.unlink()
    return read_csv(out)


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


ORDERINGS = ("gauss-seidel", "delayed", "lagged")


def steps_to(stop, step):
    """The communication steps [s] from 0 to `stop` as our master takes them: whole steps while
    one fits (to a relative 1e-9), then a last one shortened to land on `stop`."""
    steps = []
    while stop - len(steps) * step >= (1 - 1e-9) * step:
        steps.append(step)
    rest = stop - len(steps) * step
    if rest > 1e-9 * step:
        steps.append(rest)
    return steps


def whole_steps(run, step):
    """A master's run (rows: the start, then one per step) up to its last whole step: engines with
    a fixed step (libcosim, the Toolbox's container) do not shorten the last one."""
    n = len(run["time"])
    if n > 1 and not np.isclose(run["time"][-1] - run["time"][-2], step, rtol=1e-9, atol=0):
        n -= 1
    return {name: column[:n] for name, column in run.items()}


def python_loop(paper, loop, ordering, stop, step, record=None, order=None):
    """The loop stepped here. Rows as the master records them: after each step, the recorded
    variables (the system file's, or `record`).

    - "gauss-seidel": as textbook, units in `order` (plant first, then what reads it): set a
      unit's inputs from the others' current outputs, then step it.
    - "delayed" (fmpy's `simulate_ssp`): every unit steps from the values its connections held
      before the step, and connections pass values on after all have stepped, from 0 at the start.
    - "lagged" (libcosim, the FMU Manipulation Toolbox's container): the same, but the
      connections start from consistent values: the outputs at the start time, passed around
      until every unit's inputs hold its providers' start outputs.
    """
    assert ordering in ORDERINGS
    spec = loop_spec(paper, loop)
    base = paper / "systems"
    units = {f["name"]: Unit(f["name"], base / f["path"], f.get("parameters", {})) for f in spec["fmu"]}
    order = order or list(units)
    links = expand(units, spec)
    inputs = {u: [(fu, out, inp) for fu, out, tu, inp in links if tu == u] for u in units}
    record = record or spec["simulation"]["record"]

    def fresh_inputs(u):
        pairs = inputs[u]
        values = [units[fu].get([out])[0] for fu, out, _ in pairs]
        units[u].set([inp for _, _, inp in pairs], values)

    held = {(fu, out): 0.0 for fu, out, _, _ in links}  # the connections' values between steps
    if ordering != "delayed":
        for _ in units:  # as many passes as units: every chain of feedthrough is through
            for u in order:
                fresh_inputs(u)
        for key in held:
            held[key] = units[key[0]].get([key[1]])[0]
    rows, time = [], 0.0
    for k, h in enumerate(steps_to(stop, step)):
        if ordering == "gauss-seidel":
            for u in order:
                fresh_inputs(u)
                units[u].fmu.doStep(currentCommunicationPoint=k * step, communicationStepSize=h)
        else:
            for u in order:
                units[u].set([inp for _, _, inp in inputs[u]], [held[(fu, out)] for fu, out, _ in inputs[u]])
                t = time if ordering == "delayed" else k * step  # simulate_ssp sums its times
                units[u].fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            for key in held:
                held[key] = units[key[0]].get([key[1]])[0]
            time += step
        rows.append([units[r.split(".")[0]].get([r.split(".", 1)[1]])[0] for r in record])
    for u in units.values():
        u.fmu.terminate()
        u.fmu.freeInstance()
    return {name: np.array([row[i] for row in rows]) for i, name in enumerate(record)}
