"""Observability of (A, C), decided reliably in floating point.

The rank of the stacked observability matrix is not a reliable test: for
``A = diag(linspace(0.1, 0.95, 20))`` and ``C = ones((1, 20))`` the pair is
observable with a smallest PBH singular value of 0.023, yet ``numpy.linalg.matrix_rank``
reports rank 18 for O_20, whose monomial rows are nearly parallel.  Two
backward-stable methods are used instead and must agree:

* the PBH test: ``[A - lambda I; C]`` has full column rank at every
  eigenvalue lambda (eigenvalues grouped, see ``eigen_clusters``); the
  smallest of these singular values is the reported margin;
* the orthogonal observability staircase, which also gives the
  observability index (the fewest steps whose outputs determine x(0)).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from ..base.format import distance as format_distance
from ..numerics.exact import Observability
from ..numerics.linalg import (
    EigenAnalysis,
    Staircase,
    Units,
    eigen_clusters,
    matrix_norm,
    staircase,
)
from ..results import Check
from ..system import System
from ..tolerances import BORDERLINE, NONZERO, ZERO, Tolerances, classify
from .outcomes import ObservabilityCode

if TYPE_CHECKING:
    from ..numerics.exact import ExactObservability

__all__ = ["observability", "pbh_margins", "observability_index", "unobservable_residual"]


# above this many sensors per state, PBH matrices are compressed by a QR factor of C
_COMPRESS_ROWS = 4


def pbh_margins(
    A: np.ndarray,
    C: np.ndarray,
    centers: np.ndarray,
    *,
    tolerances: Tolerances | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Relative PBH singular values at the given eigenvalues.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    C : ndarray, shape (p, n)
    centers : array_like of complex
        Eigenvalues (or group centers) at which to test.
    tolerances : Tolerances, optional

    Returns
    -------
    margins : ndarray
        ``sigma_min([A - lambda I; C]) / ||[A; C]||`` for each lambda.
    codes : ndarray of int8
        Rank decision (ZERO: rank deficient, BORDERLINE, NONZERO).
    """
    tol = tolerances or Tolerances()
    n, p = A.shape[0], C.shape[0]
    if p > _COMPRESS_ROWS * n and np.all(np.isfinite(C)):
        # [A - lambda I; C] = diag(I, Q) [A - lambda I; R] with C = Q R: the same singular
        # values (to rounding, as the SVD's own) from an (2n x n) matrix instead of (n + p) x n
        C = np.asarray(np.linalg.qr(C, mode="r"))
    stacked_norm = max(matrix_norm(np.vstack([A, C])), np.finfo(float).tiny)
    lam = np.asarray(centers, dtype=complex).reshape(-1)
    margins = np.empty(lam.size)
    real = lam.imag == 0
    # one batched SVD per dtype: a real shift keeps a real matrix (same values as one by one)
    for mask, shifts in ((real, lam.real[real]), (~real, lam[~real])):
        if shifts.size:
            stacked = np.vstack([A, C]).astype(shifts.dtype)
            M = np.broadcast_to(stacked, (shifts.size, *stacked.shape)).copy()
            M[:, np.arange(n), np.arange(n)] -= shifts[:, None]
            margins[mask] = np.linalg.svd(M, compute_uv=False)[:, -1] / stacked_norm
    codes = classify(margins, tol.rtol(n + p, n), factor=tol.borderline_factor)
    return margins, codes


def observability_index(system: System, *, tolerances: Tolerances | None = None) -> int | None:
    """Fewest steps tau with O_tau of full column rank, or None if unobservable.

    Computed by the orthogonal staircase, not by ranks of O_tau.

    Parameters
    ----------
    system : System
    tolerances : Tolerances, optional

    Returns
    -------
    int or None

    Examples
    --------
    >>> from ssecert import System
    >>> observability_index(System([[1.0, 0.0099], [0.0, 0.9876]], [[1, 0]]))
    2
    """
    if not isinstance(system, System):
        raise TypeError(f"system must be a System, got {type(system).__name__}")
    sc = staircase(system.A, system.C, tolerances=Tolerances.check(tolerances))
    if sc.problem or sc.rank < system.n:
        return None
    return sc.index


