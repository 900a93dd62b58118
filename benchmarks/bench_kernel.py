"""The enumeration's screening kernel against a 28-line numpy baseline and the flop limit.

Measured in one run, on one BLAS thread:

* ssecert's scan of one level of the enumeration (``_scan_level``: every
  set of k removed sensors screened for positive definiteness of its
  Gramian, the failures refined exactly), as the verdict's level (the sets
  closest to breaking ranked as well) and as a refinement level (decisions
  only);
* the baseline: 28 lines of numpy, the sets in colex order, the Gramians
  from partial sums, a float64 Cholesky written batch-innermost (arrays of
  shape (n, n, N), each operation over the whole batch), every set of the
  level screened (``baseline_failing``);
* the flop limit: the GFLOP/s of a 2000 x 2000 float64 matrix product on
  one thread.

A set is counted as n^3/3 + n^2 flops (a Cholesky factorization and the
partial sum of its Gramian): 433, 720 and 3,067 at n = 10, 12 and 20.  The
plants are those of bench_enumeration's eigenspace comparison (distinct
integer eigenvalues, each sensor seeing about half of the modes: no sensor
observes the whole state, nothing is pruned), p = 30.

    python benchmarks/bench_kernel.py [--quick] [--repeat N]
"""

from __future__ import annotations

import argparse
import math
import os
import time
from dataclasses import dataclass
from typing import Any

# one BLAS thread (before numpy is imported): the flop limit of one core
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import numpy as np
from _common import best_of, row
from bench_enumeration import modal_plant

from ssecert.numerics.linalg import balanced_units, sensor_subspaces
from ssecert.structure.enumeration import _scan_level
from ssecert.tolerances import Tolerances

NAME = "enumeration kernel vs baseline"
FULL = ((10, 6), (12, 6), (20, 5))  # (n, sensors removed): 593,775, 593,775, 142,506 sets
QUICK = ((10, 5), (12, 5), (20, 4))


def baseline_failing(proj: np.ndarray, k: int, shift: float) -> int:
    """Sets of k of the q projectors whose removal leaves ``sum - shift I`` without a Cholesky
    factor: the 28-line baseline (colex order, partial sums, Cholesky batch-innermost)."""
    q, n, _ = proj.shape
    items = np.ascontiguousarray(proj.transpose(1, 2, 0))  # (n, n, q): the batch last
    sums = (items.sum(axis=2) - shift * np.eye(n))[:, :, None]
    for j in range(1, k):  # partial sums of every j-subset, in colex order
        sums = np.concatenate(
            [sums[:, :, : math.comb(t, j - 1)] - items[:, :, t : t + 1] for t in range(j - 1, q)],
            axis=2,
        )
    failing = 0
    for t in range(k - 1, q):  # the largest item removed: the first C(t, k - 1) partial sums
        A = sums[:, :, : math.comb(t, k - 1)] - items[:, :, t : t + 1]
        ok = np.ones(A.shape[2], dtype=bool)
        for j in range(n):  # right-looking Cholesky, each operation over the whole batch
            ok &= A[j, j] > 0
            column = A[j + 1 :, j] / np.sqrt(np.where(ok, A[j, j], 1.0))
            A[j + 1 :, j + 1 :] -= column[:, None] * column[None, :]
        failing += int(A.shape[2] - ok.sum())
    return failing


def flop_limit(size: int = 2000, repeat: int = 3) -> float:
    """GFLOP/s of a float64 matrix product on one thread (the BLAS's best case)."""
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal((size, size)), rng.standard_normal((size, size))
    seconds, _ = best_of(lambda: a @ b, repeat)
    return 2.0 * size**3 / seconds / 1e9


def flops_per_set(n: int) -> float:
    """A Cholesky factorization and the partial sum of the Gramian."""
    return n**3 / 3 + n**2


@dataclass(frozen=True)
class Level:
    """One level timed three ways."""

    n: int
    k: int
    sets: int
    verdict_seconds: float
    refine_seconds: float
    baseline_seconds: float
    breaking: int
    borderline: int
    baseline_failing: int


