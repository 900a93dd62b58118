"""Shrinkage operators (proximal maps of the l1 and elastic-net penalties).

All operators act componentwise on arrays of any shape; thresholds and
weights broadcast against the input, so a batch of attack estimates of
shape (runs, p) can be shrunk with one per-sensor weight vector of shape (p,).
"""

from __future__ import annotations

import numpy as np

__all__ = ["soft_threshold", "elastic_net_shrink", "weighted_soft_threshold"]


def soft_threshold(x: np.ndarray, threshold: float | np.ndarray) -> np.ndarray:
    """S_lambda(x) = sign(x) max(|x| - lambda, 0), the proximal map of lambda ||.||_1.

    Parameters
    ----------
    x : array_like
    threshold : float or array_like
        lambda >= 0, broadcast against ``x``.

    Returns
    -------
    ndarray

    Examples
    --------
    >>> soft_threshold([-3.0, -0.5, 0.2, 2.0], 1.0).tolist()
    [-2.0, -0.0, 0.0, 1.0]

    Raises
    ------
    ValueError
        If a threshold is negative (it would enlarge values, not shrink them).
    """
    x = np.asarray(x, dtype=float)
    if np.any(np.asarray(threshold) < 0):
        raise ValueError(f"threshold must be >= 0, got {np.min(threshold)}")
    return np.sign(x) * np.maximum(np.abs(x) - threshold, 0.0)


def elastic_net_shrink(x: np.ndarray, threshold: float | np.ndarray, shrink: float) -> np.ndarray:
    """q S_lambda(x), the shrinkage of the thesis's elastic-net observer (5.4).

    With q = 1 / (1 + delta) it is the proximal map of
    lambda ||.||_1 + (delta / 2) ||.||^2 scaled as in the thesis.

    Examples
    --------
    >>> elastic_net_shrink([2.0, -0.5], 1.0, 0.5).tolist()
    [0.5, -0.0]
    """
    return shrink * soft_threshold(x, threshold)


def weighted_soft_threshold(x: np.ndarray, threshold: float, weights: np.ndarray) -> np.ndarray:
    """S_(lambda w)(x): soft thresholding with per-component weights w >= 0.

    The proximal map of lambda sum_i w_i |x_i| (weighted l1).

    Examples
    --------
    >>> weighted_soft_threshold([1.0, 1.0], 0.5, [0.0, 4.0]).tolist()
    [1.0, 0.0]
    """
    return soft_threshold(x, threshold * np.asarray(weights, dtype=float))
