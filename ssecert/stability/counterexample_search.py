"""Budgeted counterexample searches for the thesis's assumptions.

The searches look for counterexamples only (a ratio above a claimed
constant); they never prove anything, so each design gets a small fixed
budget of operations and objective evaluations (``_Meter``), half for
Lemma 1's search and half for Assumption 3's.  ``_lipschitz_search``
samples pairs and refines the worst with Nelder-Mead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .outcomes import SearchStop, SeriesCode, SeriesFailure, StopCode
from .thesis_messages import search_stop, series_failure, why_not_evaluated

__all__ = [
    "SEARCH_FLOPS",
    "SEARCH_EVALUATIONS",
    "SEARCH_MEMORY",
    "LOCAL_SEARCH_DIM",
    "PairSearch",
]

SEARCH_FLOPS = 2e9  # floating-point operations of the counterexample searches of one design
SEARCH_EVALUATIONS = 6_000  # objective evaluations of the local refinements of one design
SEARCH_MEMORY = 64 * 2**20  # bytes of the cached powers F^(-l-1) L1 and of one batch of terms
LOCAL_SEARCH_DIM = 200  # largest dimension refined by Nelder-Mead


class _SearchExhausted(Exception):
    """The searches of one design used their budget (internal)."""


class _Meter:
    """Counts the work of the searches and stops them at their budget."""

    def __init__(self, flops: float = math.inf, evaluations: float = math.inf) -> None:
        self.max_flops, self.max_evaluations = flops, evaluations
        self.flops = 0.0
        self.evaluations = 0

    def charge(self, flops: float, evaluations: int = 0) -> None:
        self.flops += flops
        self.evaluations += evaluations
        if self.flops > self.max_flops or self.evaluations > self.max_evaluations:
            raise _SearchExhausted


class _Search:
    """Evaluations of one counterexample search: failures counted, best point kept."""

    def __init__(self, meter: _Meter) -> None:
        self.meter = meter
        self.failed = 0
        self.failure: SeriesFailure | None = None  # the first
        self.best_value = -math.inf
        self.best_point: np.ndarray | None = None

    def note(self, failure: SeriesFailure | None, count: int = 1) -> None:
        """Count ``count`` points not evaluated for ``failure`` (none when it is None)."""
        if failure is not None:
            self.failed += count
            self.failure = self.failure or failure

    def objective(self, ratio) -> Any:
        """-ratio(x) for minimisation; a point whose ratio cannot be evaluated counts as 0."""

        def neg(x: np.ndarray) -> float:
            self.meter.charge(0.0, 1)
            value, failure = ratio(x)
            if failure is not None or not math.isfinite(value):
                self.note(failure or SeriesFailure(SeriesCode.RATIO_NOT_FINITE))
                return 0.0
            if value > self.best_value:
                self.best_value, self.best_point = value, np.array(x, copy=True)
            return -value

        return neg


def _local_search(neg, x0: np.ndarray, maxiter: int) -> SearchStop | None:
    """Nelder-Mead from x0; returns why it stopped early (None when it finished)."""
    from scipy.optimize import minimize

    if x0.size > LOCAL_SEARCH_DIM:
        return SearchStop(StopCode.DIMENSION, {"dimension": x0.size, "most": LOCAL_SEARCH_DIM})
    try:
        minimize(
            neg,
            x0,
            method="Nelder-Mead",
            options={"maxiter": maxiter, "xatol": 1e-10, "fatol": 1e-12},
        )
    except _SearchExhausted:
        return SearchStop(StopCode.BUDGET_LOCAL)
    return None


def _sample_rows(p: int) -> int:
    """Samples per batch: 4000, fewer when p is large (SEARCH_MEMORY bounds a batch)."""
    return int(min(4000, max(100, SEARCH_MEMORY // (8 * 8 * max(p, 1)))))


@dataclass
class PairSearch:
    """What ``_lipschitz_search`` did: the pairs it evaluated and not, the points it could not
    evaluate and the first reason, why it stopped early; ``late_stop``: why a later use of
    the same budget (the check of equation (5.9)) stopped.  ``evidence()`` is its record."""

    pairs_evaluated: int
    pairs_not_evaluated: int
    failed: int = 0
    failure: SeriesFailure | None = None
    stop: SearchStop | None = None
    late_stop: SearchStop | None = None

    def evidence(self) -> dict[str, Any]:
        """The record written in a certificate's evidence."""
        out: dict[str, Any] = {
            "pairs_evaluated": self.pairs_evaluated,
            "pairs_not_evaluated": self.pairs_not_evaluated,
        }
        if self.pairs_evaluated == 0:
            out["reason"] = why_not_evaluated(self.failure, self.stop, "no pair could be evaluated")
        else:
            if self.stop is not None:
                out["stopped"] = search_stop(self.stop)
            if self.failed and self.failure is not None:
                out["evaluations_failed"] = self.failed
                out["first_failure"] = series_failure(self.failure)
        if self.late_stop is not None and "stopped" not in out:
            out["stopped"] = search_stop(self.late_stop)
        return out


