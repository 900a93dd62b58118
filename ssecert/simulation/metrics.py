"""Estimation metrics, per run and step, and their Monte Carlo aggregates.

Definitions (docs/architecture.md, "Simulation metrics"):

* error: ||x_hat - x||, the absolute estimation error;
* error relative to the initial error: ||x_hat(k) - x(k)|| / ||x_hat(0) - x(0)||
  (the denominator floored at 1e-9 ||x0||): how much of the initial error is left,
  meaningful whether the state decays, grows or stays;
* relative error: ||x_hat - x|| / max(||x||, 1e-9 ||x0||), the error relative to the
  present state (grows without bound when the state decays to 0 and the error
  does not: never compare designs on it alone);
* MSE: mean over states of (x_hat - x)^2;
* support error at step k: the Jaccard distance
  |supp(a_hat) xor supp(a)| / |supp(a_hat) or supp(a)| (0 when both are
  empty, 1 when a_hat = 0 and a != 0), our precise form of the thesis's
  MASE, which it does not define; supp uses |a_i| > 1e-9 * scale with scale
  the largest attack magnitude of the run (1 when there is no attack);
* settling step of a mean error curve: the first step from which the curve
  stays within 5% of its initial distance to its final value (None when it
  is not finite);
* detection delay: steps from the first attacked step until the estimated
  support contains every attacked sensor and keeps doing so to the end of
  the horizon (NaN if it never does).
"""

from __future__ import annotations

import warnings
from typing import Any, Literal

import numpy as np

__all__ = [
    "absolute_error",
    "initial_relative_error",
    "relative_error",
    "mse",
    "support_error",
    "detection_delay",
    "settling_step",
    "nanquantile",
    "summarize",
    "SUPPORT_RTOL",
]

SUPPORT_RTOL = 1e-9


