"""Prints the PlanarArm FMU's per-step cost through its C ABI (criterion, just run) against the
in-process arm step, and fmpy driving the same FMU; run through scripts/bench-fmu.

Checks first that fmpy's run computes what the arm computes in process (its 12 outputs after
1000 steps from the start, bit for bit, against the ones benches/fmu_step.rs wrote, which it
checked against the C ABI's), then that every time and ratio is a finite positive number.

usage: fmu_ratio.py CRITERION_DIR PlanarArm.fmu FMU_BENCH_DIR [--smoke]   (--smoke: fmpy timed over 2 runs, not 5)"""
import argparse
import json
import pathlib
import subprocess
import sys

from bench_checks import agree, fail, positive

ap = argparse.ArgumentParser()
ap.add_argument("criterion", type=pathlib.Path)
ap.add_argument("fmu")
ap.add_argument("reference", type=pathlib.Path, help="the folder benches/fmu_step.rs wrote in_process.json to")
ap.add_argument("--smoke", action="store_true")
args = ap.parse_args()


def median(name):
    est = json.loads((args.criterion / name / "new" / "estimates.json").read_text())
    return positive(name, est["median"]["point_estimate"] * 1e-9)


here = pathlib.Path(__file__).parent
fmpy = json.loads(subprocess.run([sys.executable, here / "fmpy_arm.py", args.fmu, "2" if args.smoke else "5"],
                                 check=True, capture_output=True, text=True).stdout)
reference = json.loads((args.reference / "in_process.json").read_text())
if fmpy["steps"] != reference["steps"] or sorted(fmpy["outputs"]) != sorted(reference["outputs"]):
    fail(f"fmpy ran {fmpy['steps']} steps with outputs {sorted(fmpy['outputs'])}, the reference {reference['steps']} with {sorted(reference['outputs'])}")
names = sorted(reference["outputs"])
agree(f"the FMU's outputs after {fmpy['steps']} steps, fmpy vs in process", [fmpy["outputs"][n] for n in names],
      [reference["outputs"][n] for n in names], 0.0)
print(f"\nfmpy's run of the FMU is the in-process arm's: {len(names)} outputs after {fmpy['steps']} steps, bit for bit")

step = median("arm_1ms_in_process_step")
step_out = median("arm_1ms_in_process_step_and_outputs")
abi = median("arm_1ms_fmu_abi_set_step_get")
fmpy_s = positive("fmpy's step", fmpy["seconds_per_step"])
print("\nOne 1 ms communication step of the default arm (4 RK4 sub-steps), median:")
print(f"  in process, step only            {step * 1e6:8.3f} µs")
print(f"  in process, step + outputs       {step_out * 1e6:8.3f} µs")
print(f"  FMU through C ABI (set/step/get) {abi * 1e6:8.3f} µs   {abi / step:5.3f}x step only, {abi / step_out:5.3f}x step + outputs")
print(f"  fmpy driving the same FMU        {fmpy_s * 1e6:8.3f} µs   {fmpy_s / abi:5.1f}x the C ABI from Rust")
print("target: the ABI adds under 10 % to the in-process step")
if args.smoke:
    print(f"bench-fmu smoke: OK (fmpy = in process, bit for bit; ABI/in-process step {abi / step:.2f}x, fmpy/ABI {fmpy_s / abi:.1f}x)")
