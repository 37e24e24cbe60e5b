"""Full paper runs on the random family of arms and a table of issue 24's targets.

Arm k (k = 1..count) is `neurarm random-arm --seed k --joints 2 + (k - 1) % 7`, so every seven
seeds cover 2 to 8 joints. Each arm's run writes results.json; the table takes its figures from
there (nothing is recomputed here) and marks each target met or missed:
sim NN/perfect <= 1.10, none/perfect >= 5 (else: "little friction", reported, not a miss, unless
the ratios are chaotic on the arm: then a miss put down to that),
real NN/none <= 0.3, gravity whole-turn RMS < 1 % and largest < 5 % of each joint's largest
torque, joint-loop NN settled error <= 1.5 x ideal on every joint. Beside them: the share of the
perfect-compensation tracking run's samples with a joint at rest (stick-slip), and real NN/none
against the true positions (the measured one carries the emulated encoders' noise), what the
real arm's true friction law gives fed the same measured speed (perfect/none), and real NN/none
with the sensors' noise off: a miss that the noise-free run meets while the true law on the
measured speed does no better than the net is the sensors' limit, and is marked so; a miss
where even the true law with the noise off stays above the target, and the net does no worse
than the law with and without the noise, is beyond the arm (friction too small a part of the
uncompensated error), and is marked so. For sim NN/perfect: the simulated arm's true law scaled by 0.99 and by 1.01 over perfect; a miss no
further above 1 than the farther of those two from 1, on either side (a law 1 % off moves the
ratio that far: upwards where the perfect run's error is tiny, either way where the arm sticks
and slips), is marked so. Where the law scaled by 0.999 or 1.001 already moves the ratio past
the target's margin and the nets are further off than 0.1 % at low speed, the ratio is chaotic
on that arm and the miss is marked so.
"""

import argparse
import concurrent.futures
import json
import math
import os
import subprocess
import sys
import time

from bench_checks import fail, positive

# As the report's: beyond this settled error [rad] even the ideal compensator leaves joints stuck.
STUCK_SETTLED_RAD = 0.05

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


def paths(out, seed):
    name = f"seed{seed:02d}_j{joints_of(seed)}"
    return (os.path.join(out, "arms", name + ".toml"), os.path.join(out, "runs", name), os.path.join(out, "runs", name + ".log"))


def run_arm(neurarm, out, seed, extra):
    config, run_dir, log = paths(out, seed)
    subprocess.run([neurarm, "random-arm", "--seed", str(seed), "--joints", str(joints_of(seed)), "-o", config], check=True)
    started = time.monotonic()
    with open(log, "w") as f:
        rc = subprocess.run([neurarm, "paper", "-c", config, "-o", run_dir, "--threads", "1", *extra], stdout=f, stderr=subprocess.STDOUT).returncode
    return read_row(out, seed, time.monotonic() - started, rc)


