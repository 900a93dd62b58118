"""Batched observer simulation against a Python loop over runs, in one run.

The sparse soft observer (SSO, window 1) of the Lasso paper on its Sec. 5.2
set-up: n = 10, p = 15, s = 3, 100 runs x 300 steps.  The reference runs
each Monte Carlo run on its own, step by step, with numpy vectors (the
natural transcription of the algorithm); ssecert runs all runs at once.
Both produce the same estimates (checked).  The Lasso paper reports
4e-6 s per step for its MATLAB SSO.

    python benchmarks/bench_observers.py
"""

from __future__ import annotations

import time

import numpy as np

from ssecert.estimators.shrinkage import soft_threshold
from ssecert.observers import SparseSoftObserver


def reference(A, C, L, step, threshold, y):
    """Loop over runs, then over steps, one vector at a time."""
    steps, runs, p = y.shape
    n = A.shape[0]
    out = np.empty((steps + 1, runs, n))
    for r in range(runs):
        x = np.zeros(n)
        a = np.zeros(p)
        out[0, r] = x
        for k in range(steps):
            resid = y[k, r] - (C @ x + a)
            x = A @ x + L @ resid
            a = soft_threshold(a + step * resid, threshold)
            out[k + 1, r] = x
    return out


def main() -> None:
    rng = np.random.default_rng(0)
    n, p, s, runs, steps = 10, 15, 3, 100, 300
    A = rng.standard_normal((n, n))
    A /= np.abs(np.linalg.eigvals(A)).max() * 1.01  # stable, as in the paper
    C = rng.standard_normal((p, n))
    step = 0.99 / np.linalg.norm(np.hstack([C, np.eye(p)]), 2) ** 2
    threshold = 0.05 * step
    L = step * A @ C.T
    x = rng.uniform(2, 3, (runs, n)) * rng.choice([-1, 1], (runs, n))
    attack = np.zeros((runs, p))
    for r in range(runs):
        idx = rng.choice(p, s, replace=False)
        attack[r, idx] = rng.uniform(4, 5, s) * rng.choice([-1, 1], s)
    y = np.empty((steps, runs, p))
    for k in range(steps):
        y[k] = x @ C.T + attack
        x = x @ A.T
    observer = SparseSoftObserver(A, C, L, step=step, threshold=threshold)
    best_batched, best_ref = np.inf, np.inf
    for _ in range(5):
        t0 = time.perf_counter()
        traj = observer.run(y)
        best_batched = min(best_batched, time.perf_counter() - t0)
    for _ in range(2):
        t0 = time.perf_counter()
        ref = reference(A, C, L, step, threshold, y)
        best_ref = min(best_ref, time.perf_counter() - t0)
    same = np.allclose(traj.x_hat, ref, rtol=1e-10, atol=1e-10)
    per_b = best_batched / (runs * steps) * 1e6
    per_r = best_ref / (runs * steps) * 1e6
    print(f"SSO, n = {n}, p = {p}, {runs} runs x {steps} steps (same estimates: {same})")
    print(f"{'method':<40} {'us per run-step':>16}")
    print(f"{'reference: Python loop over runs':<40} {per_r:16.3f}")
    print(f"{'ssecert: batched over runs':<40} {per_b:16.3f}")
    print(
        f"speed-up: {per_r / per_b:.1f}x (target >= 20x); batched cost {per_b:.3f} us per "
        f"run-step (target < 1 us; the Lasso paper reports 4 us per step in MATLAB)"
    )


if __name__ == "__main__":
    main()
