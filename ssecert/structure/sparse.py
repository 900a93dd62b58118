"""s-sparse observability: can any estimator survive s attacked sensors?

``max_removable`` is the largest k such that removing any k sensors leaves
(A, C_rest) observable (-1 when (A, C) itself is unobservable).  With s
attacked sensors, secure estimation is possible iff 2s <= max_removable
(Proposition 1 of the lecture notes; 2s-sparse observability in the Lasso
paper).  The verdict assumes the attacked set is fixed over the window.

Two exact methods answer it, in different numerics:

* **enumeration**: sensor sets by increasing size, so the first breaking
  set found is a smallest one, lexicographically first among equals.  Each
  sensor's observable row space comes from an orthogonal Krylov staircase;
  a set of kept sensors is observable iff the sum of their orthogonal
  projectors is positive definite, screened for many sets per numpy call by
  a batched Cholesky factorization of colex-ordered partial sums and decided
  exactly by SVD where screening fails.  Sensors that alone observe the whole
  state must all be removed to break the plant, which prunes the search.
* **eigenspace** (PBH): (A, C_T) is unobservable iff some eigenvector v of A
  has C_T v = 0, so the smallest breaking sets are the supports of C v over
  nonzero v in an eigenspace.  One support per eigenvalue of geometric
  multiplicity 1; for an eigenspace of dimension g, the C(p, g-1)
  hyperplanes through g-1 of the sensor rows.

Every holds verdict is re-checked on its critical sensor sets (the sets
that come closest to breaking) by the other numerics, and the margin is
reported; every fails verdict carries a stealthy attack verified by
simulation.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._exact import ExactPlant
from .._linalg import (
    EigenAnalysis,
    SensorSubspaces,
    eigen_clusters,
    sensor_subspaces,
    stacked_rank,
    unit_normalized,
)
from .._validation import as_choice, as_int_option
from ..results import Check, Verdict
from ..system import System
from ..tolerances import BORDERLINE, NONZERO, ZERO, Tolerances, classify
from ._combinatorics import colex_blocks, count_subsets
from .attacks import stealthy_attack
from .observability import pbh_margins

__all__ = [
    "sparse_observability",
    "scan_removals",
    "RemovalScan",
    "DEFAULT_MAX_SETS",
    "METHODS",
]

DEFAULT_MAX_SETS = 50_000_000
METHODS = ("auto", "enumeration", "eigenspace")
_CRITICAL = 8  # critical sets re-checked per level

Progress = Callable[[int, int], None]


@dataclass
class _Outcome:
    """What one method found (internal)."""

    method: str
    status: str  # "exact", "lower_bound", "inconclusive"
    max_removable: int | None = None
    breaking_set: tuple[int, ...] | None = None
    z: np.ndarray | None = None
    checked: int = 0
    needed: int | None = None  # sets needed to finish, when over budget
    problems: list[str] = field(default_factory=list)
    critical: list[tuple[int, ...]] = field(default_factory=list)  # kept-sensor sets
    details: dict[str, Any] = field(default_factory=dict)


# ---------------------------------------------------------------------------
# enumeration


def _enumeration(
    system: System,
    s: int,
    max_sets: int,
    tol: Tolerances,
    progress: Progress | None,
    subspaces: SensorSubspaces | None = None,
    eig: EigenAnalysis | None = None,
    exact: ExactPlant | None = None,
) -> _Outcome:
    A, C = system.A, system.C
    n, p = system.n, system.p
    out = _Outcome(method="enumeration", status="inconclusive")
    sub = subspaces if subspaces is not None else sensor_subspaces(A, C, tolerances=tol)
    if sub.borderline.any():
        bad = np.flatnonzero(sub.borderline).tolist()
        out.problems.append(
            f"the observable subspace of sensor(s) {bad} has a borderline rank decision"
        )
        return out
    full = np.flatnonzero(sub.ranks == n)  # must all be removed to break the plant
    rest = np.flatnonzero(sub.ranks < n)
    q = rest.size
    out.details = {
        "sensor_observable_dimensions": sub.ranks.tolist(),
        "sensors_observing_everything": full.tolist(),
    }
    if q == 0:
        # every sensor alone observes the state: only removing all breaks it
        out.status = "exact"
        out.max_removable = p - 1
        out.breaking_set = tuple(range(p))
        z = np.zeros(n)
        z[0] = 1.0
        out.z = z
        out.critical = [tuple(range(min(2 * s, p - 1), p))]
        return out
    P = sub.bases[rest]  # (q, n, n), zero-padded orthonormal rows
    proj = np.einsum("qkn,qkm->qnm", P, P)
    base = proj.sum(axis=0)
    target = 2 * s - full.size  # level whose sets have 2s removed sensors
    best_critical: list[tuple[float, tuple[int, ...]]] = []
    if target < 0:
        # every set of 2s sensors keeps a sensor that alone observes the state
        dropped = set(full[: 2 * s].tolist())
        best_critical = [(0.0, tuple(i for i in range(p) if i not in dropped))]
    for k in range(q + 1):
        count = math.comb(q, k)
        if out.checked + count > max_sets:
            out.needed = count_subsets(q, range(k, max(target, k) + 1))
            out.status = "lower_bound"
            out.max_removable = full.size + k - 1
            out.problems.append(
                f"enumeration budget of {max_sets:,} sets reached before sets of "
                f"{full.size + k} sensor{'s' if full.size + k != 1 else ''}"
            )
            break
        level = _scan_level(
            P,
            sub.ranks[rest],
            proj,
            base,
            k,
            rest,
            full,
            tol,
            critical=(k == target),
            progress=progress,
            errors=sub.errors[rest],
        )
        out.checked += level.checked
        if level.critical:
            best_critical = level.critical
        first, z_first, within = _resolve_failures(system, level.failures, eig, tol, exact, out)
        if first is not None:
            out.status = "exact"
            out.max_removable = full.size + k - 1
            out.breaking_set = first
            out.z = z_first
            if level.borderline or within:
                out.details["borderline_sets_at_breaking_size"] = level.borderline + len(within)
            break
        if level.borderline or within:
            out.status = "lower_bound"
            out.max_removable = full.size + k - 1
            if level.borderline:
                out.problems.append(
                    f"{level.borderline} set(s) of {full.size + k} sensors have a borderline "
                    f"rank decision"
                )
            if within:
                out.details["within_precision_of_breaking"] = [list(w) for w in within[:8]]
                distance = out.details.get("distance_to_breaking")
                out.problems.append(
                    f"removing sensors {list(within[0])}"
                    + (
                        f" (and {len(within) - 1} other set(s) of that size)"
                        if len(within) > 1
                        else ""
                    )
                    + " leaves a plant that is observable in exact arithmetic but within "
                    "floating-point precision of an unobservable one"
                    + (f" (relative distance {distance:.1e})" if distance is not None else "")
                    + ": the answer depends on digits the data do not have"
                )
            break
    out.critical = [kept for _, kept in best_critical]
    return out


def _clearly_observable(
    system: System, kept: tuple[int, ...], eig: EigenAnalysis | None, tol: Tolerances
) -> bool:
    """Float evidence, independent of the Krylov screening, that (A, C_kept) is observable
    with a margin beyond the borderline band (PBH at every eigenvalue group and the
    conservative staircase)."""
    from .._linalg import staircase

    if eig is None or eig.problems or not kept:
        return False
    Ck = system.C[list(kept)]
    centers = np.array([c.center for c in eig.clusters], dtype=complex)
    _, codes = pbh_margins(system.A, Ck, centers, tolerances=tol)
    if not np.all(codes == NONZERO):
        return False
    sc = staircase(system.A, Ck, tolerances=tol, error_model="compound")
    return sc.rank == system.n and not sc.problem


def _distance(
    system: System, kept: tuple[int, ...], eig: EigenAnalysis | None, tol: Tolerances
) -> float | None:
    """Smallest relative PBH singular value of (A, C_kept) over the eigenvalue groups and the
    computed eigenvalues: how far the kept sensors are from losing observability."""
    if not kept:
        return 0.0
    Ck = system.C[list(kept)]
    points = [c.center for c in eig.clusters] if eig is not None else []
    lam = np.linalg.eigvals(system.A)
    points.extend(lam[lam.imag >= 0])
    m, _ = pbh_margins(system.A, Ck, np.array(points, dtype=complex), tolerances=tol)
    return float(m.min()) if m.size else None


def _resolve_failures(
    system: System,
    failures: dict[tuple[int, ...], np.ndarray],
    eig: EigenAnalysis | None,
    tol: Tolerances,
    exact: ExactPlant | None,
    out: _Outcome,
) -> tuple[tuple[int, ...] | None, np.ndarray | None, list[tuple[int, ...]]]:
    """Confirm the float failures of a level on the exact data, in lexicographic order.

    Returns the first breaking set that survives (exactly unobservable, or
    undecidable exactly and kept on the float evidence) with its direction,
    and the sets that are exactly observable but within floating-point
    precision of unobservable.  Sets that are exactly observable with a clear
    margin were float mistakes (basis errors amplified by defective
    eigenvalues) and are dropped, counted in ``out.details``.
    """
    p = system.p
    within: list[tuple[int, ...]] = []
    for removed in sorted(failures):
        if exact is None:
            return removed, failures[removed], within
        if out.details.get("float_failures_refuted_exactly", 0) >= REFUTATION_LIMIT:
            # the float screening is wrong too often on this plant to be worth confirming
            # set by set; what is left counts as undecided
            out.details["refutation_limit_reached"] = True
            within.append(removed)
            continue
        gone = set(removed)
        kept = tuple(i for i in range(p) if i not in gone)
        decision = exact.observability(kept)
        if decision.state == "unobservable":
            out.details["breaking_set_exact"] = True
            return removed, decision.z, within
        if decision.state == "unknown":
            out.details["breaking_set_exact"] = False
            return removed, failures[removed], within
        if _clearly_observable(system, kept, eig, tol):
            out.details["float_failures_refuted_exactly"] = (
                out.details.get("float_failures_refuted_exactly", 0) + 1
            )
        else:
            within.append(removed)
            if len(within) == 1:
                out.details["distance_to_breaking"] = _distance(system, kept, eig, tol)
    return None, None, within


@dataclass
class _Level:
    checked: int = 0
    failures: dict[tuple[int, ...], np.ndarray] = field(default_factory=dict)
    borderline: int = 0
    critical: list[tuple[float, tuple[int, ...]]] = field(default_factory=list)


def _scan_level(
    P: np.ndarray,
    ranks: np.ndarray,
    proj: np.ndarray,
    base: np.ndarray,
    k: int,
    rest: np.ndarray,
    full: np.ndarray,
    tol: Tolerances,
    *,
    critical: bool = False,
    progress: Progress | None = None,
    errors: np.ndarray | None = None,
) -> _Level:
    """Check every removal of ``full`` plus k sensors of ``rest``."""
    q = rest.size
    n = proj.shape[-1]
    if errors is None:
        errors = np.zeros(q)
    # A set that is rank deficient in exact arithmetic shows a smallest
    # eigenvalue up to about sum(err_i^2) <= (sum err_i)^2 when the sensors'
    # bases carry errors err_i: screen at least that far from zero.
    shift = max(tol.screen_rtol * max(q, 1), 10.0 * float(np.sum(errors)) ** 2)
    total = math.comb(q, k)
    level = _Level()
    candidates: list[tuple[float, tuple[int, ...]]] = []
    # the screening shift is folded into the base once, not per block
    shifted = base - shift * np.eye(n)
    buffer = np.empty((0, n, n))
    for block in colex_blocks(proj, shifted, k):
        if buffer.shape[0] < len(block):
            buffer = np.empty((len(block), n, n))
        ok, proxy = _screen(block.matrices, shift, critical, buffer[: len(block)])
        if critical:
            for j in np.argsort(proxy)[:_CRITICAL]:
                dropped = set(rest[block.subsets(np.array([j]))[0]].tolist())
                candidates.append(
                    (float(proxy[j]), tuple(int(i) for i in rest if i not in dropped))
                )
            candidates.sort()
            del candidates[_CRITICAL:]
        bad = np.flatnonzero(~ok)
        if bad.size:
            subsets = block.subsets(bad)
            codes, _, nulls = _refine(P, ranks, subsets, q, tol, errors)
            for row, code, zvec in zip(subsets, codes, nulls):
                removed = tuple(sorted(full.tolist() + rest[row].tolist()))
                if code == ZERO:
                    level.failures[removed] = zvec
                elif code == BORDERLINE:
                    level.borderline += 1
        level.checked += len(block)
        if progress is not None:
            progress(level.checked, total)
    level.critical = candidates
    return level


@dataclass(frozen=True)
class RemovalScan:
    """Result of ``scan_removals``.

    Attributes
    ----------
    size : int
        Number of removed sensors per set.
    checked : int
        Number of sets decided.
    breaking_sets : tuple of tuple of int
        Removed-sensor sets that leave the plant unobservable, sorted; each is
        confirmed on the exact data when the plant is small enough (n <= 60):
        its kept sensors have Krylov rank below n modulo two primes.
    borderline : int
        Sets whose rank decision was borderline, or that floating point
        finds breaking while the exact data are observable within precision.
    """

    size: int
    checked: int
    breaking_sets: tuple[tuple[int, ...], ...]
    borderline: int


def scan_removals(
    system: System,
    size: int,
    *,
    prune: bool = True,
    tolerances: Tolerances | None = None,
    progress: Progress | None = None,
) -> RemovalScan:
    """Check every set of ``size`` removed sensors for observability of the rest.

    Parameters
    ----------
    system : System
    size : int
        Number of sensors removed in each set, 0 <= size <= p.
    prune : bool, default True
        Skip sets that keep a sensor which alone observes the whole state
        (they cannot break observability).  With ``prune=False`` all C(p,
        size) sets are decided, which is what the enumeration benchmark
        measures.
    tolerances : Tolerances, optional
    progress : callable, optional

    Returns
    -------
    RemovalScan

    Examples
    --------
    >>> import numpy as np
    >>> from ssecert import System
    >>> ex2 = System(np.eye(3), [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [1, -1, 1]])
    >>> scan_removals(ex2, 2).breaking_sets
    ((0, 2),)
    """
    tol = Tolerances.check(tolerances)
    size = as_int_option(size, "size", min_value=0, max_value=system.p)
    original = system
    system, _ = unit_normalized(system)
    sub = sensor_subspaces(system.A, system.C, tolerances=tol)
    n = system.n
    if prune:
        full = np.flatnonzero(sub.ranks == n)
        rest = np.flatnonzero(sub.ranks < n)
    else:
        full = np.zeros(0, dtype=np.int64)
        rest = np.arange(system.p)
    k = size - full.size
    if k < 0:
        return RemovalScan(size, 0, (), 0)
    P = sub.bases[rest]
    proj = np.einsum("qkn,qkm->qnm", P, P)
    level = _scan_level(
        P,
        sub.ranks[rest],
        proj,
        proj.sum(axis=0),
        k,
        rest,
        full,
        tol,
        progress=progress,
        errors=sub.errors[rest],
    )
    # every reported breaking set is confirmed on the exact data; refuted ones are dropped
    # when independent float evidence shows a clear margin, else counted as borderline
    exact = ExactPlant(original.A, original.C)
    eig = eigen_clusters(system.A, tolerances=tol)
    confirmed, borderline = [], level.borderline
    for removed in sorted(level.failures):
        gone = set(removed)
        kept = tuple(i for i in range(system.p) if i not in gone)
        state = exact.observability(kept, proof=False).state
        if state != "observable":
            confirmed.append(removed)
        elif not _clearly_observable(system, kept, eig, tol):
            borderline += 1
    return RemovalScan(size, level.checked, tuple(confirmed), borderline)


def _screen(
    shifted: np.ndarray, shift: float, want_proxy: bool, out: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Cholesky screening of Gramians already shifted by ``-shift I``.

    Returns whether each factorization exists and, when asked, a proxy for
    the smallest eigenvalue of the unshifted Gramian (squared smallest
    Cholesky pivot plus the shift, an upper bound) that ranks the sets that
    come closest to breaking.
    """
    from .._linalg import _CHOLESKY

    if _CHOLESKY is None:  # pragma: no cover - depends on the numpy build
        w = np.linalg.eigvalsh(shifted)[:, 0]
        return w > 0, w + shift
    with np.errstate(all="ignore"):
        L = _CHOLESKY(shifted, out=out)
    ok = np.isfinite(L[:, -1, -1]) & np.isfinite(L[:, 0, 0])
    if not want_proxy:
        return ok, np.empty(0)
    proxy = np.where(ok, np.min(np.diagonal(L, axis1=1, axis2=2), axis=1) ** 2 + shift, -np.inf)
    return ok, proxy


