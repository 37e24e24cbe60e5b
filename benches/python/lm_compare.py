"""The gravity-net benchmark's peers, on the data, split and initial weights neurarm's bench
wrote: a numpy implementation of the same trainlm loop, and scipy's MINPACK
(`least_squares(method="lm")`) with an analytic Jacobian. Prints the three side by side.

usage: lm_compare.py target/lm-bench/gravity.json"""
import json
import sys
import time

import numpy as np
from scipy.optimize import least_squares

data = json.loads(open(sys.argv[1]).read())
X = np.hstack([np.array(data["x_train"]), np.ones((len(data["x_train"]), 1))])
T = np.array(data["t_train"])
Xt = np.hstack([np.array(data["x_test"]), np.ones((len(data["x_test"]), 1))])
Tt = np.array(data["t_test"])
theta0 = np.array(data["theta0"])
scale = np.array(data["error_scale"])
s = data["settings"]
q, n1 = X.shape
k = T.shape[1]
h = data["hidden"]
ph = h * n1
P = ph + k * (h + 1)


def unpack(theta):
    return theta[:ph].reshape(h, n1), theta[ph:].reshape(k, h + 1)


def forward(theta, x):
    w1, w2 = unpack(theta)
    a = np.tanh(x @ w1.T)
    at = np.hstack([a, np.ones((len(x), 1))])
    return a, at, at @ w2.T


def test_mse(theta):
    """MSE on the test part in the targets' units (N²m²)."""
    _, _, y = forward(theta, Xt)
    return float(((y - Tt) ** 2 * scale).mean())


def jacobian(theta, a, at):
    """∂y/∂θ, rows (sample, output), built with numpy broadcasting (the naive product)."""
    _, w2 = unpack(theta)
    d = 1.0 - a ** 2
    jac = np.zeros((q, k, P))
    for o in range(k):
        jac[:, o, :ph] = ((w2[o, :h] * d)[:, :, None] * X[:, None, :]).reshape(q, ph)
        jac[:, o, ph + o * (h + 1): ph + (o + 1) * (h + 1)] = at
    return jac.reshape(q * k, P)


def numpy_trainlm(max_epochs):
    theta = theta0.copy()
    mu = s["mu"]
    a, at, y = forward(theta, X)
    mse = ((T - y) ** 2).mean()
    history, excluded, t0 = [], 0.0, time.perf_counter()
    epochs = 0
    for epoch in range(1, max_epochs + 1):
        e = (T - y).ravel()
        jac = jacobian(theta, a, at)
        jtj = jac.T @ jac
        g = jac.T @ e
        if 2 * np.linalg.norm(g) / (q * k) < s["min_grad"]:
            break
        improved = False
        while mu <= s["mu_max"]:
            delta = np.linalg.solve(jtj + mu * np.eye(P), g)
            trial = theta + delta
            a2, at2, y2 = forward(trial, X)
            mse2 = ((T - y2) ** 2).mean()
            if mse2 < mse:
                theta, a, at, y, mse = trial, a2, at2, y2, mse2
                mu *= s["mu_dec"]
                improved = True
                break
            mu *= s["mu_inc"]
        epochs = epoch
        t_eval = time.perf_counter()
        history.append((t_eval - t0 - excluded, test_mse(theta)))
        excluded += time.perf_counter() - t_eval
        if not improved:
            break
    total = time.perf_counter() - t0 - excluded
    return epochs, total, history


class Reached(Exception):
    pass


def scipy_lm(max_nfev, target=1e-5):
    """MINPACK until the test MSE reaches `target` (then stopped: its time is what is
    compared) or `max_nfev` evaluations."""
    history, excluded, counts = [], [0.0], {"jac": 0, "theta": theta0}
    t0 = time.perf_counter()

    def fun(theta):
        _, _, y = forward(theta, X)
        t_eval = time.perf_counter()
        m = test_mse(theta)
        history.append((t_eval - t0 - excluded[0], m))
        excluded[0] += time.perf_counter() - t_eval
        if m <= target:
            counts["theta"] = theta.copy()
            raise Reached
        return (y - T).ravel()

    def jac(theta):
        counts["jac"] += 1
        a, at, _ = forward(theta, X)
        return jacobian(theta, a, at)

    try:
        result = least_squares(fun, theta0, jac=jac, method="lm", max_nfev=max_nfev)
        counts["theta"] = result.x
    except Reached:
        pass
    total = time.perf_counter() - t0 - excluded[0]
    return counts, total, history


def first_below(history, target=1e-5):
    return next((t for t, m in history if m <= target), None)


ours = data["neurarm"]
epochs, np_total, np_hist = numpy_trainlm(s["epochs"])
res, sp_total, sp_hist = scipy_lm(max_nfev=s["epochs"])
rows = [
    ("neurarm (Rust)", ours["seconds_per_epoch"], ours["epochs"], ours["seconds_to_test_mse_1e-5"], ours["final_test_mse"], ours["seconds"]),
    ("numpy trainlm loop", np_total / max(epochs, 1), epochs, first_below(np_hist), np_hist[-1][1], np_total),
    ("scipy MINPACK lm", sp_total / max(res["jac"], 1), res["jac"], first_below(sp_hist), test_mse(res["theta"]), sp_total),
]
fmt = lambda v, f: "never" if v is None else f.format(v)
print("\n4-25-4 gravity net, 2401 pairs of a 7^4 grid (1681 train / 360 test), same start:")
print(f"{'trainer':<20}{'s/epoch':>11}{'epochs':>8}{'s to test MSE 1e-5':>20}{'final test MSE':>16}{'total s':>9}")
for name, per, ep, to, final, total in rows:
    print(f"{name:<20}{per:>11.5f}{ep:>8}{fmt(to, '{:.3f}'):>20}{final:>16.3e}{total:>9.2f}")
print(f"epoch speed-up vs numpy: {rows[1][1] / rows[0][1]:.1f}x (target >= 5x)")
if rows[0][3] is not None and rows[2][3] is not None:
    print(f"time to test MSE 1e-5 vs scipy: {rows[2][3] / rows[0][3]:.1f}x (target >= 50x)")
else:
    print("time to test MSE 1e-5 vs scipy: not comparable (a trainer never reached 1e-5 N²m²)")
print("(scipy's 'epochs' are Jacobian evaluations, and it stops at the target; MSE in N²m²)")
