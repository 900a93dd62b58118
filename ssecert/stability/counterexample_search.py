"""Budgeted counterexample searches for the thesis's assumptions.

The searches look for counterexamples only (a ratio above a claimed
constant); they never prove anything, so each design gets a small fixed
budget of operations and objective evaluations (``_Meter``), half for
Lemma 1's search and half for Assumption 3's.  ``_lipschitz_search``
samples pairs and refines the worst with Nelder-Mead.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["SEARCH_FLOPS", "SEARCH_EVALUATIONS", "SEARCH_MEMORY", "LOCAL_SEARCH_DIM"]

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
        self.reason = ""
        self.best_value = -math.inf
        self.best_point: np.ndarray | None = None

    def note(self, reason: str, count: int = 1) -> None:
        if reason:
            self.failed += count
            self.reason = self.reason or reason

    def objective(self, ratio) -> Any:
        """-ratio(x) for minimisation; a point whose ratio cannot be evaluated counts as 0."""

        def neg(x: np.ndarray) -> float:
            self.meter.charge(0.0, 1)
            value, reason = ratio(x)
            if reason or not math.isfinite(value):
                self.note(reason or "a non-finite ratio")
                return 0.0
            if value > self.best_value:
                self.best_value, self.best_point = value, np.array(x, copy=True)
            return -value

        return neg


def _local_search(neg, x0: np.ndarray, maxiter: int) -> str:
    """Nelder-Mead from x0; returns why it stopped early ('' when it finished)."""
    from scipy.optimize import minimize

    if x0.size > LOCAL_SEARCH_DIM:
        return f"no local refinement in dimension {x0.size} (> {LOCAL_SEARCH_DIM})"
    try:
        minimize(
            neg,
            x0,
            method="Nelder-Mead",
            options={"maxiter": maxiter, "xatol": 1e-10, "fatol": 1e-12},
        )
    except _SearchExhausted:
        return "the search budget ran out during the local refinement"
    return ""


def _sample_rows(p: int) -> int:
    """Samples per batch: 4000, fewer when p is large (SEARCH_MEMORY bounds a batch)."""
    return int(min(4000, max(100, SEARCH_MEMORY // (8 * 8 * max(p, 1)))))


def _lipschitz_search(
    pi, dim: int, rng: np.random.Generator, scale: float, meter: _Meter, samples: int = 4000
) -> tuple[float | None, np.ndarray | None, np.ndarray | None, dict[str, Any]]:
    """Largest ||Pi(a1) - Pi(a2)|| / ||a1 - a2|| found by sampling and local refinement.

    ``pi(a)`` returns (values with NaN rows, reason).  The ratio is None when
    no pair could be evaluated.
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
    stopped = ""
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
        stopped = "the search budget ran out during sampling"
    finite = np.flatnonzero(np.isfinite(ratios))
    info: dict[str, Any] = {
        "pairs_evaluated": int(finite.size),
        "pairs_not_evaluated": int(samples - finite.size),
    }
    if finite.size == 0:
        info["reason"] = search.reason or stopped or "no pair could be evaluated"
        return None, None, None, info
    best = int(finite[np.argmax(ratios[finite])])

    def ratio(x: np.ndarray) -> tuple[float, str]:
        x1, x2 = x[:dim], x[dim:]
        den = float(np.linalg.norm(x1 - x2))
        if den == 0:
            return 0.0, ""
        values, reason = pi(np.vstack([x1, x2]))
        if reason:
            return math.nan, reason
        with np.errstate(over="ignore", invalid="ignore"):
            return float(np.linalg.norm(values[0] - values[1])) / den, ""

    if not stopped:
        stopped = _local_search(search.objective(ratio), np.concatenate([a1[best], a2[best]]), 2000)
    if stopped:
        info["stopped"] = stopped
    if search.failed:
        info["evaluations_failed"] = search.failed
        info["first_failure"] = search.reason
    if search.best_point is not None and search.best_value > ratios[best]:
        x = search.best_point
        return float(search.best_value), x[:dim], x[dim:], info
    return float(ratios[best]), a1[best], a2[best], info
