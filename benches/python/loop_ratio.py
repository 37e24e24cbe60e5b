"""Prints the closed-loop step cost (arm + NN friction compensator + task-space controller, 1 ms
communication step): our master and the plain Rust loop (criterion, just run by
scripts/bench-loop), libcosim running the same loop from its SSP file (its own stepping loop in
C++, one `cosim_execution_step` call for all steps, no observer), and fmpy driving the same three
FMUs from Python, Gauss–Seidel with one fmi2SetReal / fmi2DoStep / fmi2GetReal per unit and step
(the least a Python master can do).

Checks first that they run the master's loop (its end-effector trajectory, written by
benches/closed_loop.rs as master_xy.csv): fmpy's Gauss–Seidel run ends where the master's does,
to 1e-9 m; libcosim, which passes values on after all units have stepped (one step's delay, see
tests/python/test_ssp_engines.py), takes the master's first step to 1e-12 m and stays within
1 mm of it; then that every time and ratio is a finite positive number.

usage: loop_ratio.py CRITERION_DIR LOOP_BENCH_DIR [--smoke]   (--smoke: fmpy over 200 steps, not 5000)"""
import argparse
import fnmatch
import json
import math
import statistics
import pathlib
import shutil
import time
import tomllib

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from libcosimpy.CosimEnums import CosimVariableType
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver

from bench_checks import agree, fail, positive

ap = argparse.ArgumentParser()
ap.add_argument("criterion", type=pathlib.Path)
ap.add_argument("bench", type=pathlib.Path, help="the folder benches/closed_loop.rs wrote the loop to")
ap.add_argument("--smoke", action="store_true")
args = ap.parse_args()
criterion, bench = args.criterion, args.bench
STEPS = 200 if args.smoke else 5000  # fmpy's
LIBCOSIM_CHECKED_STEPS = 1000
END_EFFECTOR = ["arm.x", "arm.y"]
# libcosim's FMI Library logs "Start attribute is required ..." at error level for every FMU's
# `time`, which FMI 2.0 forbids a start (see tests/python/test_ssp_engines.py): not a failure, and
# libcosim's failures are caught by its calls' results.
log_output_level(CosimLogLevel.FATAL)


def median(name):
    est = json.loads((criterion / name / "new" / "estimates.json").read_text())
    return positive(name, est["median"]["point_estimate"] * 1e-9)


def master_xy():
    """The master's end-effector [m] at the start and after each checked step: rows (x, y)."""
    lines = (bench / "master_xy.csv").read_text().splitlines()
    if lines[0] != "time," + ",".join(END_EFFECTOR):
        fail(f"master_xy.csv: unexpected header {lines[0]!r}")
    return [tuple(float(v) for v in line.split(",")[1:]) for line in lines[1:]]


def fmpy_seconds_per_step():
    """Seconds per step, and the end effector (x, y) [m] after the STEPS steps."""
    spec = tomllib.loads((bench / "system.toml").read_text())
    units, variables, unzipped = {}, {}, []
    for f in spec["fmu"]:
        md = read_model_description(str(bench / f["path"]))
        unzipped.append(extract(str(bench / f["path"])))
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped[-1],
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
    seconds = (time.perf_counter() - start) / STEPS
    end = units["arm"].getReal([variables["arm"][name.split(".", 1)[1]].valueReference for name in END_EFFECTOR])
    for u in order:
        units[u].terminate()
        units[u].freeInstance()
    for folder in unzipped:
        shutil.rmtree(folder, ignore_errors=True)
    return seconds, tuple(end)


def libcosim_seconds_per_step(batches, batch_steps):
    """The median and the fastest of `batches` runs of `batch_steps` steps each, after a warm-up;
    libcosim as the SSP sets it up (fixed-step algorithm, its default worker threads)."""
    execution = CosimExecution.from_ssp_file(str(bench / "system.ssp"))
    assert execution.step(200), "libcosim failed a step"
    times = []
    for _ in range(batches):
        start = time.perf_counter()
        assert execution.step(batch_steps), "libcosim failed a step"
        times.append((time.perf_counter() - start) / batch_steps)
    return statistics.median(times), min(times)


