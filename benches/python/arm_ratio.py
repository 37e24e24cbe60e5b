"""Prints neurarm's RK4 step (criterion's estimate from the run just made) against MuJoCo's
RK4 step measured now, and the ratio. Run through scripts/bench-arm."""
import json
import pathlib
import sys

import mujoco_arm

criterion = pathlib.Path(sys.argv[1])
rows = []
for case, friction in [("friction", True), ("frictionless", False)]:
    est = json.loads((criterion / f"rk4_step_1ms_{case}" / "new" / "estimates.json").read_text())
    ours = est["median"]["point_estimate"] * 1e-9
    theirs = mujoco_arm.time_per_step(friction)
    rows.append((case, ours, theirs))
print(f"\nOne RK4 step of the default 4-link arm, dt = 1 ms (MuJoCo {mujoco_arm.mujoco.__version__}, median):")
print(f"{'case':<14}{'neurarm':>12}{'MuJoCo':>12}{'MuJoCo/neurarm':>17}")
for case, ours, theirs in rows:
    print(f"{case:<14}{ours * 1e6:>10.3f}µs{theirs * 1e6:>10.3f}µs{theirs / ours:>16.1f}x")
print("target: neurarm at least 4x faster (MuJoCo/neurarm >= 4)")