def read_row(out, seed, wall_s, rc):
    """The figures of arm `seed`'s run from its results.json (or its log's last line if it failed)."""
    config, run_dir, log = paths(out, seed)
    row = {"seed": seed, "joints": joints_of(seed), "arm": config, "wall_s": wall_s, "exit_code": rc}
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
    true = r["table_1"]["true_mse_m2"]
    # Against the true positions: the measured MSE carries the emulated encoders' noise, the
    # same floor under both cases.
    row["real_nn_over_none_true"] = true["real_nn"] / true["real_none"]
    # What the sensors cost (runs written before results.json carried it: None).
    sensors = r["table_1"].get("real_sensors", {})
    row["real_perfect_over_none"] = sensors.get("perfect_over_none")
    row["real_nn_over_none_quiet"] = sensors.get("quiet_nn_over_none")
    row["real_perfect_over_none_quiet"] = sensors.get("quiet_perfect_over_none")
    law = r["table_1"].get("sim_law_sensitivity", {})
    row["sim_law_low_over_perfect"] = law.get("low_over_perfect")
    row["sim_law_high_over_perfect"] = law.get("high_over_perfect")
    row["sim_law_error"] = law.get("law_error")
    fine = r["table_1"].get("sim_law_sensitivity_fine", {})
    row["sim_fine_low_over_perfect"] = fine.get("low_over_perfect")
    row["sim_fine_high_over_perfect"] = fine.get("high_over_perfect")
    row["sim_fine_law_error"] = fine.get("law_error")
    row["diagnostic_failures"] = r["table_1"].get("diagnostic_failures", [])
    # The online-adaptation runs that failed (not one of issue 24's targets, shown beside them).
    row["adaptation_failures"] = [name for name, _ in r.get("adaptation", {}).get("failures", [])]
    row["worst_friction_net_share"] = max(f["net_error_share"] for f in r["friction"])
    # The simulated arm's nets at low speed (5-200 mrad/s), where they cross the Coulomb step:
    # what NN/perfect is most sensitive to. Runs written before results.json carried it: None.
    low = [f["low_speed_error"] for f in r["friction"] if f["arm"] == "sim" and "low_speed_error" in f]
    row["worst_low_speed_share_sim"] = max(e["rms_nm"] / e["largest_friction_nm"] for e in low) if low else None
    whole = r["gravity"]["net"]["whole_turn"]
    row["gravity_rms_share"] = max(whole["rms_share"])
    row["gravity_max_share"] = max(whole["max_share"])
    settled = r["joint_loop"]["settled_rad"]
    row["joint_nn_over_ideal"] = max(nn / ideal if ideal > 0 else math.inf for ideal, nn in zip(settled[0], settled[1]))
    # How far even the ideal compensator settles from the targets: beyond STUCK_SETTLED_RAD
    # the joints stick where K_p (q_d - q) falls below their breakaway torque (the report's
    # "gains are low for this arm's friction").
    row["joint_ideal_settled_rad"] = max(settled[0])
    row["run_s"] = r["total_s"]
    # Share of the perfect-compensation run's samples with a joint at rest: stick-slip, which
    # the report flags and which makes NN/perfect a comparison of two stick-slip motions.
    row["perfect_resting_share"] = r["table_1"].get("resting_share", {}).get("sim_perfect")
    if row["perfect_resting_share"] is None:
        row["perfect_resting_share"] = resting_share(os.path.join(run_dir, "data", "tracking_sim_perfect.csv"))
    return row


def resting_share(path):
    """Share of a tracking CSV's rows with some |arm_qd_i| < 1 mrad/s (runs written before
    results.json carried it)."""
    import csv
    with open(path) as f:
        rows = list(csv.DictReader(f))
    speeds = [c for c in (rows[0] if rows else {}) if c.startswith("arm_qd_")]
    if not rows or not speeds:
        return None
    return sum(1 for r in rows if any(abs(float(r[c])) < 1e-3 for c in speeds)) / len(rows)


def fine_scatter(row):
    """How far the true law 0.1 % off moves sim NN/perfect from 1, either way (None if not measured)."""
    low, high, err = row.get("sim_fine_low_over_perfect"), row.get("sim_fine_high_over_perfect"), row.get("sim_fine_law_error")
    return None if None in (low, high, err) else max(abs(low - 1), abs(high - 1))


def chaotic(row, low_speed):
    """True where the true law 0.1 % off already moves sim NN/perfect past the target's margin
    and the nets are further off than that at low speed: no compensator that close can be held
    to the target, so the miss says nothing of the nets (the 6-joint example: 1.64, 0.99)."""
    scatter = fine_scatter(row)
    if None in (scatter, low_speed):
        return False
    return scatter > TARGETS["sim_nn_over_perfect"] - 1 and low_speed > row["sim_fine_law_error"]


