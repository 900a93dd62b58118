"""The observer_gain check: is the gain what was asked for, and is F = A - L S stable?

Every number is about the gain as printed (F formed exactly from the floats
of A, L and S).  A deadbeat gain is judged by the power test its build ran;
the others by a Lyapunov certificate or the exact powers of F.  The helpers
that say what a check's verdict rests on are shared with the other
observer checks in ``ssecert.stability.checks``.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial
from typing import Any, NamedTuple

import numpy as np

from ..base.format import one_minus, one_plus
from ..design.gains import GainError, GainMethod
from ..numerics.exact_powers import ExactMatrix
from ..observers import ObserverDesign
from ..results import Check, Verdict
from ..system import System
from ..tolerances import Tolerances
from . import observer_messages
from .lyapunov import LyapunovMethod, lyapunov_certificate
from .outcomes import SchurCode, known
from .spectral import SchurState

__all__ = ["observer_gain_check", "EXACT_LIMIT"]


def _lyapunov_evidence(cert) -> dict[str, Any]:
    return {
        "P": cert.P,
        "decrease_P_minus_FtPF": cert.decrease,
        "margin": cert.margin,
        "error_bound": cert.error_bound,
        "contraction": cert.contraction,
        "condition_number_P": cert.condition,
        "residual": cert.residual,
        "margin_definition": (
            "lambda_min(P - F'PF) / ||P||, recomputed from P"
            if cert.method is LyapunovMethod.LYAPUNOV or cert.verdict is not Verdict.HOLDS
            else "1 - (certified upper bound on the spectral radius of the exact F)"
        ),
        "certificate": cert.method,
        "exact_decision": cert.proof,
    }


EXACT_LIMIT = 6  # largest n verified exactly in rational arithmetic


def _exact_deadbeat(system: System) -> dict[str, Any]:
    """The deadbeat construction redone in rationals on the exact values of the floats."""
    from ..design.gains import exact_deadbeat_gain

    try:
        exact = exact_deadbeat_gain(system.A.tolist(), system.C.tolist())
    except GainError as exc:
        return {"verified": False, "reason": str(exc)}
    return {
        "verified": exact.verified,
        "exact_index": exact.details["exact_index"],
        "L_exact": exact.details["L_exact"],
        "note": (
            "A and C taken as the exact rational values of their floating-point entries; "
            "F^k == 0 and F^(k-1) != 0 checked exactly"
        ),
    }


def _decided_by(tol: Tolerances, **extra: Any) -> dict[str, Any]:
    """The tolerances an observer check's verdict rests on, for its JSON."""
    return {"clear_factor": tol.certificate_clear, **extra}


def observer_gain_check(design: ObserverDesign, *, tolerances: Tolerances | None = None) -> Check:
    """Is the gain what was asked for, and is the linear error matrix F = A - L S stable?

    Every number is about the gain as printed: F is formed exactly from the
    floats of A, L and S.  For a deadbeat gain on a small plant the exact
    rational gain is also computed; it is evidence about the plant, and the
    verdict never rests on it.  ``tolerances.certificate_clear`` is the
    factor by which a Lyapunov decrease must beat its error bound.
    """
    tol = Tolerances.check(tolerances)
    gain = design.gain
    F = design.error_matrix
    if not np.all(np.isfinite(F)):
        return _overflowed_check(design, tol)
    computed_radius = float(np.abs(np.linalg.eigvals(F)).max())
    fields: dict[str, Any] = {"L": gain.L, "gain_method": gain.method, "kind": design.kind}
    title = f"Observer gain ({gain.method})"
    evidence: dict[str, Any] = {
        "details": gain.details,
        "computed_eigenvalue_radius": computed_radius,
    }
    if gain.method is GainMethod.DEADBEAT:
        return _deadbeat_check(design, fields, evidence, title)
    what = error_matrix_name(design)
    if what != "A - L C":
        evidence["error_matrix"] = (
            f"F = {what}: the error map of the {design.inner_steps} inner steps per sample "
            "(L is one inner step's gain, step A S')"
        )
    cert = lyapunov_certificate(F, exact=_exact(design), clear=tol.certificate_clear)
    fields["spectral_radius"] = cert.spectral_radius
    evidence.update(_lyapunov_evidence(cert))
    verdict = Verdict(cert.verdict)
    shown = exact_radius(cert)
    if verdict is Verdict.HOLDS and cert.method is not LyapunovMethod.LYAPUNOV:
        fields["spectral_radius"] = cert.contraction
    # the floats may have underflowed to zero (A (I - step S'S)^m, m large)
    summary = observer_messages.linear_gain_summary(cert, what, zero=not np.any(F))
    return Check(
        id="observer_gain",
        title=title,
        verdict=verdict,
        summary=summary,
        value=fields["spectral_radius"] if shown is None else shown.value,
        # (an exact instability has no margin: that of the Lyapunov solution that did not
        # verify is not "1 - spectral radius bound")
        margin=cert.margin
        if cert.method is LyapunovMethod.LYAPUNOV or verdict is Verdict.HOLDS
        else None,
        method="discrete Lyapunov (dlyap)"
        if cert.method is LyapunovMethod.LYAPUNOV
        else f"{cert.method.value} of {what}",
        # exact powers bound the spectral radius; their margin is that bound's distance from 1
        value_name=(
            shown.name.replace("A - L C", what)
            if shown is not None
            else ("" if what == "A - L C" else f"spectral radius of {what}")
        ),
        margin_name="" if cert.method is LyapunovMethod.LYAPUNOV else "1 - spectral radius bound",
        value_text="" if shown is None else shown.text,
        fields=fields,
        evidence=evidence,
        witness=cert.witness if verdict is Verdict.FAILS else None,
        tolerances=_decided_by(tol, error_bound=cert.error_bound),
        code=cert.decided_by,
    )


