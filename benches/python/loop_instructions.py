"""Instructions per step of the closed loop (arm + NN friction compensator + task-space
controller, 1 ms), counted by callgrind: our master, the plain Rust loop and libcosim on the same
loop's SSP. Unlike times, instruction counts do not move with the load of a shared machine; but
they do not see cache misses, threads waiting for each other or system calls, so their ratios are
not the ratios of times (libcosim's time, spent largely in its thread pool's hand-overs, is far
above what its instructions say).

- master and plain loop: the criterion bench run with NEURARM_LOOP_PROFILE_STEPS=N (both loops
  take N steps, criterion skipped), collecting only inside `master_step` and `plain_step`;
- libcosim: two runs of the SSP, of N0 and N0 + N steps; the difference is N steps' worth
  (setup and loading cancel), every thread counted.

Usage: loop_instructions.py BENCH_EXECUTABLE BENCH_DIR
"""
import os
import pathlib
import re
import subprocess
import sys
import tempfile

bench_exe, bench = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
STEPS = 2000
LIBCOSIM_SETUP_STEPS = 200

LIBCOSIM_RUN = """
import sys
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
log_output_level(CosimLogLevel.FATAL)
assert CosimExecution.from_ssp_file(sys.argv[1]).step(int(sys.argv[2])), "libcosim failed a step"
"""


def callgrind(command, out, *options, env=None):
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", *options, *command],
                   check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def inclusive(out, function):
    """The inclusive instruction count of `function` (its name up to the arguments)."""
    text = subprocess.run(["callgrind_annotate", "--inclusive=yes", str(out)], check=True,
                          capture_output=True, text=True).stdout
    for line in text.splitlines():
        m = re.match(r"\s*([\d,]+) \(.*?\)\s+\S*?:(\S+) \[", line)
        if m and m.group(2) == function:
            return int(m.group(1).replace(",", ""))
    raise SystemExit(f"{function} not found in {out}")


def total(out):
    text = subprocess.run(["callgrind_annotate", str(out)], check=True, capture_output=True, text=True).stdout
    return int(re.search(r"([\d,]+) \(100.0%\)\s+PROGRAM TOTALS", text).group(1).replace(",", ""))


with tempfile.TemporaryDirectory() as tmp:
    tmp = pathlib.Path(tmp)
    master_fn, plain_fn = "closed_loop::master_step", "closed_loop::plain_step"
    callgrind([str(bench_exe), "--bench", "no-such-benchmark"], tmp / "loops.out", "--collect-atstart=no",
              f"--toggle-collect={master_fn}", f"--toggle-collect={plain_fn}",
              env={**os.environ, "NEURARM_LOOP_PROFILE_STEPS": str(STEPS)})
    master = inclusive(tmp / "loops.out", master_fn) / STEPS
    plain = inclusive(tmp / "loops.out", plain_fn) / STEPS
    script = tmp / "libcosim_run.py"
    script.write_text(LIBCOSIM_RUN)
    counts = []
    for n in [LIBCOSIM_SETUP_STEPS, LIBCOSIM_SETUP_STEPS + STEPS]:
        callgrind([sys.executable, str(script), str(bench / "system.ssp"), str(n)], tmp / f"libcosim{n}.out")
        counts.append(total(tmp / f"libcosim{n}.out"))
    libcosim = (counts[1] - counts[0]) / STEPS

print("\nClosed loop, one 1 ms step, instructions (callgrind; not the ratios of times):")
print(f"  plain Rust loop, no FMI         {plain:9.0f}")
print(f"  our master, three FMUs          {master:9.0f}   {master / plain:5.3f}x the plain loop's (the 1.05x target is of times)")
print(f"  libcosim, the loop's SSP        {libcosim:9.0f}   {libcosim / master:5.2f}x our master's")
