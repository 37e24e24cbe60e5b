"""Prints the closed-loop step cost (arm + NN friction compensator + task-space controller, 1 ms
communication step): our master and the plain Rust loop (criterion, just run by
scripts/bench-loop), libcosim running the same loop from its SSP file (its own stepping loop in
C++, one `cosim_execution_step` call for all steps, no observer), and fmpy driving the same three
FMUs from Python, Gauss–Seidel with one fmi2SetReal / fmi2DoStep / fmi2GetReal per unit and step
(the least a Python master can do)."""
import fnmatch
import json
import statistics
import pathlib
import sys
import time
import tomllib

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

criterion, bench = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
STEPS = 5000  # fmpy's


def median(name):
    return json.loads((criterion / name / "new" / "estimates.json").read_text())["median"]["point_estimate"] * 1e-9


def fmpy_seconds_per_step():
    spec = tomllib.loads((bench / "system.toml").read_text())
    units, variables = {}, {}
    for f in spec["fmu"]:
        md = read_model_description(str(bench / f["path"]))
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(bench / f["path"])),
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName=f["name"])
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        variables[f["name"]] = {v.name: v for v in md.modelVariables}
        for k, v in f.get("parameters", {}).items():
            fmu.setReal([variables[f["name"]][k].valueReference], [float(v)])
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        units[f["name"]] = fmu
    links = []  # (from unit, output, to unit, input)
    for c in spec["connection"]:
        (fu, fp), (tu, tp) = c["from"].split(".", 1), c["to"].split(".", 1)
        star = fp.index("*")
        for name, v in variables[fu].items():
            if v.causality == "output" and fnmatch.fnmatchcase(name, fp):
                links.append((fu, name, tu, tp.replace("*", name[star: len(name) - (len(fp) - star - 1)])))
    order = ["arm", "comp", "ctl"]
    outs = {u: sorted({o for fu, o, _, _ in links if fu == u}) for u in order}
    out_vrs = {u: [variables[u][o].valueReference for o in outs[u]] for u in order}
    ins = {u: [(fu, outs[fu].index(o), variables[u][i].valueReference) for fu, o, tu, i in links if tu == u] for u in order}
    in_vrs = {u: [vr for _, _, vr in ins[u]] for u in order}
    values = {u: list(units[u].getReal(out_vrs[u])) for u in order}
    for u in order[1:]:  # consistent start: the plant's outputs through the feedthrough units
        units[u].setReal(in_vrs[u], [values[fu][k] for fu, k, _ in ins[u]])
        values[u] = list(units[u].getReal(out_vrs[u]))
    t = 0.0
    start = time.perf_counter()
    for n in range(STEPS):
        for u in order:
            units[u].setReal(in_vrs[u], [values[fu][k] for fu, k, _ in ins[u]])
            units[u].doStep(currentCommunicationPoint=n * 1e-3, communicationStepSize=1e-3)
            values[u] = units[u].getReal(out_vrs[u])
    return (time.perf_counter() - start) / STEPS


def libcosim_seconds_per_step(batches, batch_steps):
    """The median and the fastest of `batches` runs of `batch_steps` steps each, after a warm-up;
    libcosim as the SSP sets it up (fixed-step algorithm, its default worker threads)."""
    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_ssp_file(str(bench / "system.ssp"))
    assert execution.step(200), "libcosim failed a step"
    times = []
    for _ in range(batches):
        start = time.perf_counter()
        assert execution.step(batch_steps), "libcosim failed a step"
        times.append((time.perf_counter() - start) / batch_steps)
    return statistics.median(times), min(times)


master = median("closed_loop_1ms_master")
plain = median("closed_loop_1ms_in_process")
alternating = json.loads((bench / "alternating.json").read_text())
libcosim, libcosim_best = libcosim_seconds_per_step(batches=alternating["batches"] // 4, batch_steps=alternating["batch_steps"])
fmpy = fmpy_seconds_per_step()
print("\nClosed loop (arm + NN friction compensator + task-space controller), one 1 ms step, median:")
print(f"  plain Rust loop, no FMI         {plain * 1e6:8.2f} µs   real-time factor {1e-3 / plain:7.0f}")
print(f"  our master, three FMUs          {master * 1e6:8.2f} µs   real-time factor {1e-3 / master:7.0f}   "
      f"{master / plain:5.3f}x the plain loop's time (target <= 1.05x)")
print(f"  libcosim, the loop's SSP        {libcosim * 1e6:8.2f} µs   real-time factor {1e-3 / libcosim:7.0f}   "
      f"{libcosim / master:5.1f}x our master's time (target >= 5x)")
print(f"  fmpy driving the same FMUs      {fmpy * 1e6:8.2f} µs   real-time factor {1e-3 / fmpy:7.0f}   "
      f"{fmpy / master:5.1f}x our master's time")
best_master, best_plain = alternating["master_s"], alternating["plain_s"]
print(f"\nThe fastest batch of {alternating['batch_steps']} steps ({alternating['batches']} batches of master and "
      f"plain loop in alternation; {alternating['batches'] // 4} of libcosim), per step:")
print(f"  plain Rust loop, no FMI         {best_plain * 1e6:8.2f} µs")
print(f"  our master, three FMUs          {best_master * 1e6:8.2f} µs   {best_master / best_plain:5.3f}x the plain loop's time (target <= 1.05x)")
print(f"  libcosim, the loop's SSP        {libcosim_best * 1e6:8.2f} µs   {libcosim_best / best_master:5.1f}x our master's time (target >= 5x)")
