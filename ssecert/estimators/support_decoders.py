"""Decoders that find the attack support: estimate x from y = M x + a, a sparse.

* ``l1_decoder``: argmin_x ||y - M x||_1, a linear program (HiGHS);
* ``l0_decoder``: exact search over attack supports (what Imhotep-SMT returns),
  screening supports in batches before deciding each survivor.

``M`` is the sensing matrix (C for one step, or the stacked O_tau whose row
``k * p + i`` is sensor ``i`` at step ``k``).  The iterative Lasso solvers are
in ``decoders``.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..base.validation import as_float_option, as_int_option, describe
from ..tolerances import EPS, default_rtol
from .decoders import _as_measurements, _as_sensing_matrix

__all__ = ["L0Solution", "l1_decoder", "l0_decoder"]

DEFAULT_MAX_SUPPORTS = 1_000_000
_CHUNK_BYTES = 8 * 2**20


@dataclass(frozen=True)
class L0Solution:
    """Result of ``l0_decoder``.

    Attributes
    ----------
    x : ndarray, shape (n,)
        Least-squares state estimate from the rows of the sensors outside
        ``support`` (minimum-norm when those rows do not determine x).
    support : tuple of int
        Sensors declared attacked, sorted.
    a : ndarray, shape (m,)
        Attack estimate ``y - M x`` on the rows of ``support``, zero elsewhere.
    residual : float
        ||y_K - M_K x|| on the kept rows K.
    consistent : bool
        True when ``residual <= rtol * ||y||``: an attack on ``support``
        explains y exactly.  False means no support of at most s sensors
        does, and ``support`` is the one of s sensors with the smallest
        residual (lexicographically first among residuals within
        ``rtol * ||y||`` of the smallest).
    unique : bool
        Whether the kept rows have full column rank (x determined).
    checked : int
        Supports screened.
    verified : int
        Supports decided by an exact least-squares solve.
    rtol : float
        Relative residual tolerance used.
    screen_rtol : float
        Eigenvalue margin of the screening used.
    """

    x: np.ndarray
    support: tuple[int, ...]
    a: np.ndarray
    residual: float
    consistent: bool
    unique: bool
    checked: int
    verified: int
    rtol: float
    screen_rtol: float


def l1_decoder(M: Any, y: Any, *, tol: float = 1e-9) -> np.ndarray:
    """The l1 decoder argmin_x ||y - M x||_1, as a linear program (HiGHS).

    With the residual split as y - M x = u - v, u, v >= 0, it is the LP
    min 1^T (u + v) subject to M x + u - v = y.

    Parameters
    ----------
    M : array_like, shape (m, n)
        Sensing matrix.
    y : array_like, shape (m,)
        Measurements.
    tol : float, default 1e-9
        HiGHS primal and dual feasibility tolerances.

    Returns
    -------
    ndarray, shape (n,)
        A minimiser (a vertex of the LP when it is not unique).

    Raises
    ------
    TypeError
        If an argument has the wrong kind.
    ValueError
        If ``y`` has the wrong length or ``tol <= 0``.
    RuntimeError
        If HiGHS does not report an optimal solution.

    Examples
    --------
    >>> l1_decoder([[1.0], [1.0], [1.0]], [1.0, 1.0, 5.0]).round(9).tolist()
    [1.0]
    """
    import scipy.sparse
    from scipy.optimize import linprog

    M = _as_sensing_matrix(M)
    m, n = M.shape
    y = _as_measurements(y, m, batched=False)
    tol = as_float_option(tol, "tol", min_value=0.0, min_inclusive=False)
    eye = scipy.sparse.identity(m, format="csr")
    A_eq = scipy.sparse.hstack([scipy.sparse.csr_matrix(M), eye, -eye], format="csr")
    cost = np.concatenate([np.zeros(n), np.ones(2 * m)])
    bounds = [(None, None)] * n + [(0.0, None)] * (2 * m)
    result = linprog(
        cost,
        A_eq=A_eq,
        b_eq=y,
        bounds=bounds,
        method="highs",
        options={"primal_feasibility_tolerance": tol, "dual_feasibility_tolerance": tol},
    )
    if result.status != 0:
        raise RuntimeError(f"HiGHS did not solve the l1 decoder LP: {result.message}")
    return np.array(result.x[:n])


def _as_sensor_map(value: Any, m: int) -> tuple[np.ndarray, int]:
    """Sensor of each row: integers 0..q-1, every sensor owning a row."""
    if value is None:
        return np.arange(m), m
    if isinstance(value, (str, bytes)) or not isinstance(value, (Sequence, np.ndarray)):
        raise TypeError(f"sensors_of_row must be a list of sensor indices, got {describe(value)}")
    array = np.asarray(value)
    if array.dtype.kind == "b" or (array.size and array.dtype.kind not in "iuf"):
        raise TypeError(
            f"sensors_of_row must contain integer sensor indices, got {describe(array)}"
        )
    if array.ndim != 1 or array.shape[0] != m:
        raise ValueError(
            f"sensors_of_row must have one entry per row of M ({m}), got shape {array.shape}"
        )
    if array.dtype.kind == "f":
        if not np.all(np.isfinite(array)) or np.any(array != np.round(array)):
            raise TypeError("sensors_of_row must contain integer sensor indices, got fractions")
    sensors = array.astype(np.int64)
    if sensors.min() < 0:
        raise ValueError(f"sensors_of_row must be >= 0, got {int(sensors.min())}")
    q = int(sensors.max()) + 1
    missing = np.setdiff1d(np.arange(q), sensors)
    if missing.size:
        raise ValueError(
            f"sensors_of_row must number the sensors 0..{q - 1} with every sensor owning a row; "
            f"sensor {int(missing[0])} owns none"
        )
    return sensors, q


def _supports(q: int, k: int, chunk: int) -> Iterator[np.ndarray]:
    """k-subsets of range(q) in lexicographic order, as int arrays of at most ``chunk`` rows."""
    combos = itertools.combinations(range(q), k)
    total = math.comb(q, k)
    for start in range(0, total, chunk):
        count = min(chunk, total - start)
        flat = np.fromiter(
            itertools.chain.from_iterable(itertools.islice(combos, count)),
            dtype=np.int64,
            count=count * k,
        )
        yield flat.reshape(count, k)


def _screen(
    grams: np.ndarray,
    moments: np.ndarray,
    energies: np.ndarray,
    gram0: np.ndarray,
    moment0: np.ndarray,
    energy0: float,
    supports: np.ndarray,
    shift: float,
) -> np.ndarray:
    """Squared least-squares residuals of many supports by normal equations.

    In orthonormal coordinates of range(M) the kept rows have Gramian
    G = I - sum_S G_i, with eigenvalues in [0, 1].  Supports whose
    G - shift I has no Cholesky factor get -inf: the caller decides them
    exactly.
    """
    from ..numerics.linalg import screen_positive_definite

    G = np.broadcast_to(gram0, (supports.shape[0],) + gram0.shape).copy()
    b = np.broadcast_to(moment0, (supports.shape[0], moment0.shape[0])).copy()
    e = np.full(supports.shape[0], energy0)
    for j in range(supports.shape[1]):
        G -= grams[supports[:, j]]
        b -= moments[supports[:, j]]
        e -= energies[supports[:, j]]
    if G.shape[-1] == 0:  # M = 0: nothing to fit
        return e
    res2 = np.full(supports.shape[0], -np.inf)
    ok = screen_positive_definite(G, shift)
    if ok.any():
        w = np.linalg.solve(G[ok], b[ok][..., None])[..., 0]
        res2[ok] = e[ok] - np.einsum("ij,ij->i", b[ok], w)
    return res2


def l0_decoder(
    M: Any,
    y: Any,
    s: int,
    *,
    sensors_of_row: Sequence[int] | np.ndarray | None = None,
    max_supports: int = DEFAULT_MAX_SUPPORTS,
    rtol: float = 1e-9,
    screen_rtol: float = 1e-3,
) -> L0Solution:
    """The l0 decoder: the smallest set of attacked sensors that explains y.

    Solves min ||a||_0 (counted in sensors) subject to y = M x + a, by
    exhaustive search over supports of at most ``s`` sensors: for each
    support, least squares on the rows of the other sensors; the answer is
    the support of smallest size whose residual is at most ``rtol * ||y||``,
    lexicographically first among equals -- the answer Imhotep-SMT gives.
    Unique when the plant is 2s-sparse observable and at most s sensors are
    attacked.

    Parameters
    ----------
    M : array_like, shape (m, n)
        Sensing matrix (C, or the stacked O_tau).
    y : array_like, shape (m,)
        Measurements.
    s : int
        Largest number of attacked sensors, 0 <= s < number of sensors.
    sensors_of_row : sequence of int, optional
        Sensor (0-based) owning each row of ``M``; default, each row is its
        own sensor.  For O_tau with p sensors, row k p + i belongs to sensor
        i: ``numpy.tile(numpy.arange(p), tau)``.
    max_supports : int, default 1000000
        Largest number of supports the search may screen,
        sum_{k <= s} C(q, k) for q sensors; more is refused.
    rtol : float, default 1e-9
        A support explains y when its residual is <= rtol * ||y||.
    screen_rtol : float, default 1e-3
        Supports are screened in batches by normal equations in orthonormal
        coordinates of range(M); a support whose kept-rows Gramian has an
        eigenvalue below ``screen_rtol`` (of at most 1), or whose screened
        residual is within the screening error of the threshold, is decided
        by an exact least-squares solve.

    Returns
    -------
    L0Solution
        ``consistent`` is False when no support of at most s sensors
        explains y (noise, or more than s attacked sensors); then the
        support of s sensors with the smallest residual is returned.

    Raises
    ------
    TypeError
        If an argument has the wrong kind.
    ValueError
        If ``y`` or ``sensors_of_row`` does not match ``M``, ``s`` is out of
        range, or the search would screen more than ``max_supports`` supports.

    Examples
    --------
    >>> C = [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, -1.0], [2.0, 1.0]]
    >>> y = [1.0, 2.0, 3.0, 9.0, 4.0]            # x = (1, 2), sensor 3 attacked
    >>> sol = l0_decoder(C, y, 1)
    >>> sol.support, sol.x.round(9).tolist(), sol.consistent
    ((3,), [1.0, 2.0], True)
    >>> O = [[1.0], [1.0], [1.0], [1.0], [1.0], [1.0]]   # 3 sensors, 2 steps
    >>> l0_decoder(O, [1, 1, 7, 1, 1, 7], 1, sensors_of_row=[0, 1, 2, 0, 1, 2]).support
    (2,)
    """
    M = _as_sensing_matrix(M)
    m, n = M.shape
    y = np.array(_as_measurements(y, m, batched=False))
    sensors, q = _as_sensor_map(sensors_of_row, m)
    s = as_int_option(s, "s", min_value=0, max_value=q - 1)
    max_supports = as_int_option(max_supports, "max_supports", min_value=1)
    rtol = as_float_option(rtol, "rtol", min_value=0.0)
    screen_rtol = as_float_option(
        screen_rtol, "screen_rtol", min_value=0.0, max_value=1.0, min_inclusive=False
    )
    total = sum(math.comb(q, k) for k in range(s + 1))
    if total > max_supports:
        raise ValueError(
            f"l0_decoder would screen {total} supports (every set of at most {s} of {q} "
            f"sensors), more than max_supports = {max_supports}; raise max_supports or lower s"
        )

    # orthonormal coordinates of range(M): kept-rows Gramians have eigenvalues in [0, 1]
    U, sv, _ = np.linalg.svd(M, full_matrices=False)
    rank = int(np.sum(sv > default_rtol(m, n) * sv[0]))
    U = U[:, :rank]
    grams = np.zeros((q, rank, rank))
    np.add.at(grams, sensors, U[:, :, None] * U[:, None, :])
    moments = np.zeros((q, rank))
    np.add.at(moments, sensors, U * y[:, None])
    energies = np.bincount(sensors, weights=y * y, minlength=q)
    gram0, moment0, energy0 = np.eye(rank), U.T @ y, float(y @ y)
    y_norm = float(np.sqrt(energy0))
    accept = rtol * y_norm
    # rounding error of a screened squared residual: with the kept-rows
    # Gramian G >= screen_rtol I, ||G^-1 b||^2 <= ||y||^2 / screen_rtol, so
    # the normal equations lose about (rank + m) eps ||y||^2 / screen_rtol
    slack = 10.0 * (rank + m) * EPS * energy0 / screen_rtol
    chunk = max(64, _CHUNK_BYTES // (8 * max(rank, 1) ** 2))

    checked = 0
    verified = 0

    def exact(support: tuple[int, ...]) -> tuple[float, np.ndarray, bool]:
        nonlocal verified
        verified += 1
        kept = ~np.isin(sensors, support)
        x, _, kept_rank, _ = np.linalg.lstsq(M[kept], y[kept], rcond=None)
        return float(np.linalg.norm(y[kept] - M[kept] @ x)), x, bool(kept_rank == n)

    def solution(
        support: tuple[int, ...], residual: float, x: np.ndarray, unique: bool
    ) -> L0Solution:
        a = np.where(np.isin(sensors, support), y - M @ x, 0.0)
        return L0Solution(
            x,
            tuple(int(i) for i in support),
            a,
            residual,
            residual <= accept,
            unique,
            checked,
            verified,
            rtol,
            screen_rtol,
        )

    for k in range(s + 1):
        last = k == s
        level_res2, level_supports = [], []
        for block in _supports(q, k, chunk):
            res2 = _screen(grams, moments, energies, gram0, moment0, energy0, block, screen_rtol)
            checked += block.shape[0]
            for row in np.flatnonzero(res2 <= accept**2 + slack):  # lexicographic order
                support = tuple(block[row].tolist())
                residual, x, unique = exact(support)
                if residual <= accept:
                    return solution(support, residual, x, unique)
            if last:
                level_res2.append(res2)
                level_supports.append(block)
        if last:
            # nothing explains y: the support of s sensors with the smallest residual
            res2 = np.concatenate(level_res2)
            supports = np.concatenate(level_supports)
            screened = res2 > -np.inf
            best = res2[screened].min() if screened.any() else np.inf
            rows = np.flatnonzero(~screened | (res2 <= best + 2.0 * slack))
            candidates = [
                (tuple(supports[row].tolist()),) + exact(tuple(supports[row].tolist()))
                for row in rows
            ]
            # residuals within rtol ||y|| of the least are ties: lexicographically first
            least = min(residual for _, residual, _, _ in candidates)
            support, residual, x, unique = next(c for c in candidates if c[1] <= least + accept)
            return solution(support, residual, x, unique)
    raise AssertionError("unreachable: the last level always returns")  # pragma: no cover
