"""Batched observer simulation against a Python loop over runs, in one run.

The sparse soft observer (SSO, window 1) of the Lasso paper on its Sec. 5.2
set-up: n = 10, p = 15, s = 3, 100 runs x 300 steps.  The reference runs
each Monte Carlo run on its own, step by step, with numpy vectors (the
natural transcription of the algorithm); ssecert runs all runs at once.
Both produce the same estimates (checked).  The Lasso paper reports
4e-6 s per step for its MATLAB SSO.

    python benchmarks/bench_observers.py [--repeat N]
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from typing import Any

import numpy as np
from _common import best_of, row, yes_no

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


@dataclass(frozen=True)
class Results:
    n: int
    p: int
    runs: int
    steps: int
    batched: float
    loop: float
    same: bool


def measure(*, repeat: int = 5) -> Results:
    """Best of ``repeat`` batched runs and of (fewer, slower) reference runs."""
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
    batched, traj = best_of(lambda: observer.run(y), repeat)
    loop, ref = best_of(lambda: reference(A, C, L, step, threshold, y), max(1, (repeat + 1) // 3))
    same = bool(np.allclose(traj.x_hat, ref, rtol=1e-10, atol=1e-10))
    return Results(n, p, runs, steps, batched, loop, same)


def print_results(r: Results) -> None:
    per_b = r.batched / (r.runs * r.steps) * 1e6
    per_r = r.loop / (r.runs * r.steps) * 1e6
    print(f"SSO, n = {r.n}, p = {r.p}, {r.runs} runs x {r.steps} steps (same estimates: {r.same})")
    print(f"{'method':<40} {'us per run-step':>16}")
    print(f"{'reference: Python loop over runs':<40} {per_r:16.3f}")
    print(f"{'ssecert: batched over runs':<40} {per_b:16.3f}")
    print(
        f"speed-up: {per_r / per_b:.1f}x (target >= 20x); batched cost {per_b:.3f} us per "
        f"run-step (target < 1 us; the Lasso paper reports 4 us per step in MATLAB)"
    )


def to_rows(r: Results) -> list[dict[str, Any]]:
    per_b = r.batched / (r.runs * r.steps) * 1e6
    note = f"same estimates: {yes_no(r.same)}; {per_b:.2g} us per run-step"
    case = f"SSO, n = {r.n}, p = {r.p}, {r.runs} runs x {r.steps} steps"
    return [
        row("batched simulation vs loop", case, r.batched, r.loop, "Python loop over runs", note)
    ]


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The figures as table rows (quick: fewer repetitions)."""
    return to_rows(measure(repeat=2 if quick else 5))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="timing repetitions (best of)")
    print_results(measure(repeat=parser.parse_args().repeat))


if __name__ == "__main__":
    main()
