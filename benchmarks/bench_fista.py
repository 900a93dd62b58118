"""FISTA against cvxpy (CLARABEL) on the partial Lasso, both timed in one run.

The instance of the benchmark: n = 20 states, p = 30 sensors, M = C with
standard Gaussian entries, an attack on s = 6 sensors with magnitudes in
[4, 5], x with entries of magnitude in [2, 3] and random signs.  For each
instance and lambda:

* cvxpy: ``partial_lasso_cvxpy`` (problem construction, canonicalisation
  and CLARABEL; CLARABEL's own solve time is shown beside it);
* FISTA: ``fista`` run for K iterations, K the fewest after which x and a
  are both within 1e-6 (relative) of the cvxpy solution.  K is found
  beforehand from an instrumented copy of the iteration (not timed) and
  checked on the timed result.  Three variants: plain FISTA (Beck-Teboulle,
  the default), with adaptive restart, and with adaptive restart in
  orthonormal coordinates (``orthonormalize=True``: M = U S V^T, iterate
  on (U I) with step 1/2; the SVD is inside the timed call).  Last, plain
  FISTA stopped by its own rule (default tol = 1e-10), with the accuracy it
  reached (worst instance).

"x err" is ||x_lasso - x|| / ||x|| of the cvxpy solution against the true
state (median).  With M = C the plant is not 2s-sparse observable (p - 2s =
18 < n = 20), so no decoder can be expected to find x there.

Times are the best of ``--repeat`` repetitions, with one BLAS thread (unless
OPENBLAS_NUM_THREADS is set); the table shows medians over ``--instances``
random instances.  A last block repeats the comparison on
the stacked model of the Lasso paper's Sec. 5.1 (M = O_tau, tau = n, a
random stable plant of the same size; m = 600 rows).

    python benchmarks/bench_fista.py [--instances 5] [--repeat 5] [--lams 0.01,0.1,1]
"""

from __future__ import annotations

import os

# one BLAS thread unless asked otherwise: these products are too small for
# threads to help, and on a busy machine thread hand-offs dominate the times
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import math
from typing import Any

import numpy as np
from _common import best_of, row

from ssecert import System
from ssecert.estimators.decoders import fista, partial_lasso_cvxpy
from ssecert.estimators.shrinkage import soft_threshold

TARGET = 1e-6
VARIANTS = {
    "plain": {"restart": False, "orthonormalize": False},
    "restart": {"restart": True, "orthonormalize": False},
    "orthonormal+restart": {"restart": True, "orthonormalize": True},
}
TABLE_VARIANTS = ("orthonormal+restart", "plain")  # the two of benchmarks/README.md


def instance(seed: int, *, stacked: bool, n: int = 20, p: int = 30, s: int = 6):
    """(M, y, x, attacked sensors) as in the Lasso paper's experiments."""
    rng = np.random.default_rng(seed)
    C = rng.standard_normal((p, n))
    tau = n if stacked else 1
    if stacked:
        A = rng.standard_normal((n, n))
        A /= 1.01 * np.abs(np.linalg.eigvals(A)).max()
        M = System(A, C).observability_matrix(tau)
    else:
        M = C
    x = rng.uniform(2.0, 3.0, n) * rng.choice([-1.0, 1.0], n)
    attacked = np.sort(rng.choice(p, s, replace=False))
    a = np.zeros((tau, p))
    a[:, attacked] = rng.uniform(4.0, 5.0, (tau, s)) * rng.choice([-1.0, 1.0], (tau, s))
    return M, M @ x + a.ravel(), x, attacked


def error(x, a, x_ref, a_ref) -> float:
    return max(
        np.linalg.norm(x - x_ref) / np.linalg.norm(x_ref),
        np.linalg.norm(a - a_ref) / np.linalg.norm(a_ref),
    )


