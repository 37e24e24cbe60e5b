"""Prints neurarm's RK4 step (criterion's estimate from the run just made) against MuJoCo's
RK4 step measured now, and the ratio. Run through scripts/bench-arm.

First checks that the two compute the same: MuJoCo's frictionless trajectory over the bench's
first 1000 steps against neurarm's (written by benches/arm_step.rs), to 1e-10 rad and 1e-9 rad/s
(both are plain RK4 of the same ODE); then that every time and ratio is a finite positive number.

usage: arm_ratio.py CRITERION_DIR ARM_BENCH_DIR [--smoke]   (--smoke: MuJoCo timed over 5 runs, not 200)"""
import argparse
import json
import pathlib

import numpy as np

import mujoco_arm
from bench_checks import agree, positive

ap = argparse.ArgumentParser()
ap.add_argument("criterion", type=pathlib.Path)
ap.add_argument("reference", type=pathlib.Path, help="the folder benches/arm_step.rs wrote frictionless.csv to")
ap.add_argument("--smoke", action="store_true")
args = ap.parse_args()

ours = np.loadtxt(args.reference / "frictionless.csv", delimiter=",", skiprows=1)[:, 1:]
theirs = mujoco_arm.states(len(ours) - 1)
if np.abs(ours[-1, :4] - ours[0, :4]).max() < 0.5:
    raise SystemExit("bench check failed: the reference arm hardly moved")
q_gap = agree("q, neurarm vs MuJoCo, frictionless", ours[:, :4].ravel(), theirs[:, :4].ravel(), 1e-10)
qd_gap = agree("q̇, neurarm vs MuJoCo, frictionless", ours[:, 4:].ravel(), theirs[:, 4:].ravel(), 1e-9)
print(f"\nMuJoCo's frictionless trajectory is neurarm's over {len(ours) - 1} steps: "
      f"within {q_gap:.1e} rad and {qd_gap:.1e} rad/s")

rows = []
for case, friction in [("friction", True), ("frictionless", False)]:
    est = json.loads((args.criterion / f"rk4_step_1ms_{case}" / "new" / "estimates.json").read_text())
    ours_s = positive(f"neurarm's step ({case})", est["median"]["point_estimate"] * 1e-9)
    theirs_s = positive(f"MuJoCo's step ({case})", mujoco_arm.time_per_step(friction, repeats=5 if args.smoke else 200))
    rows.append((case, ours_s, theirs_s, positive(f"MuJoCo/neurarm ({case})", theirs_s / ours_s)))
print(f"\nOne RK4 step of the default 4-link arm, dt = 1 ms (MuJoCo {mujoco_arm.mujoco.__version__}, median):")
print(f"{'case':<14}{'neurarm':>12}{'MuJoCo':>12}{'MuJoCo/neurarm':>17}")
for case, ours_s, theirs_s, ratio in rows:
    print(f"{case:<14}{ours_s * 1e6:>10.3f}µs{theirs_s * 1e6:>10.3f}µs{ratio:>16.1f}x")
print("target: neurarm at least 4x faster (MuJoCo/neurarm >= 4)")
if args.smoke:
    print(f"bench-arm smoke: OK (trajectories agree to {q_gap:.0e} rad; MuJoCo/neurarm "
          + ", ".join(f"{r:.1f}x {c}" for c, _, _, r in rows) + ")")