def _lipschitz_search(
    pi, dim: int, rng: np.random.Generator, scale: float, meter: _Meter, samples: int = 4000
) -> tuple[float | None, np.ndarray | None, np.ndarray | None, PairSearch]:
    """Largest ||Pi(a1) - Pi(a2)|| / ||a1 - a2|| found by sampling and local refinement.

    ``pi(a)`` returns (values with NaN rows, the first ``SeriesFailure`` or None).  The ratio
    is None when no pair could be evaluated.
    """
    search = _Search(meter)
    mags = scale * np.exp(rng.uniform(np.log(0.05), np.log(50.0), (samples, 1)))
    a1 = rng.standard_normal((samples, dim)) * mags
    d = (
        rng.standard_normal((samples, dim))
        * mags
        * np.exp(rng.uniform(np.log(1e-3), 0, (samples, 1)))
    )
    a2 = a1 + d
    ratios = np.full(samples, np.nan)
    stopped = None
    batch = max(1, samples // 8)
    try:
        for start in range(0, samples, batch):
            sl = slice(start, start + batch)
            f1, r1 = pi(a1[sl])
            f2, r2 = pi(a2[sl])
            with np.errstate(over="ignore", invalid="ignore"):
                ratios[sl] = np.linalg.norm(f1 - f2, axis=1) / np.linalg.norm(
                    a1[sl] - a2[sl], axis=1
                )
            search.note(r1 or r2, int(np.count_nonzero(~np.isfinite(ratios[sl]))))
    except _SearchExhausted:
        stopped = SearchStop(StopCode.BUDGET_SAMPLING)
    finite = np.flatnonzero(np.isfinite(ratios))
    record = PairSearch(int(finite.size), int(samples - finite.size))
    if finite.size == 0:
        record.failure, record.stop = search.failure, stopped
        return None, None, None, record
    best = int(finite[np.argmax(ratios[finite])])

    def ratio(x: np.ndarray) -> tuple[float, SeriesFailure | None]:
        x1, x2 = x[:dim], x[dim:]
        den = float(np.linalg.norm(x1 - x2))
        if den == 0:
            return 0.0, None
        values, failure = pi(np.vstack([x1, x2]))
        if failure is not None:
            return math.nan, failure
        with np.errstate(over="ignore", invalid="ignore"):
            return float(np.linalg.norm(values[0] - values[1])) / den, None

    if stopped is None:
        stopped = _local_search(search.objective(ratio), np.concatenate([a1[best], a2[best]]), 2000)
    record.stop, record.failed, record.failure = stopped, search.failed, search.failure
    if search.best_point is not None and search.best_value > ratios[best]:
        x = search.best_point
        return float(search.best_value), x[:dim], x[dim:], record
    return float(ratios[best]), a1[best], a2[best], record