def verdicts(row):
    """The targets this row misses, and whether none/perfect < 5 is reported as little friction."""
    if "error" in row:
        return ["run failed"], False
    missed = []
    if row["sim_nn_over_perfect"] > TARGETS["sim_nn_over_perfect"]:
        low, high, err = row.get("sim_law_low_over_perfect"), row.get("sim_law_high_over_perfect"), row.get("sim_law_error")
        low_speed = row.get("worst_low_speed_share_sim")
        # How far the true law 1 % off moves the ratio from 1, either way: above 1 where the
        # perfect run's error is tiny, on both sides where the arm sticks and slips and the MSE
        # is chaotic in small torques (a 1 % lower law then tracked 2.7 x better, seed 5).
        scatter = None if low is None or high is None else max(abs(low - 1), abs(high - 1))
        if scatter is not None and row["sim_nn_over_perfect"] - 1 <= scatter:
            missed.append(f"sim NN/perfect (within the true law +-{100 * err:.0f} %'s scatter: {low:.2f}, {high:.2f} x perfect)")
        elif chaotic(row, low_speed):
            missed.append(f"sim NN/perfect (chaotic: the true law +-{100 * row['sim_fine_law_error']:.1f} % already gives "
                          f"{row['sim_fine_low_over_perfect']:.2f}, {row['sim_fine_high_over_perfect']:.2f} x perfect; "
                          f"the nets {100 * low_speed:.1f} % off at low speed)")
        elif None not in (scatter, low_speed, err) and low_speed > err \
                and scatter * low_speed / err >= row["sim_nn_over_perfect"] - 1:
            # The nets are further off at low speed than the law error of the band, and the
            # band's change of the ratio, scaled by how much further, reaches the miss.
            missed.append(f"sim NN/perfect (nets {100 * low_speed:.1f} % off at low speed; the true law "
                          f"+-{100 * err:.0f} % already gives {low:.2f}, {high:.2f} x perfect)")
        else:
            detail = "" if low_speed is None else f": nets {100 * low_speed:.1f} % off at low speed, the band does not reach it"
            missed.append(f"sim NN/perfect (not explained{detail})")
    little_friction = row["sim_none_over_perfect"] < TARGETS["sim_none_over_perfect"]
    fine = fine_scatter(row)
    if little_friction and fine is not None and fine > TARGETS["sim_nn_over_perfect"] - 1:
        # The perfect run's own error is chaotic: none/perfect < 5 need not mean little friction.
        little_friction = False
        missed.append(f"none/perfect (chaotic: the true law +-{100 * row['sim_fine_law_error']:.1f} % gives "
                      f"{row['sim_fine_low_over_perfect']:.2f}, {row['sim_fine_high_over_perfect']:.2f} x perfect)")
    if row["real_nn_over_none"] > TARGETS["real_nn_over_none"]:
        quiet, perfect = row.get("real_nn_over_none_quiet"), row.get("real_perfect_over_none")
        quiet_law = row.get("real_perfect_over_none_quiet")
        if row["real_nn_over_none_true"] <= TARGETS["real_nn_over_none"]:
            missed.append("real NN/none (met on the true positions: the measured error's noise floor)")
        elif quiet is not None and quiet <= TARGETS["real_nn_over_none"] and perfect is not None and perfect >= row["real_nn_over_none_true"]:
            missed.append(f"real NN/none (the speed noise: met with it off; the true law on the measured speed gives {perfect:.2f} x none)")
        elif quiet is not None and quiet_law is not None and quiet_law > TARGETS["real_nn_over_none"] and quiet <= quiet_law \
                and perfect is not None and perfect >= row["real_nn_over_none_true"]:
            # Even the arm's own law, noise off, leaves more than the target of the uncompensated
            # error: friction is too small a part of it (little friction), and the net does as well.
            missed.append(f"real NN/none (beyond the arm: its true law gives {quiet_law:.2f} x none with the noise off, "
                          f"{perfect:.2f} x with it; the net {quiet:.2f} and {row['real_nn_over_none_true']:.2f})")
        else:
            missed.append("real NN/none")
    if row["gravity_rms_share"] >= TARGETS["gravity_rms_share"]:
        missed.append("gravity RMS")
    if row["gravity_max_share"] >= TARGETS["gravity_max_share"]:
        missed.append("gravity largest")
    if row["joint_nn_over_ideal"] > TARGETS["joint_nn_over_ideal"]:
        stuck = row.get("joint_ideal_settled_rad")
        if stuck is not None and stuck > STUCK_SETTLED_RAD:
            missed.append(f"joint loop (gains low for the friction: the ideal compensator itself settles {stuck:.2f} rad off)")
        else:
            missed.append("joint loop")
    return missed, little_friction