def iterations_to_reach(
    M, y, lam, x_ref, a_ref, *, restart: bool, orthonormalize: bool, limit: int
) -> int | None:
    """Fewest FISTA iterations within TARGET of the reference (instrumented copy, not timed)."""
    to_x = lambda u: u  # noqa: E731
    if orthonormalize:
        U, sv, Vt = np.linalg.svd(M, full_matrices=False)
        M, to_x = U, lambda u: Vt.T @ (u / sv)
    n = M.shape[1]
    nu = 1.0 / (np.linalg.norm(M, 2) ** 2 + 1.0)
    z = w = np.zeros(n + M.shape[0])
    t = 1.0
    for k in range(1, limit + 1):
        r = M @ w[:n] + w[n:] - y
        z_new = np.r_[w[:n] - nu * (M.T @ r), soft_threshold(w[n:] - nu * r, nu * lam)]
        if restart and (w - z_new) @ (z_new - z) > 0:
            t = 1.0
        t_next = 0.5 * (1.0 + math.sqrt(1.0 + 4.0 * t * t))
        z, w, t = z_new, z_new + (t - 1.0) / t_next * (z_new - z), t_next
        if error(to_x(z[:n]), z[n:], x_ref, a_ref) <= TARGET:
            return k
    return None


def measure_instance(
    M, y, x_true, lam, repeat, limit, *, variants=tuple(VARIANTS), own_rule=True
) -> dict:
    """Times and accuracies of cvxpy and the FISTA variants on one instance and lambda."""
    found = {}
    found["cvxpy"], (x_ref, a_ref) = best_of(lambda: partial_lasso_cvxpy(M, y, lam), repeat)
    found["state error"] = np.linalg.norm(x_ref - x_true) / np.linalg.norm(x_true)
    found["clarabel"] = clarabel_solve_time(M, y, lam)
    for label in variants:
        options = VARIANTS[label]
        K = iterations_to_reach(M, y, lam, x_ref, a_ref, limit=limit, **options)
        if K is None:
            found[label] = (None, math.nan, math.nan)
            continue
        seconds, sol = best_of(
            lambda K=K, options=options: fista(M, y, lam, iterations=K, tol=0.0, **options), repeat
        )
        reached = error(sol.x, sol.a, x_ref, a_ref)
        assert reached <= TARGET, (label, K, reached)
        found[label] = (K, seconds, reached)
    if own_rule:
        seconds, sol = best_of(lambda: fista(M, y, lam, iterations=limit), repeat)
        found["own-rule"] = (sol.iterations, seconds, error(sol.x, sol.a, x_ref, a_ref))
    return found


def clarabel_solve_time(M, y, lam) -> float:
    """CLARABEL's own solve time for the same problem (no cvxpy overhead)."""
    import cvxpy as cp

    x, a = cp.Variable(M.shape[1]), cp.Variable(M.shape[0])
    problem = cp.Problem(cp.Minimize(0.5 * cp.sum_squares(y - M @ x - a) + lam * cp.norm1(a)))
    problem.solve(solver=cp.CLARABEL, tol_gap_abs=1e-9, tol_gap_rel=1e-9, tol_feas=1e-9)
    return float(problem.solver_stats.solve_time)


def median(values):
    values = [v for v in values if v is not None and not math.isnan(v)]
    return float(np.median(values)) if values else math.nan


def report(title: str, rows_by_lam: dict[float, list[dict]]) -> None:
    print(title)
    head = f"{'lambda':>7} {'cvxpy ms':>9} {'(CLARABEL)':>10}"
    for label in VARIANTS:
        head += f" | {label[:19]:>19} {'ms':>7} {'cvxpy/F':>7}"
    head += f" | {'own rule it':>11} {'ms':>7} {'err':>7} | {'x err':>7}"
    print(head)
    print("-" * len(head))
    for lam, found in rows_by_lam.items():
        line = (
            f"{lam:7.0e} {median([r['cvxpy'] for r in found]) * 1e3:9.2f} "
            f"{median([r['clarabel'] for r in found]) * 1e3:10.2f}"
        )
        for label in VARIANTS:
            Ks = [r[label][0] for r in found]
            missing = sum(K is None for K in Ks)
            K = f"K={median(Ks):.0f}" + (f" ({missing} never)" if missing else "")
            ms = median([r[label][1] for r in found]) * 1e3
            ratio = median([r["cvxpy"] / r[label][1] for r in found if r[label][0] is not None])
            line += f" | {K:>19} {ms:7.2f} {ratio:7.2f}"
        own = [r["own-rule"] for r in found]
        line += (
            f" | {median([o[0] for o in own]):11.0f} "
            f"{median([o[1] for o in own]) * 1e3:7.2f} {max(o[2] for o in own):7.1e}"
        )
        line += f" | {median([r['state error'] for r in found]):7.1e}"
        print(line)
    print()


