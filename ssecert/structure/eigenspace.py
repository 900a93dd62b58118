"""Sparse observability by the eigenspace (PBH) method.

(A, C_T) is unobservable iff some eigenvector v of A has C_T v = 0, so the
smallest breaking sets are the supports of C v over nonzero v in an
eigenspace: one support per eigenvalue of geometric multiplicity 1, and for
an eigenspace of dimension g the C(p, g-1) hyperplanes through g-1 of the
sensor rows.  ``ssecert.structure.sparse`` confirms its answers exactly and
cross-checks them by enumeration.
"""

from __future__ import annotations

import functools
import itertools
import math
import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..base.format import distance as format_distance
from ..numerics.exact import ExactPlant, Observability
from ..numerics.linalg import (
    EigenAnalysis,
)
from ..system import System
from ..tolerances import BORDERLINE, NONZERO, ZERO, Tolerances, classify
from ._level_scan import _CRITICAL
from .enumeration import OutcomeStatus, SparseMethod, _distance, _Outcome
from .outcomes import Problem, ProblemCode

__all__: list[str] = []


def _eigenspace(
    system: System,
    s: int,
    max_sets: int,
    tol: Tolerances,
    eig: EigenAnalysis,
    exact: ExactPlant | None = None,
    deadline: float | None = None,
) -> _Outcome:
    """The smallest breaking set over the eigenspaces, confirmed on the exact data when given.

    ``deadline`` (a ``time.monotonic()`` value) stops the hyperplane search
    of a large eigenspace: the outcome is then ``budget``, with the reason.
    """
    out = _Outcome(method=SparseMethod.EIGENSPACE, status=OutcomeStatus.INCONCLUSIVE)
    if eig.problems:
        out.problems.extend(Problem.of(ProblemCode.EIGENVALUES, text=t) for t in eig.problems)
        return out
    best, z, critical = _smallest_support(system.C, s, max_sets, tol, eig, out, deadline)
    if out.problems:
        if out.status is not OutcomeStatus.BUDGET:
            out.status = OutcomeStatus.INCONCLUSIVE
        return out
    assert best is not None and z is not None
    if np.iscomplexobj(z):
        z = z.real if np.linalg.norm(z.real) >= np.linalg.norm(z.imag) else z.imag
    z = np.real(z)
    if exact is not None:
        confirmed = _exactly_breaking(system, best[1], z, tol, eig, exact, out)
        if confirmed is None:
            return out
        z = confirmed
    out.status = OutcomeStatus.EXACT
    out.max_removable = best[0] - 1
    out.breaking_set = best[1]
    out.z = z
    critical.sort()
    out.critical = [kept for _, kept in critical[:_CRITICAL]]
    return out


def _smallest_support(
    C: np.ndarray,
    s: int,
    max_sets: int,
    tol: Tolerances,
    eig: EigenAnalysis,
    out: _Outcome,
    deadline: float | None = None,
) -> tuple[tuple[int, tuple[int, ...]] | None, np.ndarray | None, list]:
    """(size, sensors) of the smallest support of C v over the eigenspaces, v, the critical sets.

    Problems, the hyperplanes checked and the per-eigenvalue details go to ``out``.
    """
    p, n = C.shape
    row_norms = np.linalg.norm(C, axis=1)
    safe = np.where(row_norms > 0, row_norms, 1.0)
    best: tuple[int, tuple[int, ...]] | None = None
    best_z: np.ndarray | None = None
    critical: list[tuple[float, tuple[int, ...]]] = []
    per_cluster = []
    for cluster in eig.clusters:
        V = cluster.basis
        g = cluster.geometric
        W = (C @ V) / safe[:, None]  # relative visibility of the eigenspace per sensor
        # the eigenspace error is an estimate, not a bound: a factor 10 of safety
        thr = tol.rtol(p, n + g) + 10.0 * cluster.error
        if g == 1:
            candidates, crit, problem = _eigenvector_support(W, V, thr, s, tol)
        else:
            candidates, crit, problem, used = _hyperplanes(
                W, V, thr, s, tol, max_sets - out.checked, deadline
            )
            out.checked += used
        if problem:
            out.problems.append(
                Problem.of(
                    ProblemCode.EIGENSPACE, eigenvalue=eig.label(cluster.center), text=problem.text
                )
            )
            if problem.budget:
                out.status = OutcomeStatus.BUDGET
            continue
        critical.extend(crit)
        per_cluster.append(
            {
                "eigenvalue": cluster.center,
                "geometric_multiplicity": g,
                "fewest_sensors_seeing_it": min(c[0] for c in candidates),
            }
        )
        for size, support, v in candidates:
            if best is None or (size, support) < best:
                best = (size, support)
                best_z = v
    out.details = {"eigenvalues": per_cluster}
    return best, best_z, critical


@dataclass(frozen=True)
class _Problem:
    """Why an eigenspace was left undecided: ``text`` for the report, ``budget`` when its
    search ran out of hyperplanes or time (the method's status is then ``BUDGET``)."""

    text: str
    budget: bool = False


