"""Lemma 1's map Pi(a) = -sum_l F^(-l-1) L1 Psi_q^l(a), summed in closed form.

Psi_q^l(a) reaches zero after finitely many terms when lambda > 0
(``series_terms`` counts them), so the series is a finite sum; the powers
F^(-l-1) L1 are cached once per design within a memory bound.
"""

from __future__ import annotations

import math

import numpy as np

from .counterexample_search import SEARCH_MEMORY, _Meter
from .outcomes import SeriesCode, SeriesFailure
from .thesis_messages import series_failure

__all__ = ["SeriesError", "series_terms", "pi_map"]


MAX_SERIES_TERMS = 10_000  # terms of the series for Pi summed per evaluation


class SeriesError(ArithmeticError):
    """The series for Pi cannot be summed: too many terms, or the powers of F^-1 overflow."""


def series_terms(magnitude: float, q: float, lam: float) -> float:
    """Number of nonzero terms of the series for Pi at an a with max |a_i| = magnitude.

    Psi_q^l(a) has largest entry m_l with m_0 = magnitude and
    m_(l+1) = q max(m_l - lambda, 0): for q = 1, ceil(magnitude / lambda) terms;
    for q < 1, m_l + c = q^l (m_0 + c) with c = q lambda / (1 - q).  Infinite
    for lambda = 0 (the terms only shrink geometrically).
    """
    if not magnitude > 0:
        return 0.0
    if not math.isfinite(magnitude) or lam <= 0:
        return math.inf
    if q >= 1.0:
        return float(math.ceil(magnitude / lam)) + 1.0
    if q <= 0.0:
        return 1.0
    c = q * lam / (1.0 - q)
    return float(max(1, math.ceil(math.log1p(magnitude / c) / -math.log(q)))) + 1.0


