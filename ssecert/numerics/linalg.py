"""Numerical building blocks of the structural analyses.

* ``eigen_clusters`` (from ``ssecert.numerics.eigen``): eigenvalues grouped into
  clusters with their eigenspaces, grouping decided from condition numbers
  and a defect-aware radius, every doubtful grouping reported instead of
  guessed;
* ``staircase``: orthogonal observability staircase (block Arnoldi on the
  rows of C), the reliable way to get the observable subspace and the
  observability index (the rank of the stacked observability matrix is not);
* ``sensor_subspaces``: the same for every sensor alone, vectorised;
* ``screen_positive_definite``: batched Cholesky test that never raises,
  screened in single precision with the matrices stored batch-last
  (``cholesky_batch_last``, ``single_precision_margin``) and decided by
  ``numpy.linalg.cholesky`` (``cholesky_or_nan``) where the screening is not
  conclusive;
* ``stacked_rank``: exact rank decisions of many small stacks by SVD.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from ..system import System
from ..tolerances import BORDERLINE, NONZERO, ZERO, Tolerances, classify
from .eigen import EigenAnalysis, EigenCluster, eigen_clusters

__all__ = [
    "EigenCluster",
    "EigenAnalysis",
    "eigen_clusters",
    "Staircase",
    "staircase",
    "SensorSubspaces",
    "sensor_subspaces",
    "screen_positive_definite",
    "stacked_rank",
    "matrix_norm",
    "unit_normalized",
    "balanced_units",
    "state_balancing",
    "Units",
]


class Units(NamedTuple):
    """A plant in exact power-of-two units (``balanced_units``): ``system`` holds
    alpha S^-1 A S and D C S with S = diag(states), D = diag(sensors), powers of two; a state
    direction z of ``system`` is ``states * z`` in the user's coordinates."""

    system: System
    alpha: float
    states: np.ndarray
    sensors: np.ndarray

    def to_user(self, z: np.ndarray) -> np.ndarray:
        """A state direction of the balanced plant in the user's coordinates (unit norm)."""
        out = np.asarray(z, dtype=float) * self.states
        norm = float(np.linalg.norm(out))
        return out / norm if norm > 0 and np.isfinite(norm) else out

    @property
    def balanced(self) -> bool:
        return bool(np.any(self.states != 1.0))


def state_balancing(
    A: np.ndarray, C: np.ndarray, *, spread: float = 16.0, canonical: bool = False
) -> np.ndarray | None:
    """Powers of two s that balance the states of (A, C) (``_state_balancing``), remembered
    for the last plant asked: the checks of one analysis ask for the same plant's several
    times, and a 1,000-sensor plant's balancing costs a few hundredths of a second.

    ``canonical=True`` (the structural decisions) first asks the least-squares scaling of
    the entries' logarithms (``_log_balancing``), which every power-of-two change of units
    maps to the same balanced plant, and uses it when it spreads the states by 2^16 or more;
    otherwise, and without it, LAPACK's balancing as below."""
    global _LAST_BALANCING
    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float).reshape(-1, A.shape[0])
    key = (A.shape, C.shape, A.tobytes(), C.tobytes(), float(spread), canonical)
    last = _LAST_BALANCING  # one read: another thread may replace it meanwhile
    if last is None or last[0] != key:
        last = (key, _state_balancing(A, C, spread=spread, canonical=canonical))
        _LAST_BALANCING = last
    states = last[1]
    return None if states is None else states.copy()


_LAST_BALANCING: tuple[tuple[Any, ...], np.ndarray | None] | None = None


