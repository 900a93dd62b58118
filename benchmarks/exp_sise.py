"""The simulations of Sec. IV of the SISE paper (Fosson et al., ECC 2019), with ssecert's SISE.

Set-up, as in the paper: A with independent N(0, 1/n) entries (the paper
writes N(0, 1/sqrt(n)); read as a standard deviation, so that the spectral
radius is about 1), B = [I_p; 0], C with N(0, 1) entries, x(0) ~ N(0, I),
Q = R = 0.01 I, input sparsity s = 1 known to the estimator (the support is
the largest entry of the Lasso solution), lambda = 1, support constant in
time (not used by SISE).  The nonzero input entry has random sign at each
step and magnitude fixed by an input-to-noise ratio of 20 dB, read as
|u|^2 = 100 E||w||^2 = 100 trace(Q) (|u| = sqrt(n)).

Experiments: 1 (p = 40, m = 20, n = 50), 2 (m = 30), 3 (n = 70), and
experiment 1 with |u| = 1 (the other reading of the input-to-noise ratio);
``--no-extras`` runs only 1 and 3.  The benchmark is the paper's oracle: the same
filter (Gillijns-De Moor) told the true support.  Printed: mean relative
errors ||x(k) - x_hat(k)|| / ||x(k)|| and ||u(k) - u_hat(k)|| / ||u(k)||
over runs and over k >= --transient, their medians over runs, and the
fraction of runs and steps whose support SISE got right; then the errors at
a few k (the paper's figures plot them against k), and a paragraph comparing
with the paper.

Runs share plants: ``--plants`` random plants, each simulated for
runs / plants runs in one batch (the paper does not say whether it redraws
the plant in every run).

    python benchmarks/exp_sise.py [--runs 100] [--plants 10] [--steps 100] [--transient 20]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import textwrap
import time

import numpy as np

from ssecert.estimators.sise import SISE, OracleSISE


def simulate_plant(rng, n, m, p, runs, steps, amplitude):
    """One random plant of Sec. IV and `runs` trajectories of it."""
    A = rng.standard_normal((n, n)) / np.sqrt(n)
    B = np.eye(n)[:, :p]
    C = rng.standard_normal((m, n))
    x = rng.standard_normal((runs, n))
    u = np.zeros((steps, runs, p))
    where = rng.integers(p, size=runs)
    u[:, np.arange(runs), where] = amplitude * rng.choice([-1.0, 1.0], (steps, runs))
    xs, ys = [x], []
    for k in range(steps):
        ys.append(x @ C.T + 0.1 * rng.standard_normal((runs, m)))
        x = x @ A.T + u[k] @ B.T + 0.1 * rng.standard_normal((runs, n))
        xs.append(x)
    return A, B, C, np.array(xs), np.array(ys), u


def experiment(n, m, p, *, runs, plants, steps, seed, amplitude, lasso_rtol):
    """Relative errors per (k, run) of SISE and the oracle; SISE's support hits."""
    rng = np.random.default_rng(seed)
    per = [runs // plants + (i < runs % plants) for i in range(plants)]
    out = {"sise": ([], []), "oracle": ([], [])}
    hits = []  # one (steps - 1, runs of the plant) array per plant
    Q, R = 0.01 * np.eye(n), 0.01 * np.eye(m)
    t0 = time.perf_counter()
    for count in per:
        if count == 0:
            continue
        A, B, C, xs, ys, u = simulate_plant(rng, n, m, p, count, steps, amplitude)
        estimators = {
            "sise": SISE(A, B, C, Q=Q, R=R, lasso_weight=1.0, sparsity=1, lasso_rtol=lasso_rtol),
            "oracle": OracleSISE(A, B, C, Q=Q, R=R, support=u != 0),
        }
        for name, est in estimators.items():
            state = est.initial_state(count)
            x_err, u_err, hit = [], [], []
            for k in range(steps):
                state = est.step(state, ys[k])
                x_err.append(
                    np.linalg.norm(state["x_hat"] - xs[k], axis=1) / np.linalg.norm(xs[k], axis=1)
                )
                if k >= 1:  # u_hat from y(k) estimates u(k - 1)
                    u_err.append(
                        np.linalg.norm(state["u_hat"] - u[k - 1], axis=1)
                        / np.linalg.norm(u[k - 1], axis=1)
                    )
                    hit.append(np.all(state["support"] == (u[k - 1] != 0), axis=1))
            out[name][0].append(np.array(x_err))
            out[name][1].append(np.array(u_err))
            if name == "sise":
                hits.append(np.array(hit))
    seconds = time.perf_counter() - t0
    errors = {
        name: (np.concatenate(xe, axis=1), np.concatenate(ue, axis=1))
        for name, (xe, ue) in out.items()
    }
    return errors, np.concatenate(hits, axis=1), seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100, help="runs per experiment (100)")
    parser.add_argument("--plants", type=int, default=10, help="random plants (10)")
    parser.add_argument("--steps", type=int, default=100, help="measurements per run (100)")
    parser.add_argument(
        "--transient", type=int, default=20, help="errors averaged over k >= this (20)"
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--no-extras",
        action="store_true",
        help="skip experiment 2 (m = 30) and experiment 1 with |u| = 1",
    )
    parser.add_argument(
        "--lasso-rtol",
        type=float,
        default=1e-8,
        help="FISTA stopping tolerance of the support detection (1e-8)",
    )
    args = parser.parse_args()
    if not 1 <= args.plants <= args.runs:
        parser.error("--plants must be between 1 and --runs")
    if not 1 <= args.transient < args.steps - 1:
        parser.error("--transient must be >= 1 and below --steps - 1")

    p = 40
    cases = [("1", 50, 20, np.sqrt(100 * 0.01 * 50)), ("3", 70, 20, np.sqrt(100 * 0.01 * 70))]
    if not args.no_extras:
        cases.insert(1, ("2", 50, 30, np.sqrt(100 * 0.01 * 50)))
        cases.append(("1, |u| = 1", 50, 20, 1.0))

    T = args.transient
    rows, series = [], []
    for label, n, m, amplitude in cases:
        errors, hit, seconds = experiment(
            n,
            m,
            p,
            runs=args.runs,
            plants=args.plants,
            steps=args.steps,
            seed=args.seed,
            amplitude=amplitude,
            lasso_rtol=args.lasso_rtol,
        )
        (sx, su), (ox, ou) = errors["sise"], errors["oracle"]
        # x errors are indexed by k, u errors by k - 1 (u_hat(k - 1) comes with y(k))
        row = dict(
            label=label,
            n=n,
            m=m,
            amp=amplitude,
            sx=sx[T:].mean(),
            ox=ox[T:].mean(),
            su=su[T - 1 :].mean(),
            ou=ou[T - 1 :].mean(),
            sx_med=np.median(sx[T:].mean(axis=0)),
            su_med=np.median(su[T - 1 :].mean(axis=0)),
            ou_med=np.median(ou[T - 1 :].mean(axis=0)),
            hit=hit[T - 1 :].mean(),
            runs_ok=np.mean(hit[T - 1 :].mean(axis=0) > 0.95),
            seconds=seconds,
        )
        rows.append(row)
        series.append(
            (
                label,
                sx.mean(axis=1),
                ox.mean(axis=1),
                su.mean(axis=1),
                ou.mean(axis=1),
                hit.mean(axis=1),
            )
        )

    print(
        f"SISE vs oracle, p = {p}, s = 1, Q = R = 0.01 I, lambda = 1, {args.runs} runs on "
        f"{args.plants} plants, {args.steps} steps, means over k >= {T}"
    )
    head = (
        f"{'exp':<11} {'n':>3} {'m':>3} {'|u|':>5}  {'x SISE':>8} {'x oracle':>8}  "
        f"{'u SISE':>8} {'u oracle':>8}  {'med x':>7} {'med u':>7} {'med u or':>8}  "
        f"{'supp ok':>7} {'runs ok':>7} {'time':>6}"
    )
    print(head)
    print("-" * len(head))
    for r in rows:
        print(
            f"{r['label']:<11} {r['n']:>3} {r['m']:>3} {r['amp']:>5.2f}  {r['sx']:>8.2e} "
            f"{r['ox']:>8.2e}  {r['su']:>8.2e} {r['ou']:>8.2e}  {r['sx_med']:>7.1e} "
            f"{r['su_med']:>7.1e} {r['ou_med']:>8.1e}  {r['hit']:>7.1%} {r['runs_ok']:>7.0%} "
            f"{r['seconds']:>5.1f}s"
        )
    print(
        "(x, u: mean relative errors; med: median over runs of the per-run mean; supp ok: "
        "fraction of (run, k) with SISE's support right; runs ok: runs with it right in > 95% "
        "of the steps)"
    )
    print()
    ks = [k for k in (1, 2, 5, 10, 20, 50, 99, 199) if k < args.steps]
    print("mean relative errors against k (x(k); u(k - 1) estimated from y(k))")
    print(f"{'exp':<11} {'':<9}" + "".join(f"{'k=' + str(k):>9}" for k in ks))
    for label, sx, ox, su, ou, hit in series:
        print(f"{label:<11} {'x SISE':<9}" + "".join(f"{sx[k]:>9.1e}" for k in ks))
        print(f"{'':<11} {'x oracle':<9}" + "".join(f"{ox[k]:>9.1e}" for k in ks))
        print(f"{'':<11} {'u SISE':<9}" + "".join(f"{su[k - 1]:>9.1e}" for k in ks))
        print(f"{'':<11} {'u oracle':<9}" + "".join(f"{ou[k - 1]:>9.1e}" for k in ks))
        print(f"{'':<11} {'supp ok':<9}" + "".join(f"{hit[k - 1]:>9.0%}" for k in ks))
    print()
    print(paragraph(rows, T))