def measure(
    *,
    instances: int = 5,
    repeat: int = 5,
    lams: tuple[float, ...] = (0.01, 0.1, 1.0),
    limit: int = 100_000,
    stacked: bool = True,
    variants: tuple[str, ...] = tuple(VARIANTS),
    own_rule: bool = True,
) -> dict[str, tuple[tuple[int, int], dict[float, list[dict]]]]:
    """{block: (shape of M, {lambda: one measured row per instance})}.

    ``variants`` and ``own_rule`` say which FISTA runs are timed (the table
    needs only two variants, the printed text all of them).
    """
    M, y, _, _ = instance(0, stacked=False)
    partial_lasso_cvxpy(M, y, lams[0])  # warm-up: imports and first-call costs
    fista(M, y, lams[0], iterations=10)
    blocks = [("static", False)] + ([("stacked", True)] if stacked else [])
    out = {}
    for name, is_stacked in blocks:
        rows_by_lam: dict[float, list[dict]] = {}
        for lam in lams:
            rows_by_lam[lam] = []
            for seed in range(instances):
                M, y, x_true, _ = instance(seed, stacked=is_stacked)
                rows_by_lam[lam].append(
                    measure_instance(
                        M, y, x_true, lam, repeat, limit, variants=variants, own_rule=own_rule
                    )
                )
        out[name] = (M.shape, rows_by_lam)
    return out


def print_results(results, instances: int) -> None:
    for name, (shape, rows_by_lam) in results.items():
        stacked = name == "stacked"
        report(
            f"{name}: M is {shape[0]} x 20 ({'O_tau, tau = 20' if stacked else 'M = C'}), "
            f"s = 6 attacked sensors, {instances} instances, medians; "
            f"K = iterations to reach {TARGET:g} of cvxpy; cvxpy/F > 1 means FISTA is faster",
            rows_by_lam,
        )


def to_rows(results, instances: int) -> list[dict[str, Any]]:
    """Medians over the instances; the ratio is median cvxpy over median FISTA."""
    out = []
    for name, (shape, rows_by_lam) in results.items():
        model = "O_tau, tau = 20" if name == "stacked" else "M = C"
        for lam, measured in rows_by_lam.items():
            cvxpy_seconds = median([r["cvxpy"] for r in measured])
            for label, fista_name in zip(
                TABLE_VARIANTS, ("orthonormal coordinates + restart", "plain (the default)")
            ):
                Ks = [r[label][0] for r in measured]
                missing = sum(K is None for K in Ks)
                reached = [r[label][2] for r in measured if r[label][0] is not None]
                note = (
                    f"median of {instances} instances; K = {median(Ks):.0f} iterations to "
                    f"{TARGET:g} of cvxpy (worst {max(reached, default=math.nan):.1e})"
                )
                if missing:
                    note += f"; {missing} never reached it in the iteration cap"
                out.append(
                    row(
                        "FISTA vs cvxpy",
                        f"{name} {model} ({shape[0]} x {shape[1]}), lambda {lam:g}: {fista_name}",
                        median([r[label][1] for r in measured]),
                        cvxpy_seconds,
                        "cvxpy + Clarabel",
                        note,
                    )
                )
    return out


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The figures as table rows (5 instances, best of 3; quick: 2 instances, best of 2).

    Only the two variants of the table are timed, and not the stop by FISTA's own rule.
    """
    instances, repeat = (2, 2) if quick else (5, 3)
    results = measure(instances=instances, repeat=repeat, variants=TABLE_VARIANTS, own_rule=False)
    return to_rows(results, instances)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--instances", type=int, default=5, help="random instances (seeds)")
    parser.add_argument("--repeat", type=int, default=5, help="timing repetitions (best of)")
    parser.add_argument("--lams", default="0.01,0.1,1", help="comma-separated lambdas")
    parser.add_argument("--limit", type=int, default=100_000, help="FISTA iteration cap")
    parser.add_argument("--no-stacked", action="store_true", help="skip the O_tau block")
    args = parser.parse_args()
    results = measure(
        instances=args.instances,
        repeat=args.repeat,
        lams=tuple(float(v) for v in args.lams.split(",")),
        limit=args.limit,
        stacked=not args.no_stacked,
    )
    print_results(results, args.instances)


if __name__ == "__main__":
    main()
