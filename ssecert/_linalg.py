"""Numerical building blocks of the structural analyses.

* ``eigen_clusters``: eigenvalues grouped into clusters with their
  eigenspaces, grouping decided from condition numbers and a defect-aware
  radius, every doubtful grouping reported instead of guessed;
* ``staircase``: orthogonal observability staircase (block Arnoldi on the
  rows of C), the reliable way to get the observable subspace and the
  observability index (the rank of the stacked observability matrix is not);
* ``sensor_subspaces``: the same for every sensor alone, vectorised;
* ``screen_positive_definite``: batched Cholesky test that never raises;
* ``stacked_rank``: exact rank decisions of many small stacks by SVD.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from .system import System
from .tolerances import BORDERLINE, EPS, NONZERO, ZERO, Tolerances, classify

try:  # the gufunc behind numpy.linalg.cholesky: NaN instead of an exception
    from numpy.linalg import _umath_linalg as _ul

    _CHOLESKY: np.ufunc | None = _ul.cholesky_lo
except (ImportError, AttributeError):  # pragma: no cover - depends on numpy build
    _CHOLESKY = None

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
]


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
    from ._exact import pow2_row_scaling, pow2_scale

    A, C = system.A, system.C
    with np.errstate(over="ignore"):
        top = float(np.max(np.abs(A))) if A.size else 0.0
    alpha = pow2_scale(top) if top > 0 else 1.0
    D = pow2_row_scaling(C)
    if alpha == 1.0 and np.all(D == 1.0):
        return system, 1.0
    return System(alpha * A, D[:, None] * C, sensors=system.sensors, name=system.name), alpha


def matrix_norm(M: np.ndarray) -> float:
    """Spectral norm, or 0 for an empty matrix."""
    if M.size == 0:
        return 0.0
    return float(np.linalg.norm(M, 2))


# ---------------------------------------------------------------------------
# eigenvalue clusters


@dataclass(frozen=True)
class EigenCluster:
    """A group of computed eigenvalues treated as one eigenvalue.

    Attributes
    ----------
    center : complex
        Mean of the group (real when the group is closed under conjugation).
    members : tuple of int
        Indices into ``EigenAnalysis.eigenvalues``.
    geometric : int
        Dimension of the eigenspace (numerical null space of A - center I).
    basis : ndarray, shape (n, geometric)
        Orthonormal basis of the eigenspace; real when ``center`` is real.
    error : float
        Estimated angle between ``basis`` and the exact eigenspace.
    conjugate_pair : bool
        True when the group stands for itself and its complex conjugate.
    problem : str
        Empty when the group is sound; otherwise why it is not.
    """

    center: complex
    members: tuple[int, ...]
    geometric: int
    basis: np.ndarray
    error: float
    conjugate_pair: bool
    problem: str = ""

    @property
    def algebraic(self) -> int:
        """Number of computed eigenvalues in the group."""
        return len(self.members)

    @property
    def is_real(self) -> bool:
        return not self.conjugate_pair


@dataclass(frozen=True)
class EigenAnalysis:
    """Eigenvalues of A grouped into clusters (one per conjugate pair)."""

    eigenvalues: np.ndarray
    clusters: tuple[EigenCluster, ...]
    norm: float
    condition: np.ndarray
    threshold: float
    problems: tuple[str, ...] = field(default=())
    unit: float = 1.0

    @property
    def ok(self) -> bool:
        return not self.problems

    def label(self, value: complex) -> str:
        """An eigenvalue of this (possibly rescaled) A as the caller's A has it, for messages."""
        return _eigenvalue_label(value, self.unit)


def _eigenvalue_label(value: complex, unit: float = 1.0) -> str:
    """``value / unit`` for messages: a real number when it is real."""
    v = complex(value) / unit
    return f"{v.real:.6g}" if v.imag == 0 else f"{v:.6g}"