def observability(
    system: System,
    *,
    tolerances: Tolerances | None = None,
    eigen: EigenAnalysis | None = None,
) -> Check:
    """Is (A, C) observable?  PBH test and staircase, which must agree.

    Parameters
    ----------
    system : System
    tolerances : Tolerances, optional
    eigen : EigenAnalysis, optional
        Precomputed eigenvalue groups of the plant in power-of-two units
        (``balanced_units(system).system.A``).

    Returns
    -------
    Check
        ``id = "observability"``; ``value`` and ``fields["observability_index"]``
        hold the index when observable; ``margin`` is the smallest relative
        PBH singular value over the eigenvalues.  A failing check carries an
        unobservable direction ``z`` (C A^k z = 0 for all k) as witness.

    Examples
    --------
    >>> import numpy as np
    >>> from ssecert import System
    >>> A = np.diag(np.linspace(0.1, 0.95, 20))
    >>> check = observability(System(A, np.ones((1, 20))))
    >>> check.verdict.value, check.fields["observability_index"]
    ('holds', 20)
    """
    from ..numerics.exact import ExactPlant
    from ..numerics.linalg import balanced_units

    if not isinstance(system, System):
        raise TypeError(f"system must be a System, got {type(system).__name__}")
    tol = Tolerances.check(tolerances)
    # decisions in exact power-of-two units of the states, the sensors and time: a change of
    # units changes no verdict; witnesses are given in the user's coordinates
    units = balanced_units(system)
    work, alpha = units.system, units.alpha
    A, C = work.A, work.C
    n = system.n
    eig = eigen if eigen is not None else eigen_clusters(A, tolerances=tol, unit=alpha)
    sc = staircase(A, C, tolerances=tol)
    exact = ExactPlant(system.A, system.C).observability(tuple(range(system.p)))

    pbh = _pbh_test(A, C, eig, tol)
    pbh_state = pbh.state
    stair_state: Observability
    if sc.problem:
        stair_state, stair_note = Observability.UNKNOWN, sc.problem
    else:
        stair_state = Observability.OBSERVABLE if sc.rank == n else Observability.UNOBSERVABLE
        stair_note = ""
    grouping = ""
    if _grouping_cannot_matter(eig, pbh, stair_state, exact.state):
        pbh_state, grouping = Observability.OBSERVABLE, "; ".join(eig.problems)
    out = _Verdicts(
        margin=pbh.margin,
        evidence=_evidence(eig, alpha, pbh, pbh_state, sc, stair_state, exact.to_dict(), units),
        tolerances={
            "rank_rtol": tol.rtol(n + system.p, n),
            "borderline_factor": tol.borderline_factor,
            "eigenvalue_threshold": eig.threshold,
            "witness_rtol": tol.witness_rtol,
        },
    )

    unobservable_in_floats = Observability.UNOBSERVABLE in (pbh_state, stair_state)
    if exact.state is Observability.UNOBSERVABLE and not unobservable_in_floats:
        return _exactly_unobservable(out, system.A, system.C, exact)
    if exact.state is Observability.OBSERVABLE and unobservable_in_floats:
        return _exactly_observable(out, n)
    if pbh_state is Observability.OBSERVABLE and stair_state is Observability.OBSERVABLE:
        return _observable(out, sc.index, exact.state, grouping)
    candidates, conservative = _candidate_directions(A, C, eig, alpha, pbh, pbh_state, tol)
    unobs = n - sc.rank if stair_state is Observability.UNOBSERVABLE else n - conservative.rank
    verified = _verified_direction(
        out, A, C, candidates, unobs, stair_state, exact, tol, units.to_user
    )
    if verified is not None:
        return verified
    notes = [r for r in (pbh.note, stair_note) if r]
    return _undecided(out, notes, pbh_state, stair_state, bool(candidates))


class _PBH(NamedTuple):
    """The PBH test at the eigenvalue groups and at every computed eigenvalue."""

    margins: np.ndarray  # per group
    codes: np.ndarray  # per group
    raw_codes: np.ndarray  # per computed eigenvalue in the closed upper half plane
    margin: float  # the smallest of all, as reported to users
    state: Observability
    note: str  # why unknown