def table(rows):
    head = ("| seed | joints | sim NN/perfect | sim law x0.99 / x1.01 over perfect | sim law x0.999 / x1.001 | none/perfect | real NN/none | real NN/none, true positions | real perfect/none, measured speed | real NN/none, noise off | worst friction net | sim nets at low speed | gravity RMS | gravity largest | joint NN/ideal | perfect run: joint at rest | time [s] | missed |\n"
            "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n")
    lines = []
    for row in rows:
        missed, little = verdicts(row)
        if "error" in row:
            lines.append(f"| {row['seed']} | {row['joints']} | | | | | | | | | | | | | | | {row['wall_s']:.0f} | run failed: {row['error']} |")
            continue
        share = row.get("perfect_resting_share")
        resting = "" if share is None else f"{100 * share:.1f} %"
        low = row.get("worst_low_speed_share_sim")
        low_speed = "" if low is None else f"{100 * low:.2f} %"
        fmt = lambda v: "" if v is None else f"{v:.3f}"
        lo, hi = row.get("sim_law_low_over_perfect"), row.get("sim_law_high_over_perfect")
        law = "" if lo is None or hi is None else f"{lo:.2f} / {hi:.2f}"
        lo, hi = row.get("sim_fine_low_over_perfect"), row.get("sim_fine_high_over_perfect")
        fine = "" if lo is None or hi is None else f"{lo:.2f} / {hi:.2f}"
        note = ", ".join(missed) or "none"
        if little:
            note += " (none/perfect < 5: little friction)"
        if row.get("diagnostic_failures"):
            note += "; diagnostic loop failed: " + "; ".join(row["diagnostic_failures"])
        if row.get("adaptation_failures"):
            note += "; adaptation run failed: " + ", ".join(row["adaptation_failures"])
        lines.append(
            f"| {row['seed']} | {row['joints']} | {row['sim_nn_over_perfect']:.3f} | {law} | {fine} | {row['sim_none_over_perfect']:.1f} | "
            f"{row['real_nn_over_none']:.3f} | {row['real_nn_over_none_true']:.3f} | {fmt(row.get('real_perfect_over_none'))} | {fmt(row.get('real_nn_over_none_quiet'))} | {100 * row['worst_friction_net_share']:.2f} % | {low_speed} | {100 * row['gravity_rms_share']:.2f} % | "
            f"{100 * row['gravity_max_share']:.2f} % | {row['joint_nn_over_ideal']:.2f} | {resting} | {row['run_s']:.0f} | {note} |")
    met = sum(1 for row in rows if not verdicts(row)[0])
    return head + "\n".join(lines) + f"\n\n{met} of {len(rows)} arms meet every target.\n"


# The figures of a row that are ratios, shares or times: finite and positive in every run.
POSITIVE = ["sim_nn_over_perfect", "sim_none_over_perfect", "real_nn_over_none", "real_nn_over_none_true", "worst_friction_net_share",
            "gravity_rms_share", "gravity_max_share", "joint_nn_over_ideal", "run_s"]


def check(out, count, rows, text):
    """The smoke mode's checks: every run finished with its figures; family.json holds the rows
    and family.md the table; the table rebuilt from the runs' results.json is the same table."""
    for row in rows:
        if "error" in row:
            fail(f"arm {row['seed']}'s run failed ({row['exit_code']}): {row['error']}")
        for name in POSITIVE:
            positive(f"arm {row['seed']}: {name}", row[name])
    with open(os.path.join(out, "family.json")) as f:
        written = json.load(f)
    if written["targets"] != TARGETS or [r["seed"] for r in written["arms"]] != list(range(1, count + 1)):
        fail("family.json does not hold the targets and one row per arm")
    with open(os.path.join(out, "family.md")) as f:
        if f.read() != text:
            fail("family.md is not the table printed")
    rebuilt = [read_row(out, s, math.nan, 0) for s in range(1, count + 1)]
    if table(rebuilt) != table(rows):
        fail("the table rebuilt from the runs' results.json differs from the one built as they ran")
    met = sum(1 for row in rows if not verdicts(row)[0])
    print(f"bench-family smoke: OK ({count} arms of {', '.join(str(r['joints']) for r in rows)} joints ran, {met} of them meet every target; "
          "family.json and family.md written, the table rebuilt from the runs alike)")


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--neurarm", required=True)
    p.add_argument("--count", type=int, default=20)
    p.add_argument("--out", required=True)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--rebuild", action="store_true", help="only rebuild the table from the runs already in OUT/runs")
    p.add_argument("--smoke", action="store_true", help="check the runs, the files and a rebuilt table; one line of summary")
    p.add_argument("extra", nargs="*")
    a = p.parse_args()
    if a.count < 1:
        sys.exit("bench-family: N must be at least 1")
    for sub in ("arms", "runs"):
        os.makedirs(os.path.join(a.out, sub), exist_ok=True)
    if a.rebuild:
        rows = [read_row(a.out, s, math.nan, 0 if os.path.isfile(os.path.join(paths(a.out, s)[1], "results.json")) else 1)
                for s in range(1, a.count + 1)]
    else:
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
    if a.smoke:
        check(a.out, a.count, rows, text)


if __name__ == "__main__":
    main()