def _eigen_condition(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues and their condition numbers 1 / |y^H x| (unit x, y)."""
    w, vl, vr = scipy.linalg.eig(A, left=True, right=True)
    vl = vl / np.linalg.norm(vl, axis=0)
    vr = vr / np.linalg.norm(vr, axis=0)
    dots = np.abs(np.sum(vl.conj() * vr, axis=0))
    with np.errstate(divide="ignore"):
        kappa = np.where(dots > 0, 1.0 / np.maximum(dots, np.finfo(float).tiny), np.inf)
    return w, kappa


def _compatible(dist: np.ndarray, delta: np.ndarray, tight: float) -> bool:
    """Whether the pairs i, j with |lambda_i - lambda_j| <= 2 (delta_i + delta_j) (or equal to
    rounding) connect every member of a group."""
    m = dist.shape[0]
    link = (dist <= 2.0 * (delta[:, None] + delta[None, :])) | (dist <= tight)
    seen = {0}
    frontier = [0]
    while frontier:
        i = frontier.pop()
        for j in np.flatnonzero(link[i]):
            if int(j) not in seen:
                seen.add(int(j))
                frontier.append(int(j))
    return len(seen) == m


@dataclass(frozen=True)
class _Spectrum:
    """What the grouping and eigenspace steps share: A, its eigenvalues and their bounds."""

    A: np.ndarray
    lam: np.ndarray
    kappa: np.ndarray
    delta: np.ndarray  # first-order error bounds n eps ||A|| kappa, at most ||A||
    norm: float
    threshold: float  # rank threshold of A - lambda I
    tol: Tolerances


def eigen_clusters(
    A: np.ndarray, *, tolerances: Tolerances | None = None, unit: float = 1.0
) -> EigenAnalysis:
    """Group the eigenvalues of ``A`` and compute each group's eigenspace.

    Two computed eigenvalues are grouped when their distance is below the
    larger of (i) their first-order error bounds ``n eps ||A|| kappa``
    (``kappa`` the eigenvalue condition number, huge for the perturbed
    copies of a defective eigenvalue) and (ii) the spread a defective
    eigenvalue of the group's size shows in floating point,
    ``||A|| (n cluster_rtol)^(1/m)``.  Each group's eigenspace is the
    numerical null space of ``A - center I``.  A group is reported as a
    problem (and analyses that need it become inconclusive) when the null
    space is empty or borderline, larger than the group, or when a single
    eigenvalue is so ill-conditioned that it may be a defective one that was
    not recognised.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    tolerances : Tolerances, optional
    unit : float, default 1.0
        The factor by which ``A`` was scaled from the caller's matrix: messages
        give eigenvalues divided by it.

    Returns
    -------
    EigenAnalysis
    """
    spectrum = _spectrum(A, tolerances or Tolerances())
    labels = _group_labels(spectrum)
    groups = [np.nonzero(labels == g)[0] for g in np.unique(labels)]
    group_of = {int(i): gi for gi, members in enumerate(groups) for i in members}
    clusters: list[EigenCluster] = []
    for gi, members in enumerate(groups):
        self_conjugate = _closed_under_conjugation(spectrum.lam, members, gi, group_of)
        center = complex(spectrum.lam[members].mean())
        if self_conjugate:
            center = complex(center.real, 0.0)
        elif center.imag < 0:
            continue  # represented by its conjugate group
        clusters.append(_eigen_cluster(spectrum, members, center, self_conjugate, unit))
    return EigenAnalysis(
        eigenvalues=spectrum.lam,
        clusters=tuple(clusters),
        norm=spectrum.norm,
        condition=spectrum.kappa,
        threshold=spectrum.threshold,
        problems=tuple(c.problem for c in clusters if c.problem),
        unit=unit,
    )


def _spectrum(A: np.ndarray, tol: Tolerances) -> _Spectrum:
    """The eigenvalues of A with their condition numbers, error bounds and rank threshold."""
    A = np.asarray(A, dtype=float)
    n = A.shape[0]
    norm = max(matrix_norm(A), np.finfo(float).tiny)
    lam, kappa = _eigen_condition(A)
    delta = np.minimum(n * EPS * norm * kappa, norm)
    return _Spectrum(A, lam, kappa, delta, norm, 10 * tol.rtol(n) * norm, tol)


def _group_labels(sp: _Spectrum) -> np.ndarray:
    """A group label for every eigenvalue, by validated level-wise single linkage.

    Edges are added by increasing distance; the connected component an edge
    closes is accepted as one eigenvalue when its diameter is within the
    spread a defective eigenvalue of that size can show, ||A|| (n * 1e4 *
    cluster_rtol)^(1/m), and either all its members are equal to rounding or
    A - mu I is singular at its mean.  Components that fail stay split; a
    later, larger component can pass (a Jordan block's perturbed eigenvalues
    only average out when all are in), and every acceptance is validated, so
    no radius alone merges distinct eigenvalues.
    """
    n = sp.lam.shape[0]
    labels = np.arange(n)
    dist = np.abs(sp.lam[:, None] - sp.lam[None, :])
    tight = n * sp.tol.cluster_rtol * sp.norm
    wide = n * 1e4 * sp.tol.cluster_rtol
    parent = list(range(n))
    members_of = {i: [i] for i in range(n)}
    for i, j in _linkage_edges(dist, sp.norm * wide ** (1.0 / n)):
        ri, rj = _find_root(parent, i), _find_root(parent, j)
        if ri == rj:
            # the component is unchanged, and its test ran when it last grew: the decision
            # depends on its members only (re-testing made this O(n^4) on dense plants)
            continue
        parent[rj] = ri
        members_of[ri] = members_of[ri] + members_of.pop(rj)
        comp = members_of[ri]
        if len(set(labels[comp].tolist())) == 1:
            continue
        if _one_eigenvalue(sp, comp, dist, tight, wide):
            labels[comp] = labels[comp[0]]
    return labels


def _linkage_edges(dist: np.ndarray, reach: float) -> list[tuple[int, int]]:
    """The pairs i < j within ``reach`` of each other, by increasing distance."""
    ii, jj = np.triu_indices(dist.shape[0], 1)
    keep = dist[ii, jj] <= reach
    ii, jj = ii[keep], jj[keep]
    order = np.argsort(dist[ii, jj], kind="stable")
    return [(int(ii[e]), int(jj[e])) for e in order]


def _find_root(parent: list[int], x: int) -> int:
    """The root of ``x`` in the union-find forest ``parent`` (halving the path on the way)."""
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


def _one_eigenvalue(
    sp: _Spectrum, comp: list[int], dist: np.ndarray, tight: float, wide: float
) -> bool:
    """Whether the computed eigenvalues ``comp`` are taken for one eigenvalue.

    Within rounding they are.  Beyond it, only if they are linked by pairs
    whose first-order error bounds cover their distance (perturbed copies of
    a defective eigenvalue have huge condition numbers), their spread is
    that of a defective eigenvalue of their number, and A - mu I is singular
    at their mean: well-conditioned distinct eigenvalues are never merged,
    however close (a symmetric triple lambda - d, lambda, lambda + d is
    singular at its mean, so that test alone is not enough).
    """
    sub = dist[np.ix_(comp, comp)]
    diameter = float(sub.max())
    if diameter <= tight:
        return True
    return (
        _compatible(sub, sp.delta[comp], tight)
        and diameter <= sp.norm * wide ** (1.0 / len(comp))
        and _singular_at_mean(sp, comp)
    )


def _singular_at_mean(sp: _Spectrum, members: list[int]) -> bool:
    """Whether A - mu I, mu the mean of ``members``, is numerically singular."""
    n = sp.A.shape[0]
    center = sp.lam[members].mean()
    smin = np.linalg.svd(sp.A - center * np.eye(n), compute_uv=False)[-1]
    return bool(smin <= sp.tol.borderline_factor * sp.threshold)


def _closed_under_conjugation(
    lam: np.ndarray, members: np.ndarray, gi: int, group_of: dict[int, int]
) -> bool:
    """Whether every member's conjugate lies in group ``gi`` itself."""
    conj_groups = {group_of[int(np.argmin(np.abs(lam - lam[i].conj())))] for i in members}
    return conj_groups == {gi}


def _eigen_cluster(
    sp: _Spectrum, members: np.ndarray, center: complex, self_conjugate: bool, unit: float
) -> EigenCluster:
    """The group ``members`` at ``center``: its eigenspace, that basis's error and any problem."""
    n = sp.A.shape[0]
    M = sp.A - (center.real if self_conjugate else center) * np.eye(n)
    _, s, vh = np.linalg.svd(M)
    codes = classify(s, sp.threshold, factor=sp.tol.borderline_factor)
    g = int(np.count_nonzero(codes == ZERO))
    basis = vh[n - g :].conj().T if g else np.zeros((n, 0))
    if self_conjugate:
        basis = np.real(basis)
    return EigenCluster(
        center=center,
        members=tuple(int(i) for i in members),
        geometric=g,
        basis=basis,
        error=_eigenspace_error(sp, s, g),
        conjugate_pair=not self_conjugate,
        problem=_cluster_problem(sp, members, _eigenvalue_label(center, unit), s, codes, g),
    )


def _eigenspace_error(sp: _Spectrum, s: np.ndarray, g: int) -> float:
    """Estimated angle (at most 1) between the null space of dimension g and the exact one."""
    n = s.shape[0]
    zero_max = float(s[n - g]) if g else 0.0
    gap = float(s[n - g - 1]) if g < n else sp.norm
    error = max(zero_max, sp.threshold / 10) / max(gap, np.finfo(float).tiny) if g else np.inf
    return float(min(error, 1.0))


def _cluster_problem(
    sp: _Spectrum, members: np.ndarray, label: str, s: np.ndarray, codes: np.ndarray, g: int
) -> str:
    """Why the group is not a sound eigenvalue, or "" when it is."""
    if np.any(codes == BORDERLINE):
        return (
            f"eigenvalue {label}: a singular value of A - lambda I "
            f"({s[codes == BORDERLINE].min():.2e}) is within a factor "
            f"{sp.tol.borderline_factor:g} of the rank threshold {sp.threshold:.2e}"
        )
    if g == 0:
        return (
            f"eigenvalues near {label} are too close to separate and do not behave as "
            f"one eigenvalue (A - lambda I is not singular at their mean)"
        )
    if g > len(members):
        return (
            f"eigenvalue {label}: eigenspace dimension {g} exceeds the {len(members)} "
            f"eigenvalues grouped there"
        )
    if len(members) == 1 and sp.delta[members[0]] > np.sqrt(EPS) * sp.norm:
        return (
            f"eigenvalue {label} is ill-conditioned (condition number "
            f"{sp.kappa[members[0]]:.1e}); it may be a defective eigenvalue that cannot be "
            f"resolved in floating point"
        )
    return ""


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


# ---------------------------------------------------------------------------
# observability staircase


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


def screen_positive_definite(mats: np.ndarray, shift: float | np.ndarray) -> np.ndarray:
    """True where ``mats - shift I`` has a Cholesky factorization.

    Batched and exception-free: a matrix that is not positive definite
    gives False for that matrix only.

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
    if _CHOLESKY is not None:
        with np.errstate(all="ignore"):
            L = _CHOLESKY(shifted)
        return np.isfinite(L[:, -1, -1]) & np.isfinite(L[:, 0, 0])
    return np.linalg.eigvalsh(shifted)[:, 0] > 0  # pragma: no cover


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