@dataclass(frozen=True)
class _Verdicts:
    """What every verdict shows: the PBH margin, the evidence and the tolerances."""

    margin: float
    evidence: dict[str, Any]  # added to by the deciding step
    tolerances: dict[str, Any]

    def check(
        self,
        code: ObservabilityCode,
        summary: str,
        index: int | None,
        unobs: int | None,
        witness: dict | None = None,
    ) -> Check:
        """The observability Check of ``code`` (its verdict), with this index and unobservable
        dimension."""
        return Check(
            id="observability",
            title="Observability of (A, C)",
            verdict=code.verdict,
            code=code,
            summary=summary,
            value=index,
            margin=self.margin,
            method="pbh+staircase",
            fields={"observability_index": index, "unobservable_dimension": unobs},
            evidence=self.evidence,
            witness=witness,
            tolerances=self.tolerances,
        )


def _pbh_test(A: np.ndarray, C: np.ndarray, eig: EigenAnalysis, tol: Tolerances) -> _PBH:
    """PBH margins and rank decisions at the groups and computed eigenvalues, and their answer."""
    centers = np.array([c.center for c in eig.clusters], dtype=complex)
    margins, codes = pbh_margins(A, C, centers, tolerances=tol)
    # margin over every computed eigenvalue, as reported to users
    raw = eig.eigenvalues[eig.eigenvalues.imag >= 0]
    raw_margins, raw_codes = pbh_margins(A, C, raw, tolerances=tol)
    margin = float(min(margins.min(initial=np.inf), raw_margins.min(initial=np.inf)))
    if eig.problems:
        state, note = Observability.UNKNOWN, "; ".join(eig.problems)
    elif np.any(codes == ZERO):
        state, note = Observability.UNOBSERVABLE, ""
    elif np.any(codes == BORDERLINE):
        state = Observability.UNKNOWN
        note = f"a PBH singular value ({margins[codes == BORDERLINE].min():.2e}) is borderline"
    else:
        state, note = Observability.OBSERVABLE, ""
    return _PBH(margins, codes, raw_codes, margin, state, note)


def _grouping_cannot_matter(
    eig: EigenAnalysis, pbh: _PBH, stair_state: Observability, exact_state: Observability
) -> bool:
    """True when only the eigenvalue grouping is in doubt and no grouping changes the answer."""
    # how the eigenvalues group (their multiplicities) is ambiguous, but PBH is clearly of
    # full rank at every computed eigenvalue and every group, the staircase agrees, and the
    # exact data are observable: the grouping cannot change the answer
    return bool(
        eig.problems
        and stair_state is Observability.OBSERVABLE
        and exact_state is Observability.OBSERVABLE
        and np.all(pbh.codes == NONZERO)
        and np.all(pbh.raw_codes == NONZERO)
    )


def _evidence(
    eig: EigenAnalysis,
    alpha: float,
    pbh: _PBH,
    pbh_state: Observability,
    sc: Staircase,
    stair_state: Observability,
    exact: dict[str, Any],
    units: Units,
) -> dict[str, Any]:
    """Evidence of every verdict: eigenvalues, PBH per group, the staircase, the exact decision
    (the margins are those of the plant in balanced power-of-two units)."""
    scaling = {"state_scaling": units.states} if units.balanced else {}
    return {
        **scaling,
        "eigenvalues": eig.eigenvalues / alpha,
        "pbh": [
            {
                "eigenvalue": c.center / alpha,
                "algebraic_multiplicity": c.algebraic,
                "geometric_multiplicity": c.geometric,
                "pbh_margin": float(m),
                "decision": {
                    ZERO: "rank deficient",
                    BORDERLINE: "borderline",
                    NONZERO: "full rank",
                }[int(code)],
            }
            for c, m, code in zip(eig.clusters, pbh.margins, pbh.codes)
        ],
        "staircase_block_sizes": list(sc.block_sizes),
        "staircase_step_margins": list(sc.step_margins),
        "observable_dimension": sc.rank,
        "pbh_state": pbh_state,
        "staircase_state": stair_state,
        "exact": exact,
        "margin_definition": (
            "min over eigenvalues of sigma_min([A - lambda I; C]) / ||[A; C]||_2,"
            " in units where ||A||_max and every sensor row are within a factor "
            "2 of 1 (powers of two, exact)"
        ),
        "method_detail": (
            "PBH test at grouped eigenvalues, re-checked by the orthogonal observability "
            "staircase; an unobservable direction is verified by simulating C A^k z; the exact "
            "data (floats as rationals) decide by the Krylov rank modulo a prime (full rank "
            "proves observability) or an exact kernel vector (proves the opposite)"
        ),
    }