def _state_balancing(
    A: np.ndarray, C: np.ndarray, *, spread: float, canonical: bool
) -> np.ndarray | None:
    """Powers of two s that balance the states of (A, C), or None when they spread less than
    ``spread`` or S^-1 A S and C S would not be exact (an entry under- or overflowing).

    LAPACK's gebal (``scipy.linalg.matrix_balance``) on [[A, 0], [C, 0]].  gebal's norms
    include the diagonal (LAPACK >= 3.5), which a diagonal similarity does not change, and
    the rows of C stay fixed: a state whose column of A holds only its diagonal entry, or
    which one sensor sees, is taken for balanced whatever its units (one state of a plant in
    units 2^50 was, and gebal met another's units halfway); and a state whose row holds only
    a tiny diagonal entry is put in units far from the others' (A = diag(1e-15, 1): 2^-50,
    and two sensors that see both states at once read as one).  So with ``canonical``,
    where the least-squares scaling found the units within 2^16 of each other, gebal's is not
    used beyond that spread either.  The columns of the observability matrix of gebal's
    result are then equilibrated (``_observability_balancing``),
    a further scaling used only beyond a spread of ``EXTREME_SPREAD`` (2^16): moderate units
    change no decision, and plants gebal balances (or leaves alone) keep its coordinates.
    """
    from scipy.linalg import matrix_balance

    from .exact import pow2_scale

    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float).reshape(-1, A.shape[0])
    n, p = A.shape[0], C.shape[0]
    if n < 2:
        return None
    with np.errstate(all="ignore"):
        if not (np.all(np.isfinite(A)) and np.all(np.isfinite(C))):
            return None
        if canonical:
            exponents = _log_balancing(A, C)
            if exponents.max() - exponents.min() >= _EXTREME_EXPONENTS:
                return _exact_or_none(A, C, np.ldexp(1.0, exponents))
        K = np.zeros((n + p, n + p))
        K[:n, :n], K[n:, :n] = A, C
        _, (scale, _) = matrix_balance(K, permute=False, separate=True)
        states = np.asarray(scale[:n], dtype=float)
        if not _spread_beyond(states, spread) or (
            canonical and _spread_beyond(states, EXTREME_SPREAD)
        ):
            states = np.ones(n)
        more = np.ones(n)
        A_g = A * (states[None, :] / states[:, None])
        top = float(np.max(np.abs(A_g))) if A_g.size else 0.0
        alpha = pow2_scale(top) if top > 0 else 1.0
        alpha *= pow2_scale(float(np.linalg.norm(alpha * A_g)))
        for _ in range(_BALANCING_ROUNDS):  # the sensors' units move with the states'
            step = _observability_balancing(
                alpha * A * (states * more)[None, :] / (states * more)[:, None],
                C * (states * more),
            )
            if not _spread_beyond(step, 2.0):
                break
            more = more * step
        if _spread_beyond(more, EXTREME_SPREAD):
            states = states * more
        if not _spread_beyond(states, spread):
            return None
        return _exact_or_none(A, C, states)


def _exact_or_none(A: np.ndarray, C: np.ndarray, states: np.ndarray) -> np.ndarray | None:
    """``states`` when S^-1 A S and C S are exact (no entry under- or overflows), else None."""
    with np.errstate(all="ignore"):
        A_b = A * (states[None, :] / states[:, None])
        C_b = C * states[None, :]
        back = A_b * (states[:, None] / states[None, :])
        if not (np.array_equal(back, A) and np.array_equal(C_b / states[None, :], C)):
            return None
    return states


def anchored_units(A: np.ndarray, inputs: np.ndarray, outputs: np.ndarray) -> np.ndarray | None:
    """Powers of two s for the states of x+ = A x + inputs u, w = outputs x, with u and w in
    fixed units, that bring the entries of S^-1 A S, S^-1 inputs and outputs S closest to 1
    in the least-squares sense of their logarithms (``_anchored_exponents``), when they
    spread the states and the fixed units by 2^16 or more; else None.

    The fixed units anchor the scaling: a model written with its states in units 2^k gets
    the exponents e + k (up to the rounding of the solve), so every power-of-two change of
    state units gives back the same balanced model, its states also placed against the
    channels' units (which a similarity of the states alone, like gebal's, leaves free)."""
    A = np.asarray(A, dtype=float)
    n = A.shape[0]
    inputs = np.asarray(inputs, dtype=float).reshape(n, -1)
    outputs = np.asarray(outputs, dtype=float).reshape(-1, n)
    if n == 0 or not all(np.all(np.isfinite(M)) for M in (A, inputs, outputs)):
        return None
    exponents = _anchored_exponents(A, inputs, outputs)
    anchored = inputs.size + outputs.size > 0
    top = max(int(exponents.max()), 0) if anchored else int(exponents.max())
    low = min(int(exponents.min()), 0) if anchored else int(exponents.min())
    if top - low < _EXTREME_EXPONENTS:
        return None
    return np.ldexp(1.0, exponents)


def _anchored_exponents(A: np.ndarray, inputs: np.ndarray, outputs: np.ndarray) -> np.ndarray:
    """Integer exponents e minimising, over the nonzero entries, the sum of squares of
    log2|A_ij| + e_j - e_i (i != j), log2|inputs_ij| - e_i and log2|outputs_ij| + e_j (the
    inputs and outputs in fixed units).  A group of states linked to no input or output is
    placed with its first state at 0."""
    from scipy.sparse.csgraph import connected_components

    n = A.shape[0]
    off = (A != 0) & ~np.eye(n, dtype=bool)
    W = np.where(off, _log2_abs(A), 0.0)
    M = off.astype(float)
    seen_in, seen_out = inputs != 0, outputs != 0
    W_in = np.where(seen_in, _log2_abs(inputs), 0.0)
    W_out = np.where(seen_out, _log2_abs(outputs), 0.0)
    anchors = seen_in.sum(axis=1) + seen_out.sum(axis=0)
    links = M + M.T
    N = np.diag(links.sum(axis=1) + anchors) - links
    rhs = W.sum(axis=1) - W.sum(axis=0) + W_in.sum(axis=1) - W_out.sum(axis=0)
    graph = np.zeros((n + 1, n + 1))  # node n: the fixed units
    graph[:n, :n] = links
    graph[:n, n] = graph[n, :n] = anchors
    _, labels = connected_components(graph != 0, directed=False)
    free = np.ones(n, dtype=bool)
    for label in np.unique(labels[:n]):
        if label != labels[n]:
            free[np.flatnonzero(labels[:n] == label)[0]] = False
    return _rounded_solution(N, rhs, free)[:n]