def paragraph(rows, transient) -> str:
    r1 = next(r for r in rows if r["label"] == "1")
    r3 = next(r for r in rows if r["label"] == "3")
    r2 = next((r for r in rows if r["label"] == "2"), None)
    alt = next((r for r in rows if r["label"].startswith("1, ")), None)
    order = lambda v: int(np.floor(np.log10(v)))  # noqa: E731
    close = r1["su"] < 1.5 * r1["ou"] and r1["sx"] < 1.5 * r1["ox"]
    text = [
        "What the paper shows: Fig. 1 (p = 40, m = 20, n = 50) plots the mean relative state and "
        "input errors of SISE and of the oracle over 100 runs against k; the text says that after "
        "some iterations the support is right in almost all runs and the mean relative errors "
        "are of order 1e-2, very close to the oracle. Fig. 2 (m = 30) has a perfect support, and "
        "Fig. 3 (n = 70) a lower accuracy than Fig. 1. The figures themselves are not in our "
        "copy, so only these statements can be compared. ",
        f"Ours, experiment 1: over k >= {transient}, SISE's mean relative input "
        f"error is {r1['su']:.1e} (oracle {r1['ou']:.1e}) and state error {r1['sx']:.1e} "
        f"(oracle {r1['ox']:.1e}); the support is right in {r1['hit']:.0%} of the (run, k) pairs "
        f"and in more than 95% of the steps for {r1['runs_ok']:.0%} of the runs. ",
        (
            f"This agrees with the paper: errors of order 1e-{-order(r1['su'])} for the input, "
            "SISE close to the oracle, the support right almost always. "
        )
        if close and order(r1["su"]) == -2
        else (
            "This does not match the paper's order 1e-2 / 'very close to the oracle': input "
            f"error of order 1e{order(r1['su'])}. "
        ),
        (
            f"The means are pulled up by the few runs whose support SISE keeps missing (median "
            f"per-run input error {r1['su_med']:.1e} against the oracle's {r1['ou_med']:.1e}); the "
            "paper's 'almost all runs' says the same. "
            if r1["su"] > 1.2 * r1["su_med"]
            else ""
        ),
        "The state error is relative to a state that "
        "grows (A has spectral radius about 1 and is driven by the input), so it keeps "
        "decreasing with k and its value depends on the horizon. ",
        f"Experiment 3 (n = 70): input error {r3['su']:.1e} (oracle {r3['ou']:.1e}), state "
        f"error {r3['sx']:.1e} (oracle {r3['ox']:.1e}), support right {r3['hit']:.0%}: "
        + (
            "less accurate than experiment 1, as in Fig. 3. "
            if r3["su"] > r1["su"] or r3["sx"] > r1["sx"]
            else "not less accurate than experiment 1, unlike Fig. 3's caption. "
        ),
    ]
    if r2 is not None:
        text.append(
            f"Experiment 2 (m = 30): support right {r2['hit']:.1%} of the time"
            + (
                ", perfect as in Fig. 2. "
                if r2["hit"] > 0.999
                else ", not quite the paper's 100%. "
            )
        )
    if alt is not None:
        text.append(
            f"Reading the 20 dB input-to-noise ratio per entry instead (|u| = 1) gives input "
            f"errors {alt['su']:.1e} (oracle {alt['ou']:.1e}) and support right "
            f"{alt['hit']:.0%}: an order of magnitude above the paper's statement, which is why "
            "we read the ratio against E||w||^2 = trace(Q). "
        )
    text.append(
        "Choices the paper leaves open: N(0, 1/sqrt(n)) read as a standard deviation (read as a "
        "variance, A has spectral radius about n^(1/4) > 2, the state diverges and the relative "
        "input error loses all digits to cancellation); the input's sign redrawn each step; the "
        "horizon and the transient (our --steps and --transient); y(0) used for a measurement "
        "update of the prior x_hat(0) = 0, P(0) = I."
    )
    return textwrap.fill("".join(text), width=100)


if __name__ == "__main__":
    main()