def _exactly_unobservable(
    out: _Verdicts, A: np.ndarray, C: np.ndarray, exact: ExactObservability
) -> Check:
    """Fails with the exact unobservable direction that floating point could not resolve."""
    # floating point was fooled (error amplification); the exact direction is the proof
    if exact.z is None:  # pragma: no cover - an exact unobservable verdict with proof has z
        raise RuntimeError("the exact unobservable verdict carries no direction z")
    witness = {
        "z": exact.z,
        "z_exact_integers": [str(v) for v in exact.z_exact or []],
        "unobservable_dimension": None,
        "unobservable_eigenvalues": [],
        "residual": unobservable_residual(A, C, exact.z),
        "meaning": "C A^k z = 0 exactly for every k (z_exact, checked in integer arithmetic): "
        "x0 and x0 + z give identical outputs",
    }
    return out.check(
        ObservabilityCode.EXACTLY_UNOBSERVABLE,
        "(A, C) is not observable: exact arithmetic on the data finds a state direction that "
        "produces no output (floating point could not resolve it).",
        None,
        None,
        witness,
    )


def _exactly_observable(out: _Verdicts, n: int) -> Check:
    """Inconclusive: unobservable in floating point, observable with the data taken exactly."""
    out.evidence["distance_to_unobservability"] = out.margin
    distance = format_distance(out.margin)
    return out.check(
        ObservabilityCode.WITHIN_PRECISION,
        f"In floating point (A, C) looks unobservable, but the exact data are observable "
        f"(Krylov rank {n} modulo a prime): the plant is within a relative distance "
        f"{distance} of an unobservable one, within the precision of the floating-point "
        f"rank decision, so the answer depends on digits the data do not have.",
        None,
        None,
    )


def _observable(out: _Verdicts, index: int, exact_state: Observability, grouping: str) -> Check:
    """Holds: PBH and the staircase agree on full rank, with the index and the margin."""
    confirmed = (
        " (confirmed in exact arithmetic)" if exact_state is Observability.OBSERVABLE else ""
    )
    if grouping:
        out.evidence["eigenvalue_grouping_ambiguous"] = grouping
        confirmed = (
            " (confirmed in exact arithmetic; how the eigenvalues group is ambiguous, but the "
            "PBH test has full rank at every one of them)"
        )
    return out.check(
        ObservabilityCode.OBSERVABLE,
        f"(A, C) is observable{confirmed}: x(0) is determined by {index} "
        f"step{'s' if index != 1 else ''} of output; PBH margin {out.margin:.3g}.",
        index,
        0,
    )


def _candidate_directions(
    A: np.ndarray,
    C: np.ndarray,
    eig: EigenAnalysis,
    alpha: float,
    pbh: _PBH,
    pbh_state: Observability,
    tol: Tolerances,
) -> tuple[list[tuple[np.ndarray, str, list]], Staircase]:
    """Candidate unobservable directions (PBH null vectors, then the conservative staircase's)."""
    candidates: list[tuple[np.ndarray, str, list]] = []
    if pbh_state is Observability.UNOBSERVABLE:
        unobservable = [
            {"eigenvalue": c.center / alpha, "pbh_margin": float(m)}
            for c, m, code in zip(eig.clusters, pbh.margins, pbh.codes)
            if code == ZERO
        ]
        for c, code in zip(eig.clusters, pbh.codes):
            if code == ZERO:
                candidates.append(
                    (_pbh_null_vector(A, C, c.center), "PBH null vector", unobservable)
                )
    conservative = staircase(A, C, tolerances=tol, error_model="compound")
    if not conservative.problem and conservative.rank < A.shape[0]:
        direction = conservative.unobservable_direction()
        if direction is None:  # pragma: no cover - None only at full rank
            raise RuntimeError("a rank-deficient staircase has no unobservable direction")
        candidates.append((direction, "staircase", []))
    return candidates, conservative


