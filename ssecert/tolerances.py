"""Numerical tolerances: one place, relative to the data, reported with results.

Rank decisions follow one rule everywhere.  A singular value ``sigma`` of a
matrix whose largest singular value (or a data norm standing for it) is
``scale`` is

* **zero** when ``sigma <= rtol * scale``,
* **borderline** when ``rtol * scale < sigma <= borderline_factor * rtol * scale``,
* **nonzero** otherwise,

with ``rtol = max(shape) * eps`` unless given.  A borderline decision makes
the analysis that depends on it inconclusive instead of guessing.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

__all__ = [
    "EPS",
    "BORDERLINE_FACTOR",
    "Tolerances",
    "default_rtol",
    "classify",
    "ZERO",
    "BORDERLINE",
    "NONZERO",
    "product_rounding",
    "gamma",
    "times_up",
]

EPS = float(np.finfo(np.float64).eps)
BORDERLINE_FACTOR = 100.0

ZERO = 0
BORDERLINE = 1
NONZERO = 2


def default_rtol(*dims: int) -> float:
    """``max(dims) * eps``, the default relative rank tolerance."""
    return max(max(dims, default=1), 1) * EPS


def classify(
    values: np.ndarray | float,
    threshold: np.ndarray | float,
    *,
    factor: float = BORDERLINE_FACTOR,
) -> np.ndarray:
    """Classify nonnegative magnitudes as ZERO, BORDERLINE or NONZERO.

    Parameters
    ----------
    values : array_like
        Nonnegative magnitudes (singular values, residual norms).
    threshold : array_like
        Absolute threshold ``rtol * scale``, broadcast against ``values``.
    factor : float, default 100
        Width of the borderline band above the threshold.

    Returns
    -------
    numpy.ndarray of int8
        Codes ``ZERO`` (0), ``BORDERLINE`` (1), ``NONZERO`` (2).

    Examples
    --------
    >>> classify([1e-20, 1e-14, 1.0], 1e-15).tolist()
    [0, 1, 2]
    """
    values = np.asarray(values, dtype=np.float64)
    threshold = np.asarray(threshold, dtype=np.float64)
    codes = np.full(np.broadcast(values, threshold).shape, NONZERO, dtype=np.int8)
    codes[values <= factor * threshold] = BORDERLINE
    codes[values <= threshold] = ZERO
    return codes


@dataclass(frozen=True)
class Tolerances:
    """Tolerances used by the structural analyses.

    Parameters
    ----------
    rank_rtol : float or None, default None
        Relative rank tolerance; ``None`` means ``max(shape) * eps`` of the
        matrix being decided.
    borderline_factor : float, default 100
        A singular value within this factor above the rank threshold is
        borderline and makes the decision inconclusive.
    cluster_rtol : float, default 100 * eps
        Base of the eigenvalue grouping radius: eigenvalues of a group of
        ``m`` lie within ``||A|| * (n * cluster_rtol) ** (1 / m)`` of each
        other, the spread a defective eigenvalue of multiplicity ``m``
        shows in floating point.
    screen_rtol : float, default 1000 * eps
        Shift of the batched Cholesky screening of subset Gramians, relative
        to their largest possible eigenvalue; a subset that fails screening
        is decided exactly by a singular value decomposition.
    witness_rtol : float, default 1e-6
        Largest accepted output mismatch of a simulated stealthy attack,
        relative to the attack's size.
    irrepresentable_rtol : float, default 1e-9
        An irrepresentable constant within this relative distance of 1 is
        inconclusive.
    deadbeat_rtol : float, default 1e-8
        A gain is deadbeat to rounding with index k when
        ``||(A - L C)^k|| <= deadbeat_rtol ||A||^k`` (powers computed exactly
        from the printed floats) and the power before is clearly above.
    certificate_clear : float, default 100
        How many times its floating-point error bound a certificate's margin
        (a Lyapunov decrease, an LMI's eigenvalue, a power norm above the
        deadbeat threshold) must exceed for the certificate to hold.
    """

    rank_rtol: float | None = None
    borderline_factor: float = BORDERLINE_FACTOR
    cluster_rtol: float = 100 * EPS
    screen_rtol: float = 1000 * EPS
    witness_rtol: float = 1e-6
    irrepresentable_rtol: float = 1e-9
    deadbeat_rtol: float = 1e-8
    certificate_clear: float = 100.0

    @staticmethod
    def check(value: object, name: str = "tolerances") -> Tolerances:
        """``value`` itself when it is a Tolerances (default one for None), else TypeError."""
        if value is None:
            return Tolerances()
        if not isinstance(value, Tolerances):
            raise TypeError(
                f"{name} must be a Tolerances object or None, got "
                f"{type(value).__name__} {value!r:.40}"
            )
        return value

    def rtol(self, *dims: int) -> float:
        """Relative rank tolerance for a matrix with dimensions ``dims``."""
        return self.rank_rtol if self.rank_rtol is not None else default_rtol(*dims)

    def to_dict(self) -> dict[str, float | None]:
        """Plain dictionary, for evidence and JSON."""
        return asdict(self)


def gamma(m: int) -> float:
    """Higham's gamma_m = m u / (1 - m u), u = 2^-53: the relative error bound of m roundings
    (Accuracy and Stability of Numerical Algorithms, Lemma 3.1)."""
    u = 2.0**-53
    return m * u / (1 - m * u)


def times_up(x: float, c: float) -> float:
    """``x`` times the power of two ``c``, exact unless the product is subnormal (then rounded)
    or underflows to 0: there taken up a unit in the last place, so that it stays an upper
    bound (a positive product that underflows becomes the smallest subnormal)."""
    y = x * c
    if 0 < abs(y) < 2.0**-1022 or (y == 0 and x * np.sign(c) > 0):
        return float(np.nextafter(y, np.inf))
    return y


def up_by(x: Any, ops: int) -> Any:
    """``x`` (nonnegative, a float or an array) taken up by the rounding of ``ops``
    operations."""
    return x * (1.0 + gamma(ops + 2))


def rows_norm_up(X: np.ndarray) -> np.ndarray:
    """An upper bound of the 2-norm of each row of X (X >= 0), neither under- nor overflowing
    where the row's largest entry does not: that entry times the norm of the row over it (at
    least that entry; a subnormal result taken up by a unit per operation)."""
    X = np.asarray(X, dtype=float)
    top = np.max(X, axis=1) if X.shape[1] else np.zeros(X.shape[0])
    with np.errstate(over="ignore", under="ignore", invalid="ignore", divide="ignore"):
        ratio = np.where(top[:, None] > 0, X / np.where(top > 0, top, 1.0)[:, None], 0.0)
        norm = up_by(top * np.sqrt(np.sum(ratio**2, axis=1)), X.shape[1] + 4)
    norm = np.where(norm < 2.0**-1022, norm + 2.0**-1074 * (X.shape[1] + 4), norm)
    return np.where(np.isfinite(top), np.maximum(norm, top), top)


def interval_product(
    M1: np.ndarray, R1: np.ndarray, M2: np.ndarray, R2: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Midpoint and radius of an interval matrix containing every product of matrices within
    R1 of M1 and R2 of M2 (Rump's midpoint-radius product: |M1| R2 + R1 (|M2| + R2) plus the
    rounding of M1 M2, each rounding taken up)."""
    k = M1.shape[1]
    mid = M1 @ M2
    A1, A2 = np.abs(M1), np.abs(M2)
    rad = A1 @ R2 + R1 @ (A2 + R2) + gamma(k + 2) * (A1 @ A2)
    return mid, up_by(rad, 3 * k + 4)