class _PiSeries:
    """Pi(a) = -sum_l W_l Psi_q^l(a) with W_l = F^(-l-1) L1 computed once per design.

    Psi_q^l(a) is formed in closed form (see ``series_terms``), so an
    evaluation is one tensor contraction instead of a loop over terms.  The
    powers are cached up to ``max_terms`` terms within ``memory`` bytes;
    rows that need more terms, or powers that overflow, give NaN and the
    reason (a ``SeriesFailure``).
    """

    def __init__(
        self,
        F_inv: np.ndarray,
        L1: np.ndarray,
        q: float,
        lam: float,
        *,
        max_terms: int = MAX_SERIES_TERMS,
        memory: int = SEARCH_MEMORY,
    ) -> None:
        self.F_inv, self.L1, self.q, self.lam = F_inv, L1, float(q), float(lam)
        n, p = L1.shape
        self.memory = memory
        self.max_terms = int(max(1, min(max_terms, memory // (8 * n * p))))
        # the bound on the cached powers, when it is what limits the terms (MiB)
        self.memory_limit = None if self.max_terms == max_terms else memory // 2**20
        self.W = np.empty((0, p, n))  # W[l] = (F^(-l-1) L1)^T
        self.overflow_at: int | None = None  # first l with a non-finite W_l
        self._next = F_inv.copy()

    def _extend(self, terms: int) -> None:
        have = self.W.shape[0]
        if terms <= have or self.overflow_at is not None:
            return
        want = min(self.max_terms, max(terms, 2 * have, 16))
        new = np.empty((want - have,) + self.W.shape[1:])
        P = self._next
        with np.errstate(over="ignore", invalid="ignore"):
            for j in range(want - have):
                new[j] = (P @ self.L1).T
                P = P @ self.F_inv
        finite = np.all(np.isfinite(new), axis=(1, 2))
        if not finite.all():
            self.overflow_at = have + int(np.argmin(finite))
            new = new[: self.overflow_at - have]
        self.W = np.concatenate([self.W, new])
        self._next = P

    def _terms(self, a: np.ndarray, K: int) -> np.ndarray:
        """Psi_q^l(a) for l < K, shape (rows, K, p)."""
        q, lam = self.q, self.lam
        mag = np.abs(a)[:, None, :]
        ell = np.arange(K, dtype=float)[None, :, None]
        with np.errstate(over="ignore", invalid="ignore"):
            if q >= 1.0:
                m = mag - ell * lam
            else:
                c = q * lam / (1.0 - q)
                m = q**ell * (mag + c) - c
        # term l is nonzero only while the previous one exceeds the threshold
        dead = np.zeros(m.shape, dtype=bool)
        np.less_equal(m[:, :-1], lam, out=dead[:, 1:])
        np.maximum(m, 0.0, out=m)
        m[dead] = 0.0
        m[:, 0] = mag[:, 0]
        m *= np.sign(a)[:, None, :]
        return m

    def __call__(
        self, a: np.ndarray, meter: _Meter | None = None
    ) -> tuple[np.ndarray, SeriesFailure | None]:
        """Pi at the rows of ``a`` (NaN where it cannot be summed) and the first reason a row
        could not be (None when every row was summed)."""
        a = np.atleast_2d(np.asarray(a, dtype=float))
        rows = a.shape[0]
        n, p = self.L1.shape
        out = np.full((rows, n), np.nan)
        mags = np.abs(a).max(axis=1, initial=0.0)
        needed = np.array([series_terms(float(m), self.q, self.lam) for m in mags])
        failure = None
        ok = needed <= self.max_terms
        if not ok.all():
            worst = int(np.argmax(needed))
            failure = SeriesFailure(
                SeriesCode.TOO_MANY_TERMS,
                {
                    "needed": float(needed[worst]),
                    "magnitude": float(mags[worst]),
                    "threshold": self.lam,
                    "shrink": self.q,
                    "most": self.max_terms,
                    "memory_mib": self.memory_limit,
                },
            )
        if ok.any():
            K = int(needed[ok].max())
            self._extend(K)
            if self.overflow_at is not None and self.overflow_at < K:
                over = ok & (needed > self.overflow_at)
                ok &= ~over
                failure = failure or SeriesFailure(
                    SeriesCode.POWERS_OVERFLOW,
                    {
                        "terms": self.overflow_at,
                        "norm_F_inv": float(np.linalg.norm(self.F_inv, 2)),
                        "magnitude": float(mags[over].max()),
                        "needed": float(needed[over].max()),
                    },
                )
        idx = np.flatnonzero(ok)
        if idx.size:
            K = max(1, int(needed[idx].max()))
            if meter is not None:  # the elementwise work of _terms dominates for small n
                meter.charge(idx.size * K * p * (2.0 * n + 30.0))
            chunk = max(1, int(self.memory // (8 * 4 * K * p)))
            W = self.W[:K].reshape(K * p, n)
            with np.errstate(over="ignore", invalid="ignore"):
                for start in range(0, idx.size, chunk):
                    sel = idx[start : start + chunk]
                    out[sel] = -np.dot(self._terms(a[sel], K).reshape(sel.size, K * p), W)
            bad = ~np.all(np.isfinite(out[idx]), axis=1)
            if bad.any():
                out[idx[bad]] = np.nan
                failure = failure or SeriesFailure(SeriesCode.SUM_OVERFLOW)
        return out, failure


def pi_map(
    a: np.ndarray,
    F_inv: np.ndarray,
    L1: np.ndarray,
    q: float,
    lam: float,
    *,
    max_terms: int = MAX_SERIES_TERMS,
) -> np.ndarray:
    """Pi(a) = -sum_l F^(-l-1) L1 Psi_q^l(a) for a batch of a (rows).

    The sum is finite: Psi_q^l(a) is exactly zero after finitely many
    iterations when lambda > 0 (``series_terms`` counts them).

    Raises
    ------
    SeriesError
        (an ``ArithmeticError``) when some row needs more than ``max_terms``
        terms or the powers of F^-1 overflow; the message says which.
    """
    out, failure = _PiSeries(F_inv, L1, q, lam, max_terms=max_terms)(a)
    if failure is not None:
        raise SeriesError(series_failure(failure))
    if not np.all(np.isfinite(out)):
        raise SeriesError("the series for Pi did not give finite values")
    return out
