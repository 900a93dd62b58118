"""What an enumeration of sensor sets will cost on this machine, before it starts.

A level of the enumeration (every removal of k of the q screened sensors)
costs two things: the precomputed partial sums of its m smallest sensors
(``_combinatorics.level_split``: C(q, m) matrices of n x n, built by
broadcast additions), and the work per set (its sum, its Cholesky
screening, and the share of each block's bookkeeping).  Both rates are
measured once per process and state dimension n: the partial sums on
synthetic matrices, the work per set by scanning a small real level of
synthetic sensors (tens of thousands of sets, about a tenth of a second),
with and without the ranking of the sets closest to breaking that the
verdict's level does.  The estimate so follows this machine, its BLAS and
its load, and every overhead of the enumeration's own loop.

The estimate is what the enumeration records (``cost_estimate`` in the
sparse-observability evidence, beside the time it took: ``verdict_cost``),
what a refusal over the set budget quotes (``cost_of_the_rest``), and what
the number of Dask workers suggested to bring the work under the time
budget is computed from.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..parallel import worker_threads
from ..tolerances import Tolerances
from ._combinatorics import (
    DEFAULT_CHUNK_BYTES,
    _level,
    cholesky_screen,
    count_subsets,
    level_split,
)
from ._level_scan import MIN_WORKER_SETS, _LevelTask, _scan_range

__all__ = [
    "Rates",
    "calibrate",
    "level_seconds",
    "workers_for",
    "verdict_cost",
    "cost_of_the_rest",
    "rounded_seconds",
]

# seconds of screening the calibration's small level aims at (each of its four runs takes about two to three times this)
CALIBRATION_SECONDS = 0.01


@dataclass(frozen=True)
class Rates:
    """Measured costs for n x n Gramians on this machine.

    Attributes
    ----------
    n : int
    per_set : float
        Seconds to add and screen one set's Gramian (in blocks of the
        enumeration's size).
    per_element : float
        Seconds per matrix entry of the precomputed partial sums.
    critical_factor : float
        How much more a set costs on the level that decides the verdict,
        where the sets closest to breaking are ranked too (at least 1).
    """

    n: int
    per_set: float
    per_element: float
    critical_factor: float = 1.0

    def to_dict(self) -> dict[str, Any]:
        return {
            "n": self.n,
            "seconds_per_set": self.per_set,
            "seconds_per_entry": self.per_element,
            "critical_factor": self.critical_factor,
        }


def _best_of(repeats: int, run: Any) -> float:
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


@functools.lru_cache(maxsize=64)
def calibrate(n: int) -> Rates:
    """Measure the rates for n x n Gramians (cached per process and n)."""
    rng = np.random.default_rng(0)
    per_element = _partial_sums_rate(n, rng)
    count = max(8, DEFAULT_CHUNK_BYTES // (8 * n * n))
    X = rng.standard_normal((count, n, n))
    # symmetric and diagonally dominant, so positive definite: built in O(n^2) per matrix
    gramians = X + X.transpose(0, 2, 1) + 2.0 * n * np.eye(n)
    shift = np.eye(n)
    out = np.empty_like(gramians)
    screen = _best_of(2, lambda: cholesky_screen(gramians + shift, 0.0, False, out)) / count
    plain, critical = _small_level_rates(n, screen, per_element, rng)
    return Rates(n, plain, per_element, max(1.0, critical / plain))


def _partial_sums_rate(n: int, rng: np.random.Generator) -> float:
    """Seconds per entry of the partial sums of m = 3 of q items, about 2e6 entries whatever n
    (beyond the caches, as the levels that cost anything are)."""
    q = 3
    while math.comb(q + 1, 3) * n * n <= 2_000_000:
        q += 1
    items = rng.standard_normal((q, n, n))
    entries = sum(math.comb(q, j) for j in range(4)) * n * n
    return _best_of(2, lambda: _level(items, np.eye(n), -1.0, 3)) / entries


def _small_level_rates(
    n: int, screen: float, per_element: float, rng: np.random.Generator
) -> tuple[float, float]:
    """Seconds per set of a real level scan (blocks, sums, screening, bookkeeping) of synthetic
    sensors, without and with the ranking of the sets closest to breaking.

    The level removes k of q = 24 sensors, k chosen for about
    ``CALIBRATION_SECONDS`` of screening; each sensor observes enough of the
    state that every kept set observes all of it, as in the levels that
    cost anything (a set that fails the screening is decided apart).
    """
    q = 24
    wanted = CALIBRATION_SECONDS / max(screen, 1e-12)
    k = next((k for k in range(1, q // 2 + 1) if math.comb(q, k) >= wanted), q // 2)
    rank = min(n, max(1, math.ceil(2 * n / (q - k))))
    P = np.zeros((q, n, n))
    for i in range(q):
        P[i, :rank] = np.linalg.qr(rng.standard_normal((n, rank)))[0].T
    proj = np.einsum("qkn,qkm->qnm", P, P)
    tol = Tolerances()
    shift = tol.screen_rtol * q
    sets = math.comb(q, k)
    partial = sum(math.comb(q, j) for j in range(level_split(q, k, 8 * n * n) + 1)) * n * n
    rates = []
    for critical in (False, True):
        task = _LevelTask(
            P, np.full(q, rank), proj, proj.sum(axis=0) - shift * np.eye(n), shift, k,
            np.arange(q), np.arange(0), tol, critical, np.zeros(q),
        )  # fmt: skip
        # one run, as the enumeration makes one pass (a second would find warm memory)
        seconds = _best_of(1, functools.partial(_scan_range, task, (0, sets)))
        rates.append(max(seconds - partial * per_element, 0.5 * seconds) / sets)
    return rates[0], rates[1]


def level_seconds(q: int, k: int, n: int, *, critical: bool = False) -> float:
    """Estimated seconds to screen every removal of k of q sensors (n states)."""
    if not 0 <= k <= q:
        return 0.0
    rates = calibrate(n)
    m = level_split(q, k, 8 * n * n)
    entries = sum(math.comb(q, j) for j in range(m + 1)) * n * n
    per_set = rates.per_set * (rates.critical_factor if critical else 1.0)
    return math.comb(q, k) * per_set + entries * rates.per_element


def workers_for(seconds: float, budget: float | None) -> int | None:
    """Dask workers (one thread each) that would bring ``seconds`` of work under ``budget``;
    None without a positive budget."""
    if budget is None or budget <= 0:
        return None
    return max(1, math.ceil(seconds / budget))


def _levels_seconds(q: int, n: int, first: int, target: int, threads: int = 1) -> float:
    """Estimated seconds of the levels ``first`` to ``target`` (at least level ``first``) on
    ``threads`` worker threads; the sets closest to breaking are ranked on level ``target``.
    A level is shared by as many threads as it has ranges of ``MIN_WORKER_SETS`` (one, run
    in-process, when it has fewer than two)."""
    return sum(
        level_seconds(q, k, n, critical=(k == target)) / _sharing(math.comb(q, k), threads)
        for k in range(first, max(target, first) + 1)
    )


def _sharing(sets: int, threads: int) -> int:
    """Worker threads that share a level of ``sets`` sets (``parallel.rank_ranges``)."""
    fit = sets // MIN_WORKER_SETS
    return 1 if fit < 2 else min(threads, fit)


def rounded_seconds(seconds: float) -> float:
    """``seconds`` to three significant digits, as the evidence records times."""
    return float(f"{seconds:.3g}")


def verdict_cost(
    q: int, n: int, target: int, client: Any | None, time_budget: float | None
) -> dict[str, Any]:
    """The estimated cost of the levels 0 to ``target`` (those that decide the verdict) of
    removals of q sensors, on the client's threads, and the workers the time budget needs."""
    sets = count_subsets(q, range(max(target, 0) + 1))
    seconds = _levels_seconds(q, n, 0, target)
    threads = worker_threads(client)
    record: dict[str, Any] = {
        "sets_for_verdict": sets,
        "seconds_for_verdict": rounded_seconds(_levels_seconds(q, n, 0, target, threads)),
        "worker_threads": threads,
        "rates": calibrate(n).to_dict(),
    }
    workers = workers_for(seconds, time_budget)
    if workers is not None and workers > threads:
        record["workers_for_time_budget"] = workers
    return record


def cost_of_the_rest(
    q: int, n: int, k: int, target: int, client: Any | None, time_budget: float | None
) -> tuple[float, int | None] | None:
    """What the levels k to ``target`` (past the set budget, up to the verdict's) would cost
    here: the seconds on the client's threads, to three digits, and the Dask workers that
    would bring them under ``time_budget`` (None when the client's threads suffice or without
    a positive budget); None past the verdict's level.  The refusal's words are
    ``sparse_messages.problem_text``'s."""
    if k > target:
        return None
    seconds = _levels_seconds(q, n, k, target)
    threads = worker_threads(client)
    about = rounded_seconds(_levels_seconds(q, n, k, target, threads))
    workers = workers_for(seconds, time_budget)
    return about, workers if workers is not None and workers > threads else None
