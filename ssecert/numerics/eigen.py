"""Eigenvalues of A grouped into clusters, each with its eigenspace.

``eigen_clusters`` groups the computed eigenvalues from their condition
numbers and a defect-aware radius (beyond rounding, a group must make
A - mu I singular at its mean), computes each group's eigenspace and
reports every doubtful grouping instead of guessing.  ``ssecert.numerics.linalg``
re-exports these names.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ..tolerances import BORDERLINE, EPS, ZERO, Tolerances, classify

__all__ = ["EigenCluster", "EigenAnalysis", "eigen_clusters"]


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
    ``||A|| (n 1e4 cluster_rtol)^(1/m)``.  Each group's eigenspace is the
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
    # linalg.matrix_norm, written out: linalg imports this module
    norm = max(float(np.linalg.norm(A, 2)) if A.size else 0.0, np.finfo(float).tiny)
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