def _refine(
    P: np.ndarray,
    ranks: np.ndarray,
    removed: np.ndarray,
    q: int,
    tol: Tolerances,
    errors: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact rank decision for the kept sensors of each removed subset.

    The tolerance adds the basis errors of the kept sensors: a sum of
    subspaces that is rank deficient in exact arithmetic shows a smallest
    singular value up to about their sum.
    """
    n = P.shape[-1]
    codes = np.empty(removed.shape[0], dtype=np.int8)
    rel = np.empty(removed.shape[0])
    nulls = np.zeros((removed.shape[0], n))
    for start in range(0, removed.shape[0], 256):
        chunk = removed[start : start + 256]
        keep = np.ones((chunk.shape[0], q), dtype=bool)
        np.put_along_axis(keep, chunk, False, axis=1)
        kept = [np.flatnonzero(row) for row in keep]
        width = max((len(k) for k in kept), default=0)
        if width == 0:
            codes[start : start + len(chunk)] = ZERO
            nulls[start : start + len(chunk), 0] = 1.0
            continue
        idx = np.array([np.pad(k, (0, width - len(k)), constant_values=-1) for k in kept])
        stacks = P[idx]  # (N, width, n, n)
        stacks[idx < 0] = 0.0
        stacks = stacks.reshape(len(chunk), width * n, n)
        rows = int(max(ranks[k].sum() for k in kept))
        data_error = np.array([errors[k].sum() for k in kept])
        c, r, z = stacked_rank(stacks, tolerances=tol, rows=max(rows, 1), data_error=data_error)
        codes[start : start + len(chunk)] = c
        rel[start : start + len(chunk)] = r
        nulls[start : start + len(chunk)] = z
    return codes, rel, nulls


# ---------------------------------------------------------------------------
# eigenspace (PBH)


def _eigenspace(
    system: System,
    s: int,
    max_sets: int,
    tol: Tolerances,
    eig: EigenAnalysis,
    exact: ExactPlant | None = None,
) -> _Outcome:
    out = _Outcome(method="eigenspace", status="inconclusive")
    if eig.problems:
        out.problems.extend(eig.problems)
        return out
    C = system.C
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
            mags = np.abs(W[:, 0])
            codes = classify(mags, thr, factor=tol.borderline_factor)
            if np.any(codes == BORDERLINE):
                out.problems.append(
                    f"eigenvalue {cluster.center:.6g}: sensor(s) "
                    f"{np.flatnonzero(codes == BORDERLINE).tolist()} see its eigenvector with a "
                    f"borderline magnitude"
                )
                continue
            support = tuple(int(i) for i in np.flatnonzero(codes == NONZERO))
            candidates = [(len(support), support, V[:, 0])]
            order = np.argsort(-mags, kind="stable")
            critical.append(_critical_entry(mags, order, s, p))
        else:
            candidates, crit, problem, used = _hyperplanes(
                W, V, thr, s, tol, max_sets - out.checked
            )
            out.checked += used
            if problem:
                out.problems.append(f"eigenvalue {cluster.center:.6g}: {problem}")
                if problem.startswith("budget"):
                    out.status = "budget"
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
    if out.problems:
        out.status = "inconclusive" if out.status != "budget" else "budget"
        return out
    assert best is not None and best_z is not None
    z = best_z
    if np.iscomplexobj(z):
        z = z.real if np.linalg.norm(z.real) >= np.linalg.norm(z.imag) else z.imag
    z = np.real(z)
    if exact is not None:
        gone = set(best[1])
        decision = exact.observability(tuple(i for i in range(p) if i not in gone))
        if decision.state == "observable":
            kept = tuple(i for i in range(p) if i not in gone)
            distance = _distance(system, kept, eig, tol)
            out.details["distance_to_breaking"] = distance
            out.problems.append(
                f"its smallest support, sensors {list(best[1])}, does not break the exact data "
                f"(relative distance {distance:.1e} to a plant it breaks: the data are within "
                f"precision of one, or its eigenvectors are too ill-conditioned to trust)"
            )
            return out
        out.details["breaking_set_exact"] = decision.state == "unobservable"
        if decision.state == "unobservable":
            if decision.z is None:  # pragma: no cover - an exact unobservable verdict has z
                raise RuntimeError("the exact unobservable verdict carries no direction z")
            z = decision.z
    out.status = "exact"
    out.max_removable = best[0] - 1
    out.breaking_set = best[1]
    out.z = z
    critical.sort()
    out.critical = [kept for _, kept in critical[:_CRITICAL]]
    return out


def _critical_entry(
    mags: np.ndarray, order: np.ndarray, s: int, p: int
) -> tuple[float, tuple[int, ...]]:
    """Kept sensors after removing the 2s that see a mode best, and what remains."""
    removed = order[: min(2 * s, p)]
    kept = tuple(sorted(int(i) for i in range(p) if i not in set(removed.tolist())))
    remaining = float(mags[order[2 * s]]) if 2 * s < p else 0.0
    return remaining, kept


def _hyperplanes(
    W: np.ndarray,
    V: np.ndarray,
    thr: float,
    s: int,
    tol: Tolerances,
    budget: int,
) -> tuple[list, list, str, int]:
    """Smallest supports of W u over u != 0 for an eigenspace of dimension g > 1."""
    p, g = W.shape
    _, sv, vh = np.linalg.svd(W, full_matrices=True)
    smax = max(float(sv[0]), np.finfo(float).tiny)
    sv = np.concatenate([sv, np.zeros(g - sv.size)])  # fewer sensors than g: rank < g
    rank_codes = classify(sv / smax, thr, factor=tol.borderline_factor)
    if np.any(rank_codes == BORDERLINE):
        return [], [], "the sensors' view of its eigenspace has a borderline rank", 0
    if np.any(rank_codes == ZERO):
        u = vh[-1].conj()
        return [(0, (), V @ u)], [], "", 0
    row_norm = np.linalg.norm(W, axis=1)
    row_codes = classify(row_norm, thr, factor=tol.borderline_factor)
    if np.any(row_codes == BORDERLINE):
        return [], [], "a sensor sees its eigenspace with a borderline magnitude", 0
    rows = np.flatnonzero(row_codes == NONZERO)
    total = math.comb(rows.size, g - 1)
    if total > budget:
        return [], [], f"budget: {total:,} hyperplanes exceed the remaining budget", 0
    candidates: list[tuple[int, tuple[int, ...], np.ndarray]] = []
    critical: list[tuple[float, tuple[int, ...]]] = []
    best_size = None
    combos = itertools.combinations(rows.tolist(), g - 1)
    chunk = 4096
    while True:
        idx = np.array(list(itertools.islice(combos, chunk)), dtype=np.int64).reshape(-1, g - 1)
        if idx.shape[0] == 0:
            break
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
        if np.any(independent == BORDERLINE) or np.any(codes[use] == BORDERLINE):
            return [], [], "a hyperplane through its sensor rows is borderline", total
        used = np.flatnonzero(use)
        if used.size:
            seen = codes[used] == NONZERO  # (N, p) supports
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
                candidates.append((low, support, V @ u[used[j]]))
            # the hyperplanes whose (2s+1)-th strongest sensor sees them least
            if 2 * s < p:
                remaining = -np.partition(-mags[used], 2 * s, axis=1)[:, 2 * s]
            else:
                remaining = np.zeros(used.size)
            for j in used[np.argsort(remaining, kind="stable")[:_CRITICAL]]:
                order = np.argsort(-mags[j], kind="stable")
                critical.append(_critical_entry(mags[j], order, s, p))
            critical.sort()
            critical = critical[:_CRITICAL]
    if not candidates:  # every (g-1)-subset dependent: only possible if rows.size < g - 1
        u = vh[-1].conj()
        support = tuple(int(i) for i in rows)
        candidates = [(len(support), support, V @ u)]
    candidates.sort(key=lambda c: (c[0], c[1]))
    return candidates[:1], critical, "", total


# ---------------------------------------------------------------------------
# cost estimate and public entry point


def _estimates(
    system: System, s: int, eig: EigenAnalysis, sub: SensorSubspaces | None
) -> dict[str, float]:
    """Rough flop counts of the two methods."""
    n, p = system.n, system.p
    if eig.problems:
        eigen_cost = math.inf
    else:
        eigen_cost = sum(
            math.comb(p, c.geometric - 1) * p * c.geometric + n**3 for c in eig.clusters
        )
    if sub is None:
        enum_cost = math.inf
    else:
        full = int(np.count_nonzero(sub.ranks == n))
        q = p - full
        upto = max(0, 2 * s - full + 1)
        enum_cost = count_subsets(q, range(upto + 1)) * (n**3 / 3 + n * n) + p * n**3
    return {"eigenspace": float(eigen_cost), "enumeration": float(enum_cost)}


def _run(
    system: System,
    s: int,
    method: str,
    max_sets: int,
    tol: Tolerances,
    progress: Progress | None,
    eig: EigenAnalysis,
    exact: ExactPlant | None = None,
) -> tuple[_Outcome, list[_Outcome], dict[str, float]]:
    n, p = system.n, system.p
    sub: SensorSubspaces | None = None
    estimates: dict[str, float] = {}
    if method == "enumeration":
        order = ["enumeration"]
    elif method == "eigenspace":
        order = ["eigenspace"]
    else:
        estimates = _estimates(system, s, eig, None)
        # the enumeration costs at least the p sensor staircases
        if estimates["eigenspace"] <= p * n**3:
            order = ["eigenspace", "enumeration"]
        else:
            sub = sensor_subspaces(system.A, system.C, tolerances=tol)
            estimates = _estimates(system, s, eig, sub)
            order = sorted(["eigenspace", "enumeration"], key=lambda m: estimates[m])
    tried: list[_Outcome] = []
    for name in order:
        if name == "enumeration":
            if sub is None:
                sub = sensor_subspaces(system.A, system.C, tolerances=tol)
            outcome = _enumeration(system, s, max_sets, tol, progress, sub, eig, exact)
        else:
            outcome = _eigenspace(system, s, max_sets, tol, eig, exact)
            if outcome.status == "exact":
                if sub is None:
                    sub = sensor_subspaces(system.A, system.C, tolerances=tol)
                checked = _cross_check(system, s, outcome, tol, eig, exact, sub)
                if checked is not outcome:
                    tried.append(outcome)
                    outcome = checked
        tried.append(outcome)
        if outcome.status == "exact":
            return outcome, tried, estimates
    # no exact answer: prefer a lower bound that decides the verdict
    for outcome in tried:
        if outcome.status == "lower_bound" and outcome.max_removable is not None:
            if outcome.max_removable >= 2 * s:
                return outcome, tried, estimates
    return tried[0], tried, estimates


CROSS_CHECK_SETS = 200_000  # enumeration that confirms an eigenspace answer when this cheap
REFUTATION_LIMIT = 5_000  # float failures confirmed exactly per enumeration (about 1 ms each)


def _cross_check(
    system: System,
    s: int,
    outcome: _Outcome,
    tol: Tolerances,
    eig: EigenAnalysis,
    exact: ExactPlant | None,
    sub: SensorSubspaces,
) -> _Outcome:
    """Confirm an eigenspace answer by enumerating every set up to its breaking-set size.

    The eigenspace method's minimality rests on the computed eigenvalue
    groups, which ill-conditioned or hidden defective eigenvalues can merge
    or split; the enumeration does not use them.  Agreement keeps the
    answer (with the enumeration's lexicographically first breaking set); a
    smaller breaking set or a smaller set within precision of breaking
    replaces it; an enumeration that misses the eigenspace method's exactly
    confirmed set makes the answer disputed.
    """
    assert outcome.breaking_set is not None and outcome.max_removable is not None
    n = system.n
    full = int(np.count_nonzero(sub.ranks == n))
    q = system.p - full
    size = len(outcome.breaking_set)
    needed = count_subsets(q, range(max(size - full, 0) + 1))
    if needed > CROSS_CHECK_SETS:
        outcome.details["cross_check"] = {
            "status": "not run",
            "sets_needed": needed,
            "limit": CROSS_CHECK_SETS,
        }
        return outcome
    enum = _enumeration(system, s, CROSS_CHECK_SETS, tol, None, sub, eig, exact)
    record = {
        "status": enum.status,
        "max_removable": enum.max_removable,
        "breaking_set": list(enum.breaking_set) if enum.breaking_set is not None else None,
        "sets_checked": enum.checked,
    }
    mr = outcome.max_removable
    if enum.max_removable is not None and enum.max_removable < mr:
        found = "a breaking set" if enum.status == "exact" else "a set within precision of breaking"
        outcome.problems.append(
            f"the enumeration finds {found} of "
            f"{enum.max_removable + 1} sensors, smaller than the eigenspace method's {size} (its "
            f"eigenvalue groups missed it)"
        )
        outcome.status = "inconclusive"
        enum.details["cross_check_of_eigenspace"] = {
            "max_removable": mr,
            "breaking_set": list(outcome.breaking_set),
        }
        return enum
    if enum.status == "exact" and enum.max_removable == mr:
        record["agrees"] = True
        outcome.breaking_set = enum.breaking_set
        outcome.z = enum.z
        outcome.details["breaking_set_exact"] = enum.details.get(
            "breaking_set_exact", outcome.details.get("breaking_set_exact")
        )
    elif (
        outcome.details.get("breaking_set_exact")
        and enum.max_removable is not None
        and (enum.max_removable >= size)
    ):
        record["agrees"] = False
        outcome.problems.append(
            f"the enumeration finds no breaking set of {size} sensors, although sensors "
            f"{list(outcome.breaking_set)} break the exact data: the enumeration's decisions "
            f"are unreliable on this plant"
        )
        outcome.status = "inconclusive"
    outcome.details["cross_check"] = record
    return outcome


def _recheck_holds(
    system: System,
    outcome: _Outcome,
    eig: EigenAnalysis,
    tol: Tolerances,
    s: int,
    exact: ExactPlant | None = None,
) -> tuple[float | None, list[dict[str, Any]], str]:
    """Independent re-check of the sets closest to breaking.

    Each is also decided on the exact data when affordable: a set the exact
    data prove unobservable withdraws the holds.

    Enumeration results are re-checked by the PBH test at the eigenvalues;
    eigenspace results by the Krylov staircase of the kept sensors.  Returns
    the margin (smallest relative PBH singular value found), the records and
    a problem string (empty when every re-check agrees).
    """
    from .._linalg import staircase

    records = []
    margin = None
    problem = ""
    centers = np.array([c.center for c in eig.clusters], dtype=complex)
    for kept in outcome.critical:
        if not kept:
            continue
        Ck = system.C[list(kept)]
        m, codes = pbh_margins(system.A, Ck, centers, tolerances=tol)
        sc = staircase(system.A, Ck, tolerances=tol, error_model="compound")
        pbh_ok = bool(np.all(codes == NONZERO)) and not eig.problems
        stair_ok = sc.rank == system.n and not sc.problem
        value = float(m.min()) if m.size else None
        if value is not None:
            margin = value if margin is None else min(margin, value)
        exact_state = (
            exact.observability(kept, proof=False).state if exact is not None else "unknown"
        )
        records.append(
            {
                "kept_sensors": list(kept),
                "pbh_margin": value,
                "pbh_full_rank": pbh_ok,
                "staircase_full_rank": stair_ok,
                "exact": exact_state,
            }
        )
        if exact_state == "unobservable" and not problem:
            problem = (
                f"without sensors outside {list(kept)} the exact data are unobservable "
                f"(an exact kernel vector), which floating point missed"
            )
        checker_ok = pbh_ok if outcome.method == "enumeration" else stair_ok
        if eig.problems and outcome.method == "enumeration":
            checker_ok = stair_ok
        if not checker_ok and not problem:
            problem = (
                f"re-check of kept sensors {list(kept)} does not confirm observability "
                f"(PBH full rank: {pbh_ok}, staircase full rank: {stair_ok})"
            )
    # Independently of any grouping: at every computed eigenvalue, remove the
    # 2s sensors that see its (numerical) eigenvector best and test PBH there.
    if not problem:
        raw_margin, raw_problem = _recheck_raw_eigenvalues(system, s, tol, eig.eigenvalues)
        if raw_margin is not None:
            margin = raw_margin if margin is None else min(margin, raw_margin)
        problem = raw_problem
    return margin, records, problem


def _recheck_raw_eigenvalues(
    system: System, s: int, tol: Tolerances, lam: np.ndarray
) -> tuple[float | None, str]:
    """PBH at each computed eigenvalue after removing the 2s sensors that see it best."""
    A, C = system.A, system.C
    n, p = system.n, system.p
    if 2 * s >= p:
        return None, ""
    norms = np.linalg.norm(C, axis=1)
    safe = np.where(norms > 0, norms, 1.0)
    worst = None
    for value in lam[lam.imag >= 0]:
        shift = value.real if value.imag == 0 else value
        _, _, vh = np.linalg.svd(A - shift * np.eye(n))
        v = vh[-1].conj()
        seen = np.abs(C @ v) / safe
        kept = np.sort(np.argsort(-seen, kind="stable")[2 * s :])
        m, codes = pbh_margins(A, C[kept], np.array([value]), tolerances=tol)
        worst = float(m[0]) if worst is None else min(worst, float(m[0]))
        if codes[0] != NONZERO:
            return worst, (
                f"the PBH test at the computed eigenvalue {value:.6g}, after removing the "
                f"{2 * s} sensors that see its eigenvector best, is "
                f"{'rank deficient' if codes[0] == ZERO else 'borderline'}"
            )
    return worst, ""


def sparse_observability(
    system: System,
    max_attacked: int,
    *,
    method: str = "auto",
    max_sets: int = DEFAULT_MAX_SETS,
    horizon: int | None = None,
    seed: int = 0,
    tolerances: Tolerances | None = None,
    progress: Progress | None = None,
    eigen: EigenAnalysis | None = None,
) -> Check:
    """Decide s-sparse observability and find the weakest sensor set.

    Parameters
    ----------
    system : System
    max_attacked : int
        s, the largest number of attacked sensors (s >= 0).
    method : {"auto", "enumeration", "eigenspace"}, default "auto"
        ``auto`` picks the cheaper method from a cost estimate and falls back
        to the other when the first cannot decide.
    max_sets : int, default 50,000,000
        Budget of sensor sets (enumeration) or hyperplanes (eigenspace).
        Beyond it, the verdict still holds when every set of up to 2s sensors
        was checked (``max_removable_is_lower_bound`` is then true), and is
        inconclusive otherwise.
    horizon : int, optional
        Length of the stealthy-attack witness (default n).
    seed : int, default 0
        Seed of the initial state used to simulate the witness.
    tolerances : Tolerances, optional
    progress : callable, optional
        ``progress(done, total)`` called during enumeration.
    eigen : EigenAnalysis, optional
        Precomputed eigenvalue groups of the plant in power-of-two units
        (``unit_normalized(system)[0].A``).

    Returns
    -------
    Check
        ``id = "sparse_observability"`` with fields ``max_removable``,
        ``max_removable_is_lower_bound``, ``max_correctable``,
        ``breaking_set`` and ``method``; a failing check carries the
        stealthy attack as ``witness``.

    Examples
    --------
    >>> from ssecert import System
    >>> ugv = System([[1.0, 0.0099], [0.0, 0.9876]], [[1, 0], [0, 1], [0, 1]])
    >>> check = sparse_observability(ugv, 1)
    >>> check.verdict.value, check.fields["max_removable"], check.fields["breaking_set"]
    ('fails', 0, [0])
    """
    if not isinstance(system, System):
        raise TypeError(f"system must be a System, got {type(system).__name__}")
    tol = Tolerances.check(tolerances)
    seed = as_int_option(seed, "seed", min_value=0)
    s = as_int_option(max_attacked, "max_attacked", min_value=0)
    method = as_choice(method, "method", METHODS)
    max_sets = as_int_option(max_sets, "max_sets", min_value=1)
    H = system.n if horizon is None else as_int_option(horizon, "horizon", min_value=1)
    # decisions in power-of-two units (no sensor's units can tip a rank threshold), confirmed
    # on the user's exact data; the witness is built in the user's units
    work, alpha = unit_normalized(system)
    eig = eigen if eigen is not None else eigen_clusters(work.A, tolerances=tol)
    exact = ExactPlant(system.A, system.C)
    outcome, tried, estimates = _run(work, s, method, max_sets, tol, progress, eig, exact)
    for o in tried:
        for item in o.details.get("eigenvalues", []):
            item["eigenvalue"] = item["eigenvalue"] / alpha

    p = system.p
    evidence: dict[str, Any] = {
        "methods_tried": [
            {
                "method": o.method,
                "status": o.status,
                "max_removable": o.max_removable,
                "breaking_set": list(o.breaking_set) if o.breaking_set is not None else None,
                "sets_checked": o.checked,
                "problems": o.problems,
            }
            for o in tried
        ],
        "cost_estimates_flops": estimates,
        "max_sets": max_sets,
        "assumption": "the attacked sensor set is fixed over the observation window",
        "condition": f"secure estimation with s = {s} attacked sensors needs 2s = {2 * s} <= max_removable",
    }
    evidence.update(outcome.details)
    tolerances_out = tol.to_dict()
    title = f"{s}-sparse observability"
    base_fields: dict[str, Any] = {
        "max_attacked": s,
        "method": outcome.method,
    }

    def fields(mr: int | None, lower: bool, bset: tuple[int, ...] | None) -> dict[str, Any]:
        if mr is None:
            correctable = None
        else:
            correctable = -1 if mr < 0 else mr // 2
        return {
            **base_fields,
            "max_removable": mr,
            "max_removable_is_lower_bound": lower,
            "max_correctable": correctable,
            "breaking_set": list(bset) if bset is not None else None,
        }

    def make(
        verdict: Verdict,
        summary: str,
        value: int | None,
        extra: dict[str, Any],
        margin: float | None = None,
        witness: dict | None = None,
    ) -> Check:
        return Check(
            id="sparse_observability",
            title=title,
            verdict=verdict,
            summary=summary,
            value=value,
            margin=margin,
            method=outcome.method,
            fields=extra,
            evidence=evidence,
            witness=witness,
            tolerances=tolerances_out,
        )

    if outcome.status == "exact":
        mr = outcome.max_removable
        assert mr is not None and outcome.breaking_set is not None and outcome.z is not None
        if 2 * s > mr:
            verdict, summary, witness = _failure(
                system, work, s, outcome, H, seed, tol, evidence, exact
            )
            return make(
                verdict, summary, mr, fields(mr, False, outcome.breaking_set), witness=witness
            )
        margin, records, problem = _recheck_holds(work, outcome, eig, tol, s, exact)
        evidence["recheck"] = records
        evidence["margin_definition"] = (
            "smallest relative PBH singular value sigma_min([A - lambda I; C_T]) / ||[A; C]||"
            " over the kept-sensor sets T that come closest to breaking"
        )
        if problem:
            evidence["disputed_max_removable"] = mr
            return make(
                Verdict.INCONCLUSIVE,
                f"The {outcome.method} method finds max_removable = {mr}, but {problem}.",
                None,
                fields(None, False, None),
                margin=margin,
            )
        else:
            summary = (
                f"Removing any {mr} of the {p} sensors keeps the plant observable, so up to "
                f"{mr // 2} attacked sensors can be corrected (s = {s} needed)."
            )
        return make(
            Verdict.INCONCLUSIVE if problem else Verdict.HOLDS,
            summary,
            mr,
            fields(mr, False, outcome.breaking_set),
            margin=margin,
        )

    if outcome.status == "lower_bound" and outcome.max_removable is not None:
        mr = outcome.max_removable
        if mr >= 2 * s:
            margin, records, problem = _recheck_holds(work, outcome, eig, tol, s, exact)
            evidence["recheck"] = records
            if problem:
                summary = f"Lower bound max_removable >= {mr}, but {problem}."
            else:
                summary = (
                    f"Every set of up to {mr} sensors was checked and none breaks observability, "
                    f"so s = {s} attacked sensors can be corrected; the exact max_removable was "
                    f"not computed ({'; '.join(outcome.problems)})."
                )
            return make(
                Verdict.INCONCLUSIVE if problem else Verdict.HOLDS,
                summary,
                mr,
                fields(mr, True, None),
                margin=margin,
            )
    reasons = [pr for o in tried for pr in o.problems] or ["no method could decide"]
    needed = next((o.needed for o in tried if o.needed is not None), None)
    hint = ""
    if needed is not None:
        hint = (
            f" About {needed:,} more sensor sets are needed; raise the budget with "
            f"--max-sets (max_sets=...)."
        )
    lower = outcome.max_removable if outcome.status == "lower_bound" else None
    return make(
        Verdict.INCONCLUSIVE,
        f"Sparse observability could not be decided: {'; '.join(reasons)}.{hint}",
        lower,
        {**fields(lower, lower is not None, None), "sets_needed": needed},
    )


def _failure(
    system: System,
    work: System,
    s: int,
    outcome: _Outcome,
    H: int,
    seed: int,
    tol: Tolerances,
    evidence: dict[str, Any],
    exact: ExactPlant,
) -> tuple[Verdict, str, dict[str, Any] | None]:
    """Verdict, summary and stealthy-attack witness of a failing check.

    ``work`` is the plant in power-of-two units used for float decisions;
    the witness is built on the user's ``system``.
    """
    from .._linalg import staircase

    mr = outcome.max_removable
    B = outcome.breaking_set
    z = outcome.z
    assert mr is not None and B is not None and z is not None
    names = [system.sensors[i] for i in B]
    # independent confirmation that the kept sensors do not observe the plant
    kept = [i for i in range(system.p) if i not in set(B)]
    sc_rank = (
        staircase(work.A, work.C[kept], tolerances=tol, error_model="compound").rank if kept else 0
    )
    decision = exact.observability(tuple(kept))
    evidence["breaking_set_check"] = {
        "kept_sensors": kept,
        "kept_observable_dimension": sc_rank,
        "unobservable": sc_rank < system.n,
        "exact": decision.to_dict(),
    }
    if decision.state == "observable":
        return (
            Verdict.INCONCLUSIVE,
            (
                f"The {outcome.method} method finds breaking set {list(B)}, but without those sensors "
                f"the exact data are observable (Krylov rank {system.n} modulo a prime): the plant is "
                f"within floating-point precision of one they break, and the answer depends on digits "
                f"the data do not have."
            ),
            None,
        )
    witness = stealthy_attack(system, B, z, s, horizon=H, seed=seed, tolerances=tol)
    witness_out = witness.to_dict()
    if decision.state == "unobservable":
        witness_out["exact_check"] = (
            "removing the breaking set leaves the exact data "
            "unobservable: z_exact_integers (up to scale) satisfies "
            "C_i A^k z = 0 exactly for every kept sensor i"
        )
        witness_out["z_exact_integers"] = [str(v) for v in decision.z_exact or []]
    if decision.state != "unobservable" and (
        not witness.verified or (kept and sc_rank >= system.n)
    ):
        return (
            Verdict.INCONCLUSIVE,
            (
                f"The {outcome.method} method finds breaking set {list(B)}, but the stealthy attack "
                f"built from it does not verify (output mismatch {witness.residual:.2e}, kept sensors "
                f"observable dimension {sc_rank})."
            ),
            witness_out,
        )
    if mr == -1:
        what = "(A, C) itself is not observable: some states produce no output at all."
    elif len(B) <= s:
        what = (
            f"Removing sensor{'s' if len(B) > 1 else ''} {', '.join(names)} leaves the plant "
            f"unobservable, and {len(B)} <= s = {s}: an attacker on "
            f"{'them' if len(B) > 1 else 'it'} can mimic a different initial state without "
            f"being detected."
        )
    else:
        what = (
            f"Removing sensors {', '.join(names)} leaves the plant unobservable; split into two "
            f"groups of at most s = {s}, they give two attacks under which different initial "
            f"states produce the same outputs."
        )
    summary = (
        f"max_removable = {mr} < 2s = {2 * s}: {s} attacked sensor{'s' if s != 1 else ''} "
        f"cannot be corrected. {what}"
    )
    return Verdict.FAILS, summary, witness_out