def product_rounding(
    X: np.ndarray, Y: np.ndarray, addend: np.ndarray | None = None, scale: float = 1.0
) -> float:
    """An upper bound on the 2-norm of fl(addend - scale X Y) minus its exact value, for float
    X, Y, addend and scalar ``scale``.

    Entrywise the rounding of a dot product of k terms is at most gamma_k |X| |Y| (Higham,
    Accuracy and Stability of Numerical Algorithms, 3.5) with gamma_k = k u / (1 - k u); a
    scalar multiple and the subtraction add at most two more roundings.  The Frobenius norm of
    that bound, computed with a safety factor, bounds the 2-norm.
    """
    X = np.asarray(X, dtype=float)
    Y = np.asarray(Y, dtype=float)
    if X.size == 0 or Y.size == 0:
        return 0.0
    u = EPS / 2
    k = X.shape[-1] + 3
    gamma = k * u / (1 - k * u)
    with np.errstate(over="ignore", invalid="ignore"):
        bound = abs(float(scale)) * (np.abs(X) @ np.abs(Y))
        if addend is not None:
            bound = bound + np.abs(np.asarray(addend, dtype=float))
        top = float(np.max(bound))
        frobenius = top * float(np.sqrt(np.sum(np.square(bound / top)))) if top > 0 else 0.0
        # underflow adds at most one subnormal unit per operation
        value = frobenius * gamma * (1 + 4 * k * u) + k * 5e-324 * np.sqrt(bound.size)
    return float(value) if np.isfinite(value) else float("inf")
