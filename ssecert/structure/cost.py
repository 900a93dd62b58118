"""What an enumeration of sensor sets will cost on this machine, before it starts.

A level of the enumeration (every removal of k of the q screened sensors)
costs two things: the precomputed partial sums of its m smallest sensors
(``_combinatorics.level_split``: C(q, m) matrices of n x n, built by
broadcast additions), and one addition and one Cholesky screening per set.
Both rates are measured once per process and state dimension n on
synthetic matrices of the same shape (a few tens of milliseconds), so the
estimate follows this machine, its BLAS and its load.

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
from ._combinatorics import (
    DEFAULT_CHUNK_BYTES,
    _level,
    cholesky_screen,
    count_subsets,
    level_split,
)

__all__ = [
    "Rates",
    "calibrate",
    "level_seconds",
    "workers_for",
    "verdict_cost",
    "cost_of_the_rest",
    "rounded_seconds",
]

# the sets closest to breaking are ranked on the level that decides the verdict (argsort of
# the pivots and the kept sets of each block's best): measured about a third more per set
CRITICAL_OVERHEAD = 1.35


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
    """

    n: int
    per_set: float
    per_element: float

    def to_dict(self) -> dict[str, Any]:
        return {"n": self.n, "seconds_per_set": self.per_set, "seconds_per_entry": self.per_element}


def _best_of(repeats: int, run: Any) -> float:
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


@functools.lru_cache(maxsize=64)
def calibrate(n: int) -> Rates:
    """Measure the two rates for n x n Gramians (cached per process and n)."""
    rng = np.random.default_rng(0)
    count = max(8, DEFAULT_CHUNK_BYTES // (8 * n * n))
    X = rng.standard_normal((count, n, n))
    # symmetric and diagonally dominant, so positive definite: built in O(n^2) per matrix
    gramians = X + X.transpose(0, 2, 1) + 2.0 * n * np.eye(n)
    shift = np.eye(n)
    out = np.empty_like(gramians)
    per_set = _best_of(2, lambda: cholesky_screen(gramians + shift, 0.0, False, out)) / count
    # partial sums of m = 3 of q items, about 2e6 entries whatever n (beyond the caches, as
    # the levels that cost anything are)
    q = 3
    while math.comb(q + 1, 3) * n * n <= 2_000_000:
        q += 1
    items = rng.standard_normal((q, n, n))
    entries = sum(math.comb(q, j) for j in range(4)) * n * n
    per_element = _best_of(2, lambda: _level(items, shift, -1.0, 3)) / entries
    return Rates(n, per_set, per_element)


def level_seconds(q: int, k: int, n: int, *, critical: bool = False) -> float:
    """Estimated seconds to screen every removal of k of q sensors (n states)."""
    if not 0 <= k <= q:
        return 0.0
    rates = calibrate(n)
    m = level_split(q, k, 8 * n * n)
    entries = sum(math.comb(q, j) for j in range(m + 1)) * n * n
    per_set = rates.per_set * (CRITICAL_OVERHEAD if critical else 1.0)
    return math.comb(q, k) * per_set + entries * rates.per_element


def workers_for(seconds: float, budget: float | None) -> int | None:
    """Dask workers (one thread each) that would bring ``seconds`` of work under ``budget``;
    None without a positive budget."""
    if budget is None or budget <= 0:
        return None
    return max(1, math.ceil(seconds / budget))


def _levels_seconds(q: int, n: int, first: int, target: int) -> float:
    """Estimated seconds of the levels ``first`` to ``target`` (at least level ``first``); the
    sets closest to breaking are ranked on level ``target``."""
    return sum(
        level_seconds(q, k, n, critical=(k == target)) for k in range(first, max(target, first) + 1)
    )


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
        "seconds_for_verdict": rounded_seconds(seconds / threads),
        "worker_threads": threads,
        "rates": calibrate(n).to_dict(),
    }
    workers = workers_for(seconds, time_budget)
    if workers is not None and workers > threads:
        record["workers_for_time_budget"] = workers
    return record


def cost_of_the_rest(
    q: int, n: int, k: int, target: int, client: Any | None, time_budget: float | None
) -> str:
    """What the levels k to ``target`` (past the set budget, up to the verdict's) would cost
    here, as the end of the refusal's sentence; empty past the verdict's level."""
    if k > target:
        return ""
    seconds = _levels_seconds(q, n, k, target)
    threads = worker_threads(client)
    about = rounded_seconds(seconds / threads)
    text = f" (the rest of the verdict's sets would take about {about:g} s here"
    workers = workers_for(seconds, time_budget)
    if workers is not None and workers > threads:
        text += f"; about {workers:,} Dask workers would take them under {time_budget:g} s"
    return text + "; --max-sets raises the budget)"