def _eigenvector_support(
    W: np.ndarray, V: np.ndarray, thr: float, s: int, tol: Tolerances
) -> tuple[list, list, _Problem | None]:
    """The sensors that see a simple eigenvalue's eigenvector, its critical set, or a problem."""
    p = W.shape[0]
    mags = np.abs(W[:, 0])
    codes = classify(mags, thr, factor=tol.borderline_factor)
    if np.any(codes == BORDERLINE):
        return (
            [],
            [],
            _Problem(
                f"sensor(s) {np.flatnonzero(codes == BORDERLINE).tolist()} see its eigenvector "
                f"with a borderline magnitude"
            ),
        )
    support = tuple(int(i) for i in np.flatnonzero(codes == NONZERO))
    order = np.argsort(-mags, kind="stable")
    return [(len(support), support, V[:, 0])], [_critical_entry(mags, order, s, p)], None


def _exactly_breaking(
    system: System,
    support: tuple[int, ...],
    z: np.ndarray,
    tol: Tolerances,
    eig: EigenAnalysis,
    exact: ExactPlant,
    out: _Outcome,
) -> np.ndarray | None:
    """z (the exact kernel vector when there is one) if removing support breaks the exact data.

    None, with the problem recorded in ``out``, when the exact data stay observable.
    """
    p = system.p
    gone = set(support)
    decision = exact.observability(tuple(i for i in range(p) if i not in gone))
    if decision.state is Observability.OBSERVABLE:
        kept = tuple(i for i in range(p) if i not in gone)
        distance = _distance(system, kept, eig, tol)
        out.details["distance_to_breaking"] = distance
        out.problems.append(
            Problem.of(
                ProblemCode.NOT_EXACT, support=tuple(support), distance=format_distance(distance)
            )
        )
        return None
    out.details["breaking_set_exact"] = decision.state is Observability.UNOBSERVABLE
    if decision.state is Observability.UNOBSERVABLE:
        if decision.z is None:  # pragma: no cover - an exact unobservable verdict has z
            raise RuntimeError("the exact unobservable verdict carries no direction z")
        return decision.z
    return z


def _critical_entry(
    mags: np.ndarray, order: np.ndarray, s: int, p: int
) -> tuple[float, tuple[int, ...]]:
    """Kept sensors after removing the 2s that see a mode best, and what remains."""
    removed = order[: min(2 * s, p)]
    kept = tuple(sorted(int(i) for i in range(p) if i not in set(removed.tolist())))
    remaining = float(mags[order[2 * s]]) if 2 * s < p else 0.0
    return remaining, kept


class _ChunkView(NamedTuple):
    """What the sensors see of the hyperplanes through one chunk of (g-1)-subsets of rows."""

    u: np.ndarray  # (N, g) the normal of each hyperplane, in eigenspace coordinates
    mags: np.ndarray  # (N, p) |W u|: how much each sensor sees of it
    codes: np.ndarray  # (N, p) mags classified against the threshold scaled by its condition
    used: np.ndarray  # the hyperplanes through independent rows
    borderline: bool  # some independence or some sensor's magnitude is borderline


def _chunk_view(W: np.ndarray, idx: np.ndarray, thr: float, tol: Tolerances) -> _ChunkView:
    """The hyperplanes through the rows ``idx`` of ``W`` and what each sensor sees of them."""
    sub = W[idx]  # (N, g-1, g)
    _, s_sub, vh_sub = np.linalg.svd(sub, full_matrices=True)
    smax_sub = np.maximum(s_sub[:, 0], np.finfo(float).tiny)
    independent = classify(s_sub[:, -1] / smax_sub, thr, factor=tol.borderline_factor)
    u = vh_sub[:, -1, :].conj()  # (N, g)
    mags = np.abs(u @ W.T)  # (N, p)
    cond = smax_sub / np.maximum(s_sub[:, -1], np.finfo(float).tiny)
    thr_u = thr * np.maximum(cond, 1.0)
    codes = classify(mags, thr_u[:, None], factor=tol.borderline_factor)
    use = independent == NONZERO
    borderline = bool(np.any(independent == BORDERLINE) or np.any(codes[use] == BORDERLINE))
    return _ChunkView(u, mags, codes, np.flatnonzero(use), borderline)


def _smallest_so_far(
    view: _ChunkView,
    V: np.ndarray,
    candidates: list[tuple[int, tuple[int, ...], np.ndarray]],
    best_size: int | None,
) -> tuple[list[tuple[int, tuple[int, ...], np.ndarray]], int | None]:
    """The candidates and the smallest support size, with this chunk's smallest support added."""
    used, p = view.used, view.mags.shape[1]
    seen = view.codes[used] == NONZERO  # (N, p) supports
    sizes = np.count_nonzero(seen, axis=1)
    low = int(sizes.min())
    if best_size is None or low <= best_size:
        if best_size is None or low < best_size:
            candidates, best_size = [], low
        ties = np.flatnonzero(sizes == low)
        # among supports of equal size, the lexicographically first index
        # tuple is the lexicographically largest boolean row
        keys = [~seen[ties, c] for c in range(p - 1, -1, -1)]
        j = ties[np.lexsort(keys)[0]]
        support = tuple(int(i) for i in np.flatnonzero(seen[j]))
        candidates.append((low, support, V @ view.u[used[j]]))
    return candidates, best_size