def _log_balancing(A: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Integer exponents e, the states' units 2^e that make the entries of S^-1 A S and
    D C S closest to their matrix's own scale in the least-squares sense of their logarithms
    (Curtis and Reid's scaling): every nonzero entry of A, its diagonal included, against
    one scale alpha of A, and each sensor's row of C in its own units D.

    The normal equations are solved with the sensors' unknowns eliminated exactly (a sensor
    is linked to states only); in each connected part of the plant the first state's
    exponent is taken as 0 before rounding.  The answer moves with the data: a plant written
    with its states in units 2^k gets e + k (up to the rounding of the solve), so every
    power-of-two change of state units, sensor units or of A's scale gives back the same
    balanced plant, which LAPACK's gebal (an iteration from the data's own units) does not.
    """
    from scipy.sparse.csgraph import connected_components

    n = A.shape[0]
    nonzero = A != 0
    off = nonzero & ~np.eye(n, dtype=bool)
    seen = C != 0
    W_A = np.where(nonzero, _log2_abs(A), 0.0)
    W_off = np.where(off, W_A, 0.0)
    W_C = np.where(seen, _log2_abs(C), 0.0)
    M_off, M_C = off.astype(float), seen.astype(float)
    degree = M_C.sum(axis=1)
    used = degree > 0
    M_C, W_C, degree = M_C[used], W_C[used], degree[used]
    # normal equations of min sum over A of (w + alpha + x_col - x_row)^2 and over C of
    # (w + x_col - g_row)^2, unknowns [x, alpha]: the sensors' g eliminated
    links = M_off + M_off.T
    N = np.zeros((n + 1, n + 1))
    N[:n, :n] = np.diag(links.sum(axis=1) + M_C.sum(axis=0)) - links
    N[:n, :n] -= (M_C.T / degree[None, :]) @ M_C
    N[:n, n] = N[n, :n] = M_off.sum(axis=0) - M_off.sum(axis=1)
    N[n, n] = float(np.count_nonzero(nonzero))
    rhs = np.empty(n + 1)
    rhs[:n] = W_off.sum(axis=1) - W_off.sum(axis=0) - W_C.sum(axis=0)
    rhs[:n] += M_C.T @ (W_C.sum(axis=1) / degree)
    rhs[n] = -W_A.sum()
    parts, labels = connected_components((links + M_C.T @ M_C) != 0, directed=False)
    free = np.ones(n + 1, dtype=bool)
    free[np.unique(labels, return_index=True)[1]] = False  # each part's first state
    free[n] = N[n, n] > 0
    return _rounded_solution(N, rhs, free)[:n]


def _rounded_solution(N: np.ndarray, rhs: np.ndarray, free: np.ndarray) -> np.ndarray:
    """The normal equations N x = rhs solved for the ``free`` unknowns (the others 0), each
    rounded to the nearest integer (all 0 when the solve is not finite)."""
    x = np.zeros(rhs.size)
    if np.any(free):
        block, target = N[np.ix_(free, free)], rhs[free]
        try:
            x[free] = np.linalg.solve(block, target)
        except np.linalg.LinAlgError:
            x[free] = np.linalg.lstsq(block, target, rcond=None)[0]
    exponents = np.floor(x + 0.5)
    if not np.all(np.isfinite(exponents)):
        return np.zeros(rhs.size, dtype=int)
    return exponents.astype(int)


def _log2_abs(M: np.ndarray) -> np.ndarray:
    """log2 |M| entrywise (0 where M is 0), the exponent kept exact (frexp)."""
    mantissa, exponent = np.frexp(np.abs(M))
    with np.errstate(divide="ignore"):
        return np.where(M != 0, exponent + np.log2(np.where(M != 0, mantissa, 1.0)), 0.0)


#: the observability matrix's column scaling is used beyond this spread only
EXTREME_SPREAD = 2.0**16
_EXTREME_EXPONENTS = 16
_BALANCING_ROUNDS = 8
# flops spent on the observability blocks of the balancing
_BALANCING_WORK = 2e7


def _spread_beyond(states: np.ndarray, spread: float) -> bool:
    """Whether powers of two ``states`` (all finite) spread at least ``spread``."""
    with np.errstate(all="ignore"):
        exponents = np.log2(states)
    return bool(
        np.all(np.isfinite(exponents))
        and np.array_equal(exponents, np.round(exponents))
        and states.max() >= spread * states.min()
    )


def _observability_balancing(A: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Powers of two that equilibrate the columns of the observability matrix [C; C A; ...]
    (the matrix the structural decisions rest on), with each sensor's row in its own
    power-of-two units (a sensor's rows in every block share its units).  The caller gives A
    in fixed power-of-two units (Frobenius norm in [1, 2) before any state scaling): the
    blocks' weights then do not move with the states, and O S is the observability matrix
    of the scaled plant.  A state in units 2^50 has a column 2^50 times its neighbours'
    throughout; a coupling inside A that is large or small against the diagonal does not
    move the columns apart."""
    from .exact import pow2_row_scaling

    n, p = A.shape[0], C.shape[0]
    if p == 0 or not np.all(np.isfinite(A)):
        return np.ones(n)
    block = pow2_row_scaling(C)[:, None] * C
    squares = np.sum(block * block, axis=0)
    for _ in range(1, min(n, max(1, int(_BALANCING_WORK // max(p * n * n, 1))))):
        block = block @ A
        squares = squares + np.sum(block * block, axis=0)
    if not np.all(np.isfinite(squares)):
        return np.ones(n)
    return pow2_row_scaling(np.sqrt(squares)[:, None])  # each column's power of two


def balanced_units(system: System, *, spread: float = 16.0) -> Units:
    """The plant in exact power-of-two units, its states balanced too.

    ``unit_normalized`` scales A by a power of two and each sensor's row by its own; here the
    states are also rescaled, x = S x_b with S = diag(s) powers of two, when their spread
    exceeds ``spread``: the least-squares scaling of the entries' logarithms where it spreads
    the states by 2^16 or more (units far apart: every power-of-two change of units gives the
    same balanced plant), else LAPACK's balancing (gebal, ``scipy.linalg.matrix_balance``) of
    [[A, 0], [C, 0]] (``state_balancing``).  Observability, sparse observability and every
    breaking set are unchanged by a change of state coordinates, and powers of two change no
    rounding, so a plant written with one state in units 2^30 times smaller gets the
    decisions of the plant in its own units.  The rows of C are renormalised after the state
    scaling.
    """
    from .exact import pow2_row_scaling

    work, alpha = unit_normalized(system)
    n = system.n
    plain = Units(work, alpha, np.ones(n), pow2_row_scaling(system.C))
    A, C = system.A, plain.sensors[:, None] * system.C
    states = state_balancing(A, C, spread=spread, canonical=True)
    if states is None:
        return plain
    with np.errstate(all="ignore"):
        A_b = A * (states[None, :] / states[:, None])
        C_b = C * states[None, :]
        balanced, alpha_b = unit_normalized(System(A_b, C_b))
        rows = pow2_row_scaling(C_b)
        sensors = plain.sensors * rows
    if not np.all((sensors > 0) & (sensors < np.inf) & (sensors >= np.finfo(float).tiny)):
        return plain  # a sensor's units would leave the float range: no state balancing
    return Units(
        System(balanced.A, balanced.C, sensors=system.sensors, name=system.name),
        alpha_b,
        states,
        sensors,
    )


def unit_normalized(system: System) -> tuple[System, float]:
    """The plant in exact power-of-two units: alpha A and D C, with alpha and D powers of two.

    Observability and every sensor-wise question are unchanged by scaling A
    by a nonzero constant and each sensor's row by its own: the Krylov
    subspaces of all sensor sets are the same.  Powers of two change no
    rounding, so the decisions are exactly those of the user's data, but no
    sensor's units (1e-8 or 1e8) and no overall scale (entries near the
    float range) can tip a rank threshold.  Returns the scaled plant and
    alpha (eigenvalues of the scaled A are alpha times those of A).
    """
    from .exact import pow2_row_scaling, pow2_scale

    A, C = system.A, system.C
    with np.errstate(over="ignore"):
        top = float(np.max(np.abs(A))) if A.size else 0.0
    alpha = pow2_scale(top) if top > 0 else 1.0
    D = pow2_row_scaling(C)
    if alpha == 1.0 and np.all(D == 1.0):
        return system, 1.0
    return System(alpha * A, D[:, None] * C, sensors=system.sensors, name=system.name), alpha


def matrix_norm(M: np.ndarray) -> float:
    """Spectral norm, 0 for an empty matrix, infinite when an entry is not finite (no SVD of
    a NaN)."""
    if M.size == 0:
        return 0.0
    if not np.all(np.isfinite(M)):
        return math.inf
    return float(np.linalg.norm(M, 2))


# ---------------------------------------------------------------------------
# observability staircase


def _classify_krylov(
    values: np.ndarray,
    scale: float | np.ndarray,
    rtol: float,
    err_pess: float | np.ndarray,
    err_step: float | np.ndarray,
    factor: float,
) -> np.ndarray:
    """Zero / borderline / nonzero for Krylov residuals with amplified errors.

    A residual that is zero in exact arithmetic appears at the size of the
    accumulated basis error.  The zero threshold uses the pessimistic,
    compounded estimate ``err_pess`` (so an exact zero is never taken for a
    direction, which would overstate observability); the borderline band
    above it reaches ``factor`` times the single-step estimate ``err_step``
    and at least twice the zero threshold.
    """
    zero = np.asarray(scale) * (rtol + np.asarray(err_pess))
    upper = np.maximum(factor * np.asarray(scale) * (rtol + np.asarray(err_step)), 2.0 * zero)
    values = np.asarray(values, dtype=float)
    codes = np.full(np.broadcast(values, zero).shape, NONZERO, dtype=np.int8)
    codes[values <= upper] = BORDERLINE
    codes[values <= zero] = ZERO
    return codes


@dataclass(frozen=True)
class Staircase:
    """Orthogonal observability staircase of (A, C).

    Attributes
    ----------
    basis : ndarray, shape (r, n)
        Orthonormal rows spanning the observable row space (span of C A^k).
    block_sizes : tuple of int
        Rank added at each step; their count is the observability index
        when ``r == n``.
    step_margins : tuple of float
        Smallest kept singular value at each step, relative to its scale
        (``||C||`` at step 0, ``||A||`` later).
    problem : str
        Empty unless a rank decision was borderline.
    """

    basis: np.ndarray
    block_sizes: tuple[int, ...]
    step_margins: tuple[float, ...]
    problem: str = ""

    @property
    def rank(self) -> int:
        return int(self.basis.shape[0])

    @property
    def index(self) -> int:
        """Number of steps taken (the observability index when observable)."""
        return len(self.block_sizes)

    def unobservable_direction(self) -> np.ndarray | None:
        """A unit vector orthogonal to the observable row space, or None."""
        n = self.basis.shape[1]
        if self.rank >= n:
            return None
        if self.rank == 0:
            z = np.zeros(n)
            z[0] = 1.0
            return z
        _, _, vh = np.linalg.svd(self.basis)
        return vh[-1]


def _orthogonalize(W: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """Rows of W minus their projection on the orthonormal rows of basis (twice)."""
    if basis.shape[0] == 0:
        return W
    for _ in range(2):
        W = W - (W @ basis.T) @ basis
    return W


def staircase(
    A: np.ndarray,
    C: np.ndarray,
    *,
    max_steps: int | None = None,
    tolerances: Tolerances | None = None,
    error_model: str = "linear",
) -> Staircase:
    """Observable row space of (A, C) by orthogonal block Krylov steps.

    Each step multiplies the newly found orthonormal rows by A, removes
    their component in the rows already found (twice, for stability) and
    keeps the singular directions above the rank threshold.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    C : ndarray, shape (p, n)
    max_steps : int, optional
        Stop after this many steps (default n): the row space of the first
        ``max_steps`` blocks is that of O_tau with tau = max_steps.
    tolerances : Tolerances, optional
    error_model : {"linear", "compound"}, default "linear"
        How rounding errors accumulate in the zero threshold of later steps.
        ``"compound"`` multiplies the amplification of every normalisation
        (pessimistic: a residual that is zero in exact arithmetic is never
        taken for a new direction, even for strongly non-normal A, but long
        chains of small residuals become borderline); ``"linear"`` adds the
        single-step amplifications (tight for well-conditioned A; pair it
        with an independent check such as the PBH test).

    Returns
    -------
    Staircase
    """
    tol = tolerances or Tolerances()
    if error_model not in ("linear", "compound"):
        raise ValueError(f"error_model must be 'linear' or 'compound', got {error_model!r}")
    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float)
    n = A.shape[0]
    steps = n if max_steps is None else max_steps
    normA = max(matrix_norm(A), np.finfo(float).tiny)
    normC = matrix_norm(C)
    basis = np.zeros((0, n))
    blocks: list[int] = []
    margins: list[float] = []
    problem = ""
    if normC == 0.0:
        return Staircase(basis, (), (), "")
    W = C / normC
    scale = 1.0
    # err estimates how far the computed basis is from the exact Krylov
    # subspace: each normalisation by a small residual amplifies earlier
    # rounding errors, and a residual that is exactly zero in exact
    # arithmetic shows up at size scale * err, not scale * eps.
    rtol0 = tol.rtol(n, C.shape[0])
    err, err_step = 0.0, 0.0
    for step in range(steps):
        W = _orthogonalize(W, basis)
        if W.shape[0] == 0:
            break
        _, s, vh = np.linalg.svd(W, full_matrices=False)
        codes = _classify_krylov(s, scale, tol.rtol(*W.shape), err, err_step, tol.borderline_factor)
        thr = scale * (tol.rtol(*W.shape) + err)
        if np.any(codes == BORDERLINE) and not problem:
            problem = (
                f"staircase step {step}: singular value {s[codes == BORDERLINE].min():.2e} is "
                f"within the borderline band above the rank threshold {thr:.2e}"
            )
        r = int(np.count_nonzero(codes == NONZERO))
        if r == 0:
            break
        new = _orthogonalize(vh[:r], basis)
        new, _ = np.linalg.qr(new.T)
        new = new.T
        basis = np.vstack([basis, new])
        blocks.append(r)
        margins.append(float(s[r - 1] / scale))
        step_amp = scale * rtol0 / float(s[r - 1])
        if error_model == "compound":
            err = max(err, scale * (err + rtol0) / float(s[r - 1]))
        else:
            err = err + step_amp
        err_step = max(err_step, step_amp)
        if basis.shape[0] >= n:
            break
        W = new @ A
        scale = normA
    return Staircase(basis, tuple(blocks), tuple(margins), problem)


@dataclass(frozen=True)
class SensorSubspaces:
    """Observable row space of (A, c_i) for every sensor i.

    Attributes
    ----------
    bases : ndarray, shape (p, n, n)
        ``bases[i, :ranks[i]]`` are orthonormal rows spanning sensor i's
        observable row space; the other rows are zero.
    ranks : ndarray of int, shape (p,)
    borderline : ndarray of bool, shape (p,)
        Sensors whose rank decision was borderline.
    margins : ndarray, shape (p,)
        Smallest relative Krylov residual kept for each sensor.
    errors : ndarray, shape (p,)
        Estimated distance of each computed basis from the exact subspace
        (rounding amplified by the Krylov normalisations).
    """

    bases: np.ndarray
    ranks: np.ndarray
    borderline: np.ndarray
    margins: np.ndarray
    errors: np.ndarray

    def projectors(self) -> np.ndarray:
        """Orthogonal projectors Q_i^T Q_i onto the sensors' row spaces, (p, n, n)."""
        return np.einsum("pkn,pkm->pnm", self.bases, self.bases)


def sensor_subspaces(
    A: np.ndarray, C: np.ndarray, *, tolerances: Tolerances | None = None
) -> SensorSubspaces:
    """Krylov (Arnoldi) basis of each sensor's observable row space, vectorised.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    C : ndarray, shape (p, n)
    tolerances : Tolerances, optional

    Returns
    -------
    SensorSubspaces
    """
    tol = tolerances or Tolerances()
    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float)
    p, n = C.shape
    normA = max(matrix_norm(A), np.finfo(float).tiny)
    bases = np.zeros((p, n, n))
    ranks = np.zeros(p, dtype=np.int64)
    borderline = np.zeros(p, dtype=bool)
    margins = np.full(p, np.inf)
    row_norms = np.linalg.norm(C, axis=1)
    scale_C = max(float(row_norms.max()), np.finfo(float).tiny)
    codes = classify(row_norms, tol.rtol(p, n) * scale_C, factor=tol.borderline_factor)
    borderline |= codes == BORDERLINE
    active = codes == NONZERO
    bases[active, 0] = C[active] / row_norms[active, None]
    ranks[active] = 1
    margins[active] = row_norms[active] / scale_C
    rtol0 = tol.rtol(n)
    err = np.zeros(p)  # basis error estimates, as in ``staircase``
    err_step = np.zeros(p)
    for k in range(1, n):
        idx = np.nonzero(active)[0]
        if idx.size == 0:
            break
        Q = bases[idx, :k]
        w = bases[idx, k - 1] @ A
        for _ in range(2):
            w = w - np.einsum("ik,ikn->in", np.einsum("ikn,in->ik", Q, w), Q)
        nrm = np.linalg.norm(w, axis=1)
        codes = _classify_krylov(nrm, normA, rtol0, err[idx], err_step[idx], tol.borderline_factor)
        borderline[idx[codes == BORDERLINE]] = True
        keep = codes == NONZERO
        active[idx[~keep]] = False
        kept = idx[keep]
        bases[kept, k] = w[keep] / nrm[keep, None]
        ranks[kept] += 1
        margins[kept] = np.minimum(margins[kept], nrm[keep] / normA)
        err[kept] = np.maximum(err[kept], normA * (err[kept] + rtol0) / nrm[keep])
        err_step[kept] = np.maximum(err_step[kept], normA * rtol0 / nrm[keep])
    return SensorSubspaces(bases, ranks, borderline, margins, err)


# ---------------------------------------------------------------------------
# batched decisions


_U32 = 2.0**-24  # unit roundoff of single precision
_U64 = 2.0**-53


def cholesky_or_nan(mats: np.ndarray) -> np.ndarray:
    """``numpy.linalg.cholesky`` of each matrix, NaN for the matrices that have none.

    The factors are those of ``numpy.linalg.cholesky`` (LAPACK's, one
    matrix at a time), bit for bit; a batch that holds a matrix without a
    factorization is split in halves down to ``_ONE_BY_ONE`` matrices, then factored one by
    one, so a few failures cost a few more calls and a batch of failures one call each.

    Parameters
    ----------
    mats : ndarray, shape (N, n, n)
        Symmetric float64 matrices (only the lower triangle is read).

    Returns
    -------
    ndarray, shape (N, n, n)
        Lower Cholesky factors; all NaN where the factorization fails.
    """
    out = np.full(mats.shape, np.nan)
    pending = [(0, mats.shape[0])] if mats.shape[0] else []
    while pending:
        lo, hi = pending.pop()
        try:
            out[lo:hi] = np.linalg.cholesky(mats[lo:hi])
        except np.linalg.LinAlgError:
            if hi - lo <= _ONE_BY_ONE:
                # a small batch with a failure: one call per matrix (where most fail, as on a
                # breaking level, halving down to single matrices costs N log N factorizations)
                for i in range(lo, hi):
                    try:
                        out[i] = np.linalg.cholesky(mats[i])
                    except np.linalg.LinAlgError:
                        pass
            else:
                mid = (lo + hi) // 2
                pending += [(mid, hi), (lo, mid)]
    return out


_ONE_BY_ONE = 32  # batches with a failure at most this large are factored matrix by matrix


def cholesky_batch_last(work: np.ndarray, diagonal: np.ndarray) -> None:
    """Cholesky factorization of a batch of matrices stored with the batch last, in place.

    Column by column (left-looking), every operation runs over the whole
    batch, so that numpy vectorizes over the contiguous last axis instead
    of calling LAPACK once per small matrix.  A matrix that is not positive
    definite gets a NaN or non-positive entry in ``diagonal`` (and NaN in
    the later columns); the others are unaffected.

    Parameters
    ----------
    work : ndarray, shape (n, n, N)
        The matrices ``work[:, :, b]``; their lower triangles are read and
        overwritten with the strictly lower part of the factors (the upper
        triangles are left as they are).
    diagonal : ndarray, shape (n, N)
        Receives the diagonal of each factor.
    """
    n = work.shape[0]
    with np.errstate(invalid="ignore", divide="ignore", over="ignore", under="ignore"):
        for j in range(n):
            column = work[j:, j]
            if j:
                column -= np.einsum("ikb,kb->ib", work[j:, :j], work[j, :j])
            root = np.sqrt(column[0], out=diagonal[j])
            if j + 1 < n:
                column[1:] *= np.divide(1.0, root)


def single_precision_margin(
    n: int, trace: float | np.ndarray, frobenius: float | np.ndarray, terms: int = 0
) -> float | np.ndarray:
    """Shift that makes a single-precision Cholesky screening conclusive for LAPACK's.

    Let A be an n x n float64 matrix with ``sum(max(A_jj, 0)) <= trace``
    and Frobenius norm at most ``frobenius``, and tau the margin returned.
    When ``cholesky_batch_last`` factors A - tau I rounded to single
    precision (tau subtracted in either precision, and the matrix summed in
    single precision from at most ``terms + 1`` terms whose absolute values
    add up to at most ``frobenius`` in Frobenius norm) with positive finite
    pivots, the computed factor L32 is the exact factor of A + D with
    -3 tau / 2 I <= D <= -tau / 2 I: the rounding of the matrix and the
    backward error of the factorization (``gamma(n + 3) trace``, Higham,
    Accuracy and Stability of Numerical Algorithms, Thm 10.3) are at most
    tau / 2 in norm.  LAPACK's factor of A is the exact factor of A + E with
    ``||E|| <= gamma(4 n + 4) trace``, far below tau / 2, so A + E >= A + D
    in the Loewner order; Cholesky pivots grow with the matrix in that
    order.  Hence (whatever the conditioning of A) LAPACK's factorization
    of A succeeds and each of its diagonal entries is at least the
    corresponding entry of L32.

    Parameters
    ----------
    n : int
    trace : float or ndarray
        Upper bound of the sum of the positive diagonal entries.
    frobenius : float or ndarray
        Upper bound of the Frobenius norm (of the sum of the absolute values
        of the terms, when the single-precision matrix is a sum).
    terms : int, default 0
        Single-precision additions behind each entry.

    Returns
    -------
    float or ndarray
        The margin tau (positive).
    """
    g32 = (n + 3) * _U32 / (1 - (n + 3) * _U32)
    g64 = (4 * n + 4) * _U64 / (1 - (4 * n + 4) * _U64)
    # both factorizations' backward errors (LAPACK's bound taken 100 times over), and every
    # rounding of the single-precision matrix, (3 + terms) u32 ||A||_F, with room for tau's own
    error = (1.01 * trace + (4 + terms) * _U32 * frobenius) * (1.5 * g32 + 100 * g64)
    error = error + (3.1 + 1.01 * terms) * _U32 * frobenius
    return 2.0 * error / (1 - 8 * n * _U32) + 1e-30


def screen_positive_definite(mats: np.ndarray, shift: float | np.ndarray) -> np.ndarray:
    """True where ``mats - shift I`` has a Cholesky factorization.

    Batched and exception-free: a matrix that is not positive definite
    gives False for that matrix only.  The answer is LAPACK's (that of
    ``numpy.linalg.cholesky``): every matrix is first factored in single
    precision with the margin of ``single_precision_margin``, which proves
    LAPACK's success where it succeeds; the others are factored by LAPACK.

    Parameters
    ----------
    mats : ndarray, shape (N, n, n)
        Symmetric matrices (only the lower triangle is read).
    shift : float or ndarray of shape (N,)

    Returns
    -------
    ndarray of bool, shape (N,)
    """
    n = mats.shape[-1]
    shifted = mats - np.asarray(shift)[..., None, None] * np.eye(n)
    if shifted.shape[0] == 0 or n == 0:
        return np.ones(shifted.shape[0], dtype=bool)
    ok = single_screen(shifted)[0]
    unsure = np.flatnonzero(~ok)
    if unsure.size:
        L = cholesky_or_nan(shifted[unsure])
        ok[unsure] = np.isfinite(L[:, -1, -1]) & np.isfinite(L[:, 0, 0])
    return ok


def single_screen(shifted: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The single-precision screening of ``screen_positive_definite`` (margins per matrix).

    Parameters
    ----------
    shifted : ndarray, shape (N, n, n)
        Symmetric float64 matrices (only the lower triangle is read).

    Returns
    -------
    passed : ndarray of bool, shape (N,)
        Where LAPACK's factorization is proved to succeed.
    smallest : ndarray of float32, shape (N,)
        Smallest diagonal entry of the single-precision factor (a lower
        bound of LAPACK's smallest one where ``passed``).
    """
    N, n, _ = shifted.shape
    with np.errstate(over="ignore", invalid="ignore"):
        trace = np.maximum(np.diagonal(shifted, axis1=1, axis2=2), 0.0).sum(axis=1)
        margin = np.asarray(single_precision_margin(n, trace, np.linalg.norm(shifted, axis=(1, 2))))
        work = np.ascontiguousarray(shifted.transpose(1, 2, 0), dtype=np.float32)
        # rounded up, so that at least the margin is taken off
        work[np.arange(n), np.arange(n)] -= np.nextafter(
            margin.astype(np.float32), np.float32(np.inf)
        )
    diagonal = np.empty((n, N), dtype=np.float32)
    cholesky_batch_last(work, diagonal)
    return single_passed(diagonal)


def single_passed(diagonal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Whether each single-precision factorization succeeded, and its smallest diagonal entry.

    Parameters
    ----------
    diagonal : ndarray, shape (n, N)
        Diagonals written by ``cholesky_batch_last``.

    Returns
    -------
    passed : ndarray of bool, shape (N,)
        Every diagonal entry positive and finite.
    smallest : ndarray, shape (N,)
    """
    smallest = diagonal.min(axis=0)
    with np.errstate(over="ignore", invalid="ignore"):
        return (smallest > 0) & np.isfinite(diagonal.sum(axis=0)), smallest


def stacked_rank(
    stacks: np.ndarray,
    *,
    tolerances: Tolerances | None = None,
    rows: int | None = None,
    data_error: np.ndarray | float = 0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Full-column-rank decision for a batch of stacked matrices by SVD.

    Parameters
    ----------
    stacks : ndarray, shape (N, m, n)
        Zero padding rows are allowed: they change no singular value.
    tolerances : Tolerances, optional
    rows : int, optional
        Number of meaningful rows for the default tolerance (default m).
    data_error : float or ndarray of shape (N,), default 0
        Relative error already present in the stacked rows, added to the
        rank tolerance.

    Returns
    -------
    codes : ndarray of int8, shape (N,)
        ZERO (rank deficient), BORDERLINE or NONZERO (full column rank) for
        the smallest singular value.
    smallest : ndarray, shape (N,)
        Smallest singular value relative to the largest.
    null_vectors : ndarray, shape (N, n)
        Right singular vector of the smallest singular value.
    """
    tol = tolerances or Tolerances()
    N, m, n = stacks.shape
    if m < n:
        stacks = np.concatenate([stacks, np.zeros((N, n - m, n))], axis=1)
    _, s, vh = np.linalg.svd(stacks, full_matrices=False)
    smax = np.maximum(s[:, 0], np.finfo(float).tiny)
    rel = s[:, n - 1] / smax
    codes = classify(
        rel, tol.rtol(rows or m, n) + np.asarray(data_error), factor=tol.borderline_factor
    )
    return codes, rel, vh[:, n - 1, :]