class ExactRadius(NamedTuple):
    """What an observer check shows as its value when the exact powers of F decided it."""

    value: float | None
    name: str
    text: str  # the value in words where its float rounds onto 1 ("" otherwise)


def exact_radius(cert: Any) -> ExactRadius | None:
    """The certified spectral radius bound an exact decision rests on, None without one.

    Stable: the upper bound, "1 - 8.67e-19" where its float is 1 (F = 1 - 2^-60); unstable:
    the lower bound, "1 + 8.67e-19" where the exact traces exceed n by less than a float
    resolves (F = 1 + 2^-60)."""
    proof = cert.proof or {}
    if cert.method is LyapunovMethod.LYAPUNOV or "state" not in proof:
        return None
    state = SchurState(proof["state"])  # the decision's, as ``SchurDecision.to_dict`` keeps it
    if state is SchurState.UNKNOWN:
        return None
    if state is SchurState.STABLE:
        upper, gap = proof["spectral_radius_upper_bound"], proof.get("spectral_radius_gap", 0.0)
        text = one_minus(gap) if upper >= 1.0 and gap > 0 else ""
        return ExactRadius(upper, "spectral radius bound of A - L C", text)
    lower, excess = proof["spectral_radius_lower_bound"], proof.get("spectral_radius_excess", 0.0)
    text = one_plus(excess) if lower <= 1.0 and excess > 0 else ""
    return ExactRadius(lower, "spectral radius lower bound of A - L C", text)


def _overflowed_check(design: ObserverDesign, tol: Tolerances) -> Check:
    """observer_gain of a design whose error matrix overflows in floating point (an SSO with
    many inner steps of a long step): inconclusive, saying so."""
    return Check(
        id="observer_gain",
        title=f"Observer gain ({design.gain.method})",
        verdict=Verdict.INCONCLUSIVE,
        summary=f"The stability of the error matrix could not be decided: {overflow_reason(design)}.",
        value=None,
        margin=None,
        method="none (the error matrix overflows)",
        fields={"L": design.gain.L, "gain_method": design.gain.method, "kind": design.kind},
        evidence={"details": design.gain.details},
        tolerances=_decided_by(tol),
        code=SchurCode.NON_FINITE,
    )


def error_matrix_name(design: ObserverDesign) -> str:
    """The design's linear error matrix in words: A - L C, or for an SSO with m inner steps
    per sample A (I - step S' S)^m (its L is one inner step's gain)."""
    return f"A (I - step S' S)^{design.inner_steps}" if design.inner_steps > 1 else "A - L C"


def overflow_reason(design: ObserverDesign) -> str:
    """Why the design's error matrix is not finite, in words."""
    what = error_matrix_name(design)
    return (
        f"{what} overflows in floating point (entries beyond 1e308), and its exact value is "
        f"beyond the budget of exact arithmetic"
    )