def measure_level(n: int, k: int, repeat: int) -> Level:
    """ssecert's level scan (as the verdict's level and as a refinement level) and the
    baseline, on the modal plant with n states and 30 sensors."""
    tol = Tolerances()
    system = balanced_units(modal_plant(n=n, p=30)).system
    sub = sensor_subspaces(system.A, system.C, tolerances=tol)
    rest = np.flatnonzero(sub.ranks < n)
    full = np.flatnonzero(sub.ranks == n)
    P = sub.bases[rest]
    proj = np.einsum("qkn,qkm->qnm", P, P)
    base = proj.sum(axis=0)
    errors = sub.errors[rest]
    q = rest.size

    def scan(critical: bool) -> Any:
        return _scan_level(
            P, sub.ranks[rest], proj, base, k, rest, full, tol, critical=critical, errors=errors
        )

    verdict, level = best_of(lambda: scan(True), repeat)
    refine, _ = best_of(lambda: scan(False), repeat)
    # the enumeration's screening shift (``_scan_level``)
    shift = max(tol.screen_rtol * max(q, 1), 10.0 * float(np.sum(errors)) ** 2)
    baseline, failing = best_of(lambda: baseline_failing(proj, k, shift), repeat)
    return Level(
        n=n,
        k=k,
        sets=math.comb(q, k),
        verdict_seconds=verdict,
        refine_seconds=refine,
        baseline_seconds=baseline,
        breaking=len(level.failures),
        borderline=level.borderline,
        baseline_failing=failing,
    )


def measure(quick: bool, repeat: int) -> tuple[float, list[Level]]:
    limit = flop_limit(repeat=repeat)
    levels = [measure_level(n, k, repeat) for n, k in (QUICK if quick else FULL)]
    return limit, levels


def _rate(level: Level, seconds: float, limit: float) -> str:
    sets = level.sets / seconds
    gflops = sets * flops_per_set(level.n) / 1e9
    return f"{sets:,.0f} sets/s, {gflops:.2f} GFLOP/s, 1/{limit / gflops:.0f} of the limit"


def print_results(limit: float, levels: list[Level]) -> None:
    print(f"flop limit: {limit:.1f} GFLOP/s (float64 matmul 2000^3, one thread)")
    for lv in levels:
        print(
            f"n = {lv.n}, p = 30, remove {lv.k}: {lv.sets:,} sets, "
            f"{flops_per_set(lv.n):,.0f} flops per set"
        )
        for label, seconds in (
            ("ssecert, verdict's level", lv.verdict_seconds),
            ("ssecert, refinement level", lv.refine_seconds),
            ("28-line baseline", lv.baseline_seconds),
        ):
            print(
                f"  {label:<27} {seconds:8.3f} s  {_rate(lv, seconds, limit)}; "
                f"{lv.baseline_seconds / seconds:.2f}x the baseline"
            )
        print(
            f"  breaking sets: ssecert {lv.breaking} (+{lv.borderline} borderline), failed "
            f"screenings of the baseline {lv.baseline_failing}"
        )


def to_rows(limit: float, levels: list[Level]) -> list[dict[str, Any]]:
    out = []
    for lv in levels:
        case = f"n = {lv.n}, p = 30, {lv.sets:,} sets of {lv.k}"
        same = f"breaking sets {lv.breaking}, baseline failures {lv.baseline_failing}"
        for label, seconds in (("verdict", lv.verdict_seconds), ("refinement", lv.refine_seconds)):
            out.append(
                row(
                    NAME,
                    f"{case} ({label} level)",
                    seconds,
                    lv.baseline_seconds,
                    "28-line numpy baseline (batch-innermost float64 Cholesky)",
                    f"{_rate(lv, seconds, limit)} ({flops_per_set(lv.n):,.0f} flops per set); "
                    f"baseline {_rate(lv, lv.baseline_seconds, limit)}; {same}",
                )
            )
    out.append(
        row(
            NAME,
            "flop limit: float64 matmul 2000^3, one thread",
            2.0 * 2000**3 / (limit * 1e9),
            None,
            "-",
            f"{limit:.1f} GFLOP/s",
        )
    )
    return out


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The figures as table rows (quick: levels a quarter the size, best of 1)."""
    limit, levels = measure(quick, 1 if quick else 3)
    return to_rows(limit, levels)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller levels")
    parser.add_argument("--repeat", type=int, default=3, help="timing repetitions (best of)")
    args = parser.parse_args()
    start = time.perf_counter()
    print_results(*measure(args.quick, args.repeat))
    print(f"({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