def libcosim_end_effector(steps):
    """libcosim's run of the SSP, `steps` steps, observed: the end effector (x, y) [m] after each."""
    execution = CosimExecution.from_ssp_file(str(bench / "system.ssp"))
    observer = CosimObserver.create_time_series(buffer_size=steps)
    assert execution.add_observer(observer)
    arm = next(s.index for s in execution.slave_infos() if s.name.decode() == "arm")
    references = {v.name.decode(): v.reference for v in execution.slave_variables(arm)}
    for name in END_EFFECTOR:
        assert observer.start_time_series(arm, references[name.split(".", 1)[1]], CosimVariableType.REAL)
    assert execution.step(steps), "libcosim failed a step"
    columns = []
    for name in END_EFFECTOR:
        _, numbers, samples = observer.time_series_real_samples(arm, references[name.split(".", 1)[1]], from_step=1, sample_count=steps)
        if list(numbers) != list(range(1, steps + 1)):
            fail(f"libcosim's observer gave steps {list(numbers)[:3]}... for {name}, not 1 to {steps}")
        columns.append(samples)
    return list(zip(*columns))


reference = master_xy()
if len(reference) <= max(STEPS, LIBCOSIM_CHECKED_STEPS):
    fail(f"master_xy.csv has {len(reference) - 1} steps, the checks need {max(STEPS, LIBCOSIM_CHECKED_STEPS)}")
if max(x for x, _ in reference[:LIBCOSIM_CHECKED_STEPS]) - min(x for x, _ in reference[:LIBCOSIM_CHECKED_STEPS]) < 0.05:
    fail("the master's arm hardly moved: nothing to check the engines against")
fmpy, fmpy_end = fmpy_seconds_per_step()
fmpy_gap = agree(f"end effector after {STEPS} steps, fmpy vs our master [m]", fmpy_end, reference[STEPS], 1e-9)
cosim = libcosim_end_effector(LIBCOSIM_CHECKED_STEPS)
agree("end effector after libcosim's first step vs our master's [m]", cosim[0], reference[1], 1e-12)
cosim_gap = max(math.hypot(cx - mx, cy - my) for (cx, cy), (mx, my) in zip(cosim, reference[1:]))
if not cosim_gap < 1e-3:
    fail(f"libcosim's run strays {cosim_gap:.3e} m from our master's over {LIBCOSIM_CHECKED_STEPS} steps (at most 1 mm)")
print(f"\nfmpy's Gauss–Seidel run is our master's (end effector within {fmpy_gap:.1e} m after {STEPS} steps); "
      f"libcosim's, one step behind, within {cosim_gap * 1e3:.3f} mm over {LIBCOSIM_CHECKED_STEPS} steps")

master = median("closed_loop_1ms_master")
plain = median("closed_loop_1ms_in_process")
alternating = json.loads((bench / "alternating.json").read_text())
libcosim, libcosim_best = libcosim_seconds_per_step(batches=max(alternating["batches"] // 4, 1), batch_steps=alternating["batch_steps"])
for name, value in [("libcosim's step", libcosim), ("libcosim's fastest batch", libcosim_best), ("fmpy's step", fmpy),
                    ("the master's fastest batch", alternating["master_s"]), ("the plain loop's fastest batch", alternating["plain_s"])]:
    positive(name, value)
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
if args.smoke:
    print(f"bench-loop smoke: OK (fmpy = our master to {fmpy_gap:.0e} m, libcosim within {cosim_gap * 1e3:.2f} mm; master/plain "
          f"{master / plain:.2f}x, libcosim/master {libcosim / master:.1f}x, fmpy/master {fmpy / master:.1f}x)")