def _exact(design: ObserverDesign) -> ExactMatrix:
    """The exact error matrix of the spec's data, of which ``design.error_matrix`` is the
    rounding (formed on demand)."""
    return design.observer_kind.exact_error(design)


def _deadbeat_check(
    design: ObserverDesign, fields: dict[str, Any], evidence: dict[str, Any], title: str
) -> Check:
    """The observer_gain check of a deadbeat gain, from the power test its build ran."""
    details = design.gain.details
    exact_note = _exact_deadbeat_note(design, evidence)
    fields["nilpotency_index"] = details.get("nilpotency_index")
    fields["observability_index"] = details.get("observability_index")
    fields["spectral_radius"] = details.get("spectral_radius_upper_bound")
    fields["spectral_radius_lower_bound"] = details.get("spectral_radius_lower_bound")
    check = partial(
        Check,
        id="observer_gain",
        title=title,
        method="deadbeat (exact powers of the printed A - L C)",
        # the printed A - L C is nilpotent only where its exact powers vanish; else the index
        # counts the steps after which they vanish to rounding
        value_name="nilpotency index"
        if details.get("exactly_nilpotent")
        else "steps to vanish (to rounding)",
        margin_name="1 - spectral radius bound",
        fields=fields,
        evidence=evidence,
        tolerances=_deadbeat_tolerances(details),
    )
    if design.gain.verified:
        summary = _nilpotent_summary(details, fields) + exact_note
        upper = known(details.get("spectral_radius_upper_bound"))
        return check(
            verdict=Verdict.HOLDS,
            summary=summary,
            value=fields["nilpotency_index"],  # the exact index when it differs
            margin=1.0 - upper,
        )
    problem = details.get("problem") or "the power test did not conclude"
    witness = _deadbeat_instability(design)
    if witness is not None:
        return check(
            verdict=Verdict.FAILS,
            summary=observer_messages.deadbeat_failure(problem) + exact_note,
            value=details.get("nilpotency_index"),
            margin=None,
            witness=witness,
        )
    return check(
        verdict=Verdict.INCONCLUSIVE,
        summary=f"The deadbeat gain could not be verified for the printed L: {problem}."
        + exact_note,
        value=details.get("nilpotency_index"),
    )


def _exact_deadbeat_note(design: ObserverDesign, evidence: dict[str, Any]) -> str:
    """The summary's sentence on the exact rational gain (small plants; '' otherwise).

    The exact construction is recorded in ``evidence["exact"]``.
    """
    if design.system.n > EXACT_LIMIT:
        return ""
    evidence["exact"] = _exact_deadbeat(design.system)
    if not evidence["exact"].get("verified"):
        return ""
    return observer_messages.exact_deadbeat_note(evidence["exact"]["exact_index"])


def _deadbeat_tolerances(details: Mapping[str, Any]) -> dict[str, Any]:
    """The tolerances of the power test, which ran when the gain was built with the run's."""
    return {
        "deadbeat_rtol": details.get("deadbeat_rtol", Tolerances().deadbeat_rtol),
        "clear_factor": details.get("clear_factor", Tolerances().certificate_clear),
    }


def _nilpotent_summary(details: Mapping[str, Any], fields: dict[str, Any]) -> str:
    """What a verified deadbeat gain's check says (``observer_messages.nilpotent_summary``).

    An exact nilpotency index that differs from the index to rounding
    becomes ``fields["nilpotency_index"]``, beside
    ``nilpotency_index_to_rounding``.
    """
    index = int(known(details.get("nilpotency_index")))
    exact_index = details.get("exact_nilpotency_index")
    if details.get("exactly_nilpotent") and exact_index is not None and exact_index != index:
        fields["nilpotency_index"] = exact_index
        fields["nilpotency_index_to_rounding"] = index
    return observer_messages.nilpotent_summary(details)


def _deadbeat_instability(design: ObserverDesign) -> dict[str, Any] | None:
    """A verified instability witness of the printed A - L C, when its radius exceeds 1."""
    lower = design.gain.details.get("spectral_radius_lower_bound")
    if lower is None or not lower > 1:
        return None
    from .lyapunov import instability_witness

    witness = instability_witness(design.error_matrix, exact=_exact(design))
    if witness is not None and witness["verified"]:
        return witness
    return None
