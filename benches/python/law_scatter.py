"""How chaotic a run's sim NN/perfect is: the perfect-compensation tracking loop of a finished
`neurarm paper` run, rerun with each joint's true friction law scaled by 1 +- EPS (a random sign
per joint, seeded), MSE over the exact law's.

The run itself measures two draws (every joint x0.999 and x1.001, `table_1.sim_law_sensitivity_fine`);
this gives the distribution. Where compensators that close to the law land anywhere between 1
and several times perfect, one NN/perfect figure says nothing of the nets.

    python3 benches/python/law_scatter.py RUN --neurarm target/release/neurarm [--draws 8] [--error 0.001]

Prints one line per draw and writes RUN/law_scatter.json ({"law_error", "draws": [{"scales",
"over_perfect"}], "nn_over_perfect"}). Each loop is written as RUN/systems/law_scatter_K.toml
(reruns with `neurarm simulate`) and its trajectory to a temporary folder.
"""

import argparse
import concurrent.futures
import json
import os
import random
import re
import subprocess
import tempfile

from null_damping_scan import mse


def main():
    p = argparse.ArgumentParser()
    p.add_argument("run", help="a finished `neurarm paper` output folder")
    p.add_argument("--neurarm", required=True)
    p.add_argument("--draws", type=int, default=8)
    p.add_argument("--error", type=float, default=0.001, help="relative error of each joint's law")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--jobs", type=int, default=2)
    a = p.parse_args()
    template_path = os.path.join(a.run, "systems", "tracking_sim_perfect_low.toml")
    with open(template_path) as f:
        template = f.read()
    joints = sorted({int(j) for j in re.findall(r"^coulomb_scale_(\d+) = ", template, re.M)})
    if not joints:
        raise SystemExit(f"{template_path}: no coulomb_scale_i parameters (not a perfect-compensation loop of neurarm paper)")
    rng = random.Random(a.seed)
    draws = [[1.0] * len(joints)] + [[1.0 + a.error * rng.choice((-1.0, 1.0)) for _ in joints] for _ in range(a.draws)]

    with tempfile.TemporaryDirectory() as scratch:
        def run(k):
            text = template
            for j, scale in zip(joints, draws[k]):
                for part in ("coulomb", "viscous"):
                    text = re.sub(rf"^{part}_scale_{j} = .*$", f"{part}_scale_{j} = {scale!r}", text, flags=re.M)
            system = os.path.join(a.run, "systems", f"law_scatter_{k}.toml")
            with open(system, "w") as f:
                f.write(f"# benches/python/law_scatter.py, draw {k} (the friction law's scales below); made from:\n" + text)
            out = os.path.join(scratch, f"{k}.csv")
            done = subprocess.run([a.neurarm, "simulate", system, "-o", out], capture_output=True, text=True)
            if done.returncode != 0:
                return None, done.stderr.strip().splitlines()[-1:] or ["failed"]
            return mse(out), None

        with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
            results = list(pool.map(run, range(len(draws))))
    exact, why = results[0]
    if exact is None:
        raise SystemExit(f"the exact law's loop failed: {why}")
    with open(os.path.join(a.run, "results.json")) as f:
        nn = json.load(f)["table_1"]["ratios"]["sim_nn_over_perfect"]
    report = {"law_error": a.error, "seed": a.seed, "nn_over_perfect": nn, "draws": []}
    print(f"exact law: MSE {exact:.4e} m^2; NN/perfect of the run {nn:.3f}")
    for k in range(1, len(draws)):
        m, why = results[k]
        ratio = None if m is None else m / exact
        report["draws"].append({"scales": draws[k], "over_perfect": ratio, "failed": why})
        scales = " ".join(f"{s:.4f}" for s in draws[k])
        print(f"draw {k}: scales {scales}: " + (f"{ratio:.3f} x perfect" if ratio is not None else f"failed: {why}"))
    ratios = [d["over_perfect"] for d in report["draws"] if d["over_perfect"] is not None]
    if ratios:
        print(f"{len(ratios)} draws at +-{100 * a.error:g} %: {min(ratios):.3f} to {max(ratios):.3f} x perfect")
    path = os.path.join(a.run, "law_scatter.json")
    with open(path + ".tmp", "w") as f:
        json.dump(report, f, indent=1)
    os.replace(path + ".tmp", path)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