def _verified_direction(
    out: _Verdicts,
    A: np.ndarray,
    C: np.ndarray,
    candidates: list[tuple[np.ndarray, str, list]],
    unobs: int,
    stair_state: Observability,
    exact: ExactObservability,
    tol: Tolerances,
    to_user: Callable[[np.ndarray], np.ndarray],
) -> Check | None:
    """Fails on the first candidate that simulation confirms (on the balanced plant (A, C));
    None when none survives.  The witness z is in the user's coordinates (``to_user``)."""
    for z, source, eigenvalues in candidates:
        residual = unobservable_residual(A, C, z)
        if residual <= tol.witness_rtol:
            out.evidence["unobservable_direction_source"] = source
            witness = {
                "z": to_user(z),
                "unobservable_dimension": unobs,
                "unobservable_eigenvalues": eigenvalues,
                "residual": residual,
                "meaning": "C A^k z = 0 for every k: x0 and x0 + z give identical outputs",
            }
            if exact.state is Observability.UNOBSERVABLE:
                witness["z_exact_integers"] = [str(v) for v in exact.z_exact or []]
                witness["exact_check"] = "an exact unobservable direction, checked in integers"
            how = [] if stair_state is Observability.UNOBSERVABLE else ["by simulation"]
            if exact.state is Observability.UNOBSERVABLE:
                how.append("in exact arithmetic")
            note = f" (confirmed {' and '.join(how)})" if how else ""
            return out.check(
                ObservabilityCode.UNOBSERVABLE,
                f"(A, C) is not observable: a {unobs}-dimensional subspace of states produces "
                f"no output{note}.",
                None,
                unobs,
                witness,
            )
        out.evidence.setdefault("rejected_directions", []).append(
            {"source": source, "residual": residual}
        )
    return None


def _undecided(
    out: _Verdicts,
    notes: list[str],
    pbh_state: Observability,
    stair_state: Observability,
    directions_tried: bool,
) -> Check:
    """Inconclusive, with why neither method's answer could be trusted."""
    reasons = list(notes)
    if pbh_state is not stair_state and Observability.UNKNOWN not in (pbh_state, stair_state):
        reasons.append(f"PBH says {pbh_state} but the staircase says {stair_state}")
    if stair_state is Observability.OBSERVABLE and pbh_state is Observability.UNKNOWN:
        reasons.append("the staircase finds full rank but the PBH test cannot confirm it")
    if directions_tried:
        reasons.append("no unobservable direction survived the simulation check")
    return out.check(
        ObservabilityCode.UNDECIDED,
        "Observability could not be decided reliably: " + "; ".join(reasons) + ".",
        None,
        None,
    )


def _pbh_null_vector(A: np.ndarray, C: np.ndarray, lam: complex) -> np.ndarray:
    """Real unit vector from the null space of [A - lambda I; C]."""
    n = A.shape[0]
    shift = lam.real if lam.imag == 0 else lam
    _, _, vh = np.linalg.svd(np.vstack([A - shift * np.eye(n), C]))
    v = vh[-1].conj()
    z = v.real if np.linalg.norm(v.real) >= np.linalg.norm(v.imag) else v.imag
    return np.real(z) / np.linalg.norm(z)


def unobservable_residual(A: np.ndarray, C: np.ndarray, z: np.ndarray) -> float:
    """max over k < n of ||C A^k z|| / (||C|| ||A^k z||), by simulating z forward.

    Zero (to rounding) exactly when z is unobservable; steps where A^k z
    has vanished (nilpotent parts) are skipped.
    """
    n = A.shape[0]
    normC = max(float(np.linalg.norm(C, 2)), np.finfo(float).tiny)
    w = np.asarray(z, dtype=float)
    start = float(np.linalg.norm(w))
    worst = 0.0
    for _ in range(n):
        size = float(np.linalg.norm(w))
        if size <= 1e-12 * start:
            break
        worst = max(worst, float(np.linalg.norm(C @ w)) / (normC * size))
        w = A @ w
    return worst