def _most_critical(
    view: _ChunkView, critical: list[tuple[float, tuple[int, ...]]], s: int
) -> list[tuple[float, tuple[int, ...]]]:
    """The critical entries so far and this chunk's (hyperplanes its (2s+1)-th sensor sees least)."""
    mags, used, p = view.mags, view.used, view.mags.shape[1]
    if 2 * s < p:
        remaining = -np.partition(-mags[used], 2 * s, axis=1)[:, 2 * s]
    else:
        remaining = np.zeros(used.size)
    for j in used[np.argsort(remaining, kind="stable")[:_CRITICAL]]:
        order = np.argsort(-mags[j], kind="stable")
        critical.append(_critical_entry(mags[j], order, s, p))
    critical.sort()
    return critical[:_CRITICAL]


def _hyperplanes(
    W: np.ndarray,
    V: np.ndarray,
    thr: float,
    s: int,
    tol: Tolerances,
    budget: int,
    deadline: float | None = None,
) -> tuple[list, list, _Problem | None, int]:
    """Smallest supports of W u over u != 0 for an eigenspace of dimension g > 1."""
    p, g = W.shape
    _, sv, vh = np.linalg.svd(W, full_matrices=True)
    smax = max(float(sv[0]), np.finfo(float).tiny)
    sv = np.concatenate([sv, np.zeros(g - sv.size)])  # fewer sensors than g: rank < g
    rank_codes = classify(sv / smax, thr, factor=tol.borderline_factor)
    if np.any(rank_codes == BORDERLINE):
        return [], [], _Problem("the sensors' view of its eigenspace has a borderline rank"), 0
    if np.any(rank_codes == ZERO):
        u = vh[-1].conj()
        return [(0, (), V @ u)], [], None, 0
    row_norm = np.linalg.norm(W, axis=1)
    row_codes = classify(row_norm, thr, factor=tol.borderline_factor)
    if np.any(row_codes == BORDERLINE):
        return [], [], _Problem("a sensor sees its eigenspace with a borderline magnitude"), 0
    rows = np.flatnonzero(row_codes == NONZERO)
    total = math.comb(rows.size, g - 1)
    if total > budget:
        problem = _Problem(f"budget: {total:,} hyperplanes exceed the remaining budget", True)
        return [], [], problem, 0
    candidates: list[tuple[int, tuple[int, ...], np.ndarray]] = []
    critical: list[tuple[float, tuple[int, ...]]] = []
    best_size = None
    combos = itertools.combinations(rows.tolist(), g - 1)
    chunk = 4096
    done = 0
    while True:
        if deadline is not None and time.monotonic() > deadline:
            ended = f"budget: the time budget ended after {done:,} of {total:,} hyperplanes"
            return [], [], _Problem(ended, True), done
        idx = np.array(list(itertools.islice(combos, chunk)), dtype=np.int64).reshape(-1, g - 1)
        if idx.shape[0] == 0:
            break
        done += idx.shape[0]
        view = _chunk_view(W, idx, thr, tol)
        if view.borderline:
            return [], [], _Problem("a hyperplane through its sensor rows is borderline"), total
        if view.used.size:
            candidates, best_size = _smallest_so_far(view, V, candidates, best_size)
            critical = _most_critical(view, critical, s)
    if not candidates:  # every (g-1)-subset dependent: only possible if rows.size < g - 1
        u = vh[-1].conj()
        support = tuple(int(i) for i in rows)
        candidates = [(len(support), support, V @ u)]
    candidates.sort(key=lambda c: (c[0], c[1]))
    return candidates[:1], critical, None, total


@functools.lru_cache(maxsize=64)
def _hyperplane_rate(p: int, g: int) -> float:
    """Seconds per hyperplane of the search over an eigenspace of dimension g seen by p sensors,
    measured once per process on a synthetic chunk (the index tuples built as the search builds
    them, then ``_chunk_view``)."""
    rng = np.random.default_rng(0)
    W = rng.standard_normal((p, g))
    combos = itertools.combinations(range(p), g - 1)
    count = min(2048, math.comb(p, g - 1))

    def chunk() -> None:
        idx = np.array(list(itertools.islice(combos, count)), dtype=np.int64)
        _chunk_view(W, idx.reshape(-1, g - 1), 1e-12, Tolerances())

    best = math.inf
    for _ in range(2):
        combos = itertools.combinations(range(p), g - 1)
        start = time.perf_counter()
        chunk()
        best = min(best, time.perf_counter() - start)
    return best / max(count, 1)


def search_seconds(p: int, eig: EigenAnalysis) -> float:
    """Estimated seconds of the eigenspace method's hyperplane searches on this machine (at most
    C(p, g - 1) hyperplanes for each eigenspace of dimension g > 1)."""
    return sum(
        math.comb(p, c.geometric - 1) * _hyperplane_rate(p, c.geometric)
        for c in eig.clusters
        if c.geometric > 1
    )
