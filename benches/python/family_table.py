"""Full paper runs on the random family of arms and a table of issue 24's targets.

Arm k (k = 1..count) is `neurarm random-arm --seed k --joints 2 + (k - 1) % 7`, so every seven
seeds cover 2 to 8 joints. Each arm's run writes results.json; the table takes its figures from
there (nothing is recomputed here) and marks each target met or missed:
sim NN/perfect <= 1.10, none/perfect >= 5 (else: "little friction", reported, not a miss),
real NN/none <= 0.3, gravity whole-turn RMS < 1 % and largest < 5 % of each joint's largest
torque, joint-loop NN settled error <= 1.5 x ideal on every joint.
"""

import argparse
import concurrent.futures
import json
import math
import os
import subprocess
import sys
import time

TARGETS = {
    "sim_nn_over_perfect": 1.10,
    "sim_none_over_perfect": 5.0,
    "real_nn_over_none": 0.3,
    "gravity_rms_share": 0.01,
    "gravity_max_share": 0.05,
    "joint_nn_over_ideal": 1.5,
}


def joints_of(seed):
    return 2 + (seed - 1) % 7


def run_arm(neurarm, out, seed, extra):
    joints = joints_of(seed)
    name = f"seed{seed:02d}_j{joints}"
    config = os.path.join(out, "arms", name + ".toml")
    run_dir = os.path.join(out, "runs", name)
    log = os.path.join(out, "runs", name + ".log")
    subprocess.run([neurarm, "random-arm", "--seed", str(seed), "--joints", str(joints), "-o", config], check=True)
    started = time.monotonic()
    with open(log, "w") as f:
        rc = subprocess.run([neurarm, "paper", "-c", config, "-o", run_dir, "--threads", "1", *extra], stdout=f, stderr=subprocess.STDOUT).returncode
    row = {"seed": seed, "joints": joints, "arm": config, "wall_s": time.monotonic() - started, "exit_code": rc}
    if rc != 0:
        with open(log) as f:
            lines = [l.strip() for l in f if l.strip()]
        row["error"] = lines[-1] if lines else "no output"
        return row
    with open(os.path.join(run_dir, "results.json")) as f:
        r = json.load(f)
    ratios = r["table_1"]["ratios"]
    row["sim_nn_over_perfect"] = ratios["sim_nn_over_perfect"]
    row["sim_none_over_perfect"] = ratios["sim_none_over_perfect"]
    row["real_nn_over_none"] = ratios["real_nn_over_none"]
    row["worst_friction_net_share"] = max(f["net_error_share"] for f in r["friction"])
    whole = r["gravity"]["net"]["whole_turn"]
    row["gravity_rms_share"] = max(whole["rms_share"])
    row["gravity_max_share"] = max(whole["max_share"])
    settled = r["joint_loop"]["settled_rad"]
    row["joint_nn_over_ideal"] = max(nn / ideal if ideal > 0 else math.inf for ideal, nn in zip(settled[0], settled[1]))
    row["run_s"] = r["total_s"]
    return row


def verdicts(row):
    """The targets this row misses, and whether none/perfect < 5 is reported as little friction."""
    if "error" in row:
        return ["run failed"], False
    missed = []
    if row["sim_nn_over_perfect"] > TARGETS["sim_nn_over_perfect"]:
        missed.append("sim NN/perfect")
    little_friction = row["sim_none_over_perfect"] < TARGETS["sim_none_over_perfect"]
    if row["real_nn_over_none"] > TARGETS["real_nn_over_none"]:
        missed.append("real NN/none")
    if row["gravity_rms_share"] >= TARGETS["gravity_rms_share"]:
        missed.append("gravity RMS")
    if row["gravity_max_share"] >= TARGETS["gravity_max_share"]:
        missed.append("gravity largest")
    if row["joint_nn_over_ideal"] > TARGETS["joint_nn_over_ideal"]:
        missed.append("joint loop")
    return missed, little_friction


def table(rows):
    head = ("| seed | joints | sim NN/perfect | none/perfect | real NN/none | worst friction net | gravity RMS | gravity largest | joint NN/ideal | time [s] | missed |\n"
            "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n")
    lines = []
    for row in rows:
        missed, little = verdicts(row)
        if "error" in row:
            lines.append(f"| {row['seed']} | {row['joints']} | | | | | | | | {row['wall_s']:.0f} | run failed: {row['error']} |")
            continue
        note = ", ".join(missed) or "none"
        if little:
            note += " (none/perfect < 5: little friction)"
        lines.append(
            f"| {row['seed']} | {row['joints']} | {row['sim_nn_over_perfect']:.3f} | {row['sim_none_over_perfect']:.1f} | "
            f"{row['real_nn_over_none']:.3f} | {100 * row['worst_friction_net_share']:.2f} % | {100 * row['gravity_rms_share']:.2f} % | "
            f"{100 * row['gravity_max_share']:.2f} % | {row['joint_nn_over_ideal']:.2f} | {row['run_s']:.0f} | {note} |")
    met = sum(1 for row in rows if not verdicts(row)[0])
    return head + "\n".join(lines) + f"\n\n{met} of {len(rows)} arms meet every target.\n"


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--neurarm", required=True)
    p.add_argument("--count", type=int, default=20)
    p.add_argument("--out", required=True)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("extra", nargs="*")
    a = p.parse_args()
    if a.count < 1:
        sys.exit("bench-family: N must be at least 1")
    for sub in ("arms", "runs"):
        os.makedirs(os.path.join(a.out, sub), exist_ok=True)
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        rows = list(pool.map(lambda s: run_arm(a.neurarm, a.out, s, a.extra), range(1, a.count + 1)))
    text = ("# The paper's pipeline on the random family of arms\n\n"
            f"Full `neurarm paper` runs, one thread each, {a.jobs} at a time; extra options: {' '.join(a.extra) or 'none'}.\n\n"
            + table(rows))
    for name, content in (("family.md", text), ("family.json", json.dumps({"targets": TARGETS, "arms": rows}, indent=1))):
        tmp = os.path.join(a.out, name + ".tmp")
        with open(tmp, "w") as f:
            f.write(content)
        os.replace(tmp, os.path.join(a.out, name))
    print(text)


if __name__ == "__main__":
    main()
