"""Prints the PlanarArm FMU's per-step cost through its C ABI (criterion, just run) against the
in-process arm step, and fmpy driving the same FMU; run through scripts/bench-fmu."""
import json
import pathlib
import subprocess
import sys

criterion, fmu, python = pathlib.Path(sys.argv[1]), sys.argv[2], sys.executable


def median(name):
    return json.loads((criterion / name / "new" / "estimates.json").read_text())["median"]["point_estimate"] * 1e-9


step = median("arm_1ms_in_process_step")
step_out = median("arm_1ms_in_process_step_and_outputs")
abi = median("arm_1ms_fmu_abi_set_step_get")
here = pathlib.Path(__file__).parent
fmpy = json.loads(subprocess.run([python, here / "fmpy_arm.py", fmu], check=True, capture_output=True, text=True).stdout)["seconds_per_step"]
print("\nOne 1 ms communication step of the default arm (4 RK4 sub-steps), median:")
print(f"  in process, step only            {step * 1e6:8.3f} µs")
print(f"  in process, step + outputs       {step_out * 1e6:8.3f} µs")
print(f"  FMU through C ABI (set/step/get) {abi * 1e6:8.3f} µs   {abi / step:5.3f}x step only, {abi / step_out:5.3f}x step + outputs")
print(f"  fmpy driving the same FMU        {fmpy * 1e6:8.3f} µs   {fmpy / abi:5.1f}x the C ABI from Rust")
print("target: the ABI adds under 10 % to the in-process step")