def relative_error(x_hat: np.ndarray, x: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """||x_hat - x|| / max(||x||, 1e-9 ||x0||), over the last axis.

    Examples
    --------
    >>> import numpy as np
    >>> float(relative_error(np.array([1.0, 1.0]), np.array([1.0, 2.0]), np.array([1.0, 2.0])))
    0.4472135954999579
    """
    num = np.linalg.norm(x_hat - x, axis=-1)
    den = np.maximum(np.linalg.norm(x, axis=-1), 1e-9 * np.linalg.norm(x0, axis=-1))
    return num / np.maximum(den, np.finfo(float).tiny)


def absolute_error(x_hat: np.ndarray, x: np.ndarray) -> np.ndarray:
    """||x_hat - x|| over the last axis.

    Examples
    --------
    >>> import numpy as np
    >>> float(absolute_error(np.array([1.0, 1.0]), np.array([1.0, 3.0])))
    2.0
    """
    return np.linalg.norm(x_hat - x, axis=-1)


def initial_relative_error(error: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """||x_hat(k) - x(k)|| / max(||x_hat(0) - x(0)||, 1e-9 ||x0||) from the absolute error
    of shape (steps + 1, runs) and the initial states x0 of shape (runs, n).

    Examples
    --------
    >>> import numpy as np
    >>> initial_relative_error(np.array([[2.0], [1.0], [0.5]]), np.array([[3.0, 4.0]])).ravel()
    array([1.  , 0.5 , 0.25])
    """
    den = np.maximum(error[:1], 1e-9 * np.linalg.norm(x0, axis=-1))
    return error / np.maximum(den, np.finfo(float).tiny)


def mse(x_hat: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Mean over the last axis of (x_hat - x)^2."""
    return np.mean((x_hat - x) ** 2, axis=-1)


def _scale(a: np.ndarray) -> np.ndarray:
    """Per-run attack scale, shape (runs,), from a of shape (steps, runs, p)."""
    peak = np.abs(a).max(axis=(0, 2))
    return np.where(peak > 0, peak, 1.0)


def support_error(a_hat: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Jaccard distance between estimated and true supports, shape (steps, runs).

    Parameters
    ----------
    a_hat, a : ndarray, shape (steps, runs, p)

    Examples
    --------
    >>> import numpy as np
    >>> a = np.array([[[0.0, 4.0, 0.0]]])
    >>> support_error(np.array([[[0.0, 3.9, 0.2]]]), a).tolist()
    [[0.5]]
    """
    thr = SUPPORT_RTOL * _scale(a)[None, :, None]
    est = np.abs(a_hat) > thr
    true = np.abs(a) > thr
    union = np.count_nonzero(est | true, axis=-1)
    diff = np.count_nonzero(est ^ true, axis=-1)
    return np.where(union > 0, diff / np.maximum(union, 1), 0.0)


def detection_delay(a_hat: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Steps from the attack onset until supp(a_hat) contains supp(a) for good, per run.

    The estimated support must contain every attacked sensor from that step
    to the end of the horizon (a support found and then lost does not
    count); NaN when that never happens or there is no attack.

    Examples
    --------
    >>> import numpy as np
    >>> a = np.zeros((5, 1, 2)); a[1:, 0, 0] = 4.0
    >>> a_hat = np.zeros((5, 1, 2)); a_hat[3:, 0, 0] = 3.0
    >>> detection_delay(a_hat, a).tolist()
    [2.0]
    """
    thr = SUPPORT_RTOL * _scale(a)[None, :, None]
    est = np.abs(a_hat) > thr
    true = np.abs(a) > thr
    attacked = true.any(axis=-1)  # (steps, runs)
    missed = np.any(true & ~est, axis=-1)  # an attacked sensor not in the estimate
    steps, runs = attacked.shape
    out = np.full(runs, np.nan)
    for r in range(runs):
        onset = np.flatnonzero(attacked[:, r])
        if onset.size == 0:
            continue
        misses = np.flatnonzero(missed[:, r])
        last = misses[-1] if misses.size else onset[0] - 1
        if last < steps - 1:
            out[r] = float(max(last + 1, onset[0]) - onset[0])
    return out


def summarize(
    series: np.ndarray, *, quantiles: tuple[float, ...] = (0.1, 0.5, 0.9)
) -> dict[str, Any]:
    """Mean and quantiles over runs of a (steps, runs) array, per step (NaN where no run
    has a value, inf where runs diverged)."""
    with warnings.catch_warnings(), np.errstate(over="ignore", invalid="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN steps give NaN, as intended
        out: dict[str, Any] = {"mean": np.nanmean(series, axis=1)}
        for q in quantiles:
            out[f"q{round(q * 100):02d}"] = quantile(series, q, axis=1)
    return out


def nanquantile(
    values: np.ndarray,
    q: float,
    axis: int | None = None,
    method: Literal["linear", "lower", "higher"] = "linear",
) -> Any:
    """``numpy.nanquantile(values, q, axis=axis, method=method)``, the same numbers, without
    its Python loop over the slices that hold a NaN (numpy quantiles each such slice on its
    own, about 0.1 ms apiece: seconds for the runs of a report's simulations).

    The slices with the same number m of values are quantiled together, on their m
    smallest (NumPy sorts NaN last): a quantile depends only on the values, so each is the
    one numpy.nanquantile gives. All-NaN slices give NaN, without numpy's warning.

    Examples
    --------
    >>> import numpy as np
    >>> data = np.array([[1.0, np.nan, 3.0], [np.nan, np.nan, np.nan], [4.0, 5.0, 6.0]])
    >>> nanquantile(data, 0.5, axis=1)
    array([ 2., nan,  5.])
    """
    values = np.asarray(values, dtype=float)
    if axis is None or values.ndim <= 1:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # an all-NaN slice gives NaN
            return np.nanquantile(values, q, axis=axis, method=method)
    moved = np.moveaxis(values, axis, -1)
    flat = moved.reshape(-1, moved.shape[-1])
    missing = np.isnan(flat)
    if not missing.any():
        return np.quantile(values, q, axis=axis, method=method)
    counts = flat.shape[1] - np.count_nonzero(missing, axis=1)
    ordered = np.sort(flat, axis=1)
    out = np.full(flat.shape[0], np.nan)
    for m in np.unique(counts[counts > 0]):
        rows = counts == m
        out[rows] = np.quantile(ordered[rows, :m], q, axis=1, method=method)
    return out.reshape(moved.shape[:-1])


def quantile(values: np.ndarray, q: float, axis: int | None = None) -> Any:
    """``numpy.nanquantile``, but inf where the quantile involves diverged (inf) runs.

    Interpolating towards an infinite value gives NaN in NumPy; a quantile
    that interpolates towards a diverged run is unbounded, not undefined.
    """
    diverged = np.isposinf(values)
    if not diverged.any():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN slices give NaN
            plain = nanquantile(values, q, axis=axis)
        return plain if np.ndim(plain) else float(plain)
    big = np.finfo(float).max
    finite = np.where(diverged, big, values)
    with warnings.catch_warnings(), np.errstate(over="ignore", invalid="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN slices give NaN, as intended
        linear = nanquantile(finite, q, axis=axis)
        low = nanquantile(finite, q, axis=axis, method="lower")
        high = nanquantile(finite, q, axis=axis, method="higher")
    unbounded = (low >= big) | ((high >= big) & (linear != low))
    result = np.where(unbounded, np.inf, linear)
    return result if np.ndim(result) else float(result)


def settling_step(curve: np.ndarray, band: float = 0.05) -> int | None:
    """The first step k from which ``curve`` stays within ``band`` x |curve[0] - curve[-1]|
    of its final value (0 when it starts there); None when the curve is not finite."""
    curve = np.asarray(curve, dtype=float)
    if curve.size == 0 or not np.all(np.isfinite(curve)):
        return None
    final = curve[-1]
    outside = np.abs(curve - final) > band * abs(curve[0] - final)
    (where,) = np.nonzero(outside)
    return int(where[-1] + 1) if where.size else 0
