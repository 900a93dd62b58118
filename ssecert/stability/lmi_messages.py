"""The words of the LMI certificates: every sentence written from an ``LMICause`` and its facts.

``ssecert.stability.lmi`` and ``ssecert.stability.zames_falb`` return
``LMICertificate`` outcomes with an ``LMICode`` (how it came out, which the
checks decide on) and an ``LMICause`` (why, with the numbers in ``facts``);
this module alone writes the reason (read through
``LMICertificate.reason``, which calls it) and the notes a certificate
gathers on the way (a balanced retry, a second multiplier), so that
rewording a sentence here changes no verdict.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from ..base.format import sig
from .outcomes import LMICause, VerifyCode, VerifyProblem

__all__ = [
    "verify_text",
    "balanced_note",
    "corner_reason",
    "not_written_back",
    "reason",
    "UNPROVEN_INSTABILITY",
]

#: what a certificate search that found nothing adds, once
UNPROVEN_INSTABILITY = "; this does not show the observer is unstable"


def corner_reason(corner: Mapping[str, Any]) -> str:
    """Why no channel-wise certificate exists: a corner of the channels' sectors whose linear
    loop is unstable (``lmi.channel_vertex_instability``)."""
    gains = ", ".join(f"{k:g}" for k in corner["gains"])
    return (
        f"the linear loop with phi_i = k_i w_i, k = ({gains}), is in the sector channel by "
        f"channel and has spectral radius {sig(corner['spectral_radius'], 6)} > 1 "
        f"({corner['unstable_corners']} of the {corner['corners']} corners k in {{0, shrink}}^m "
        f"are unstable), so no certificate that treats the channels as separate sector or "
        f"slope-restricted nonlinearities (circle criterion, Zames-Falb multipliers) can exist"
    )


def not_written_back(exponent: int) -> str:
    """Why a certificate verified in balanced coordinates is not one in the spec's."""
    return (
        f"its P, written for the spec's coordinates (entries scaled by up to 2^{exponent}), "
        f"would leave the float range or lose digits"
    )


def balanced_note(scaling: str, why: str) -> str:
    """What a retry in balanced state coordinates ``xi = scaling xi_b`` found (``why``)."""
    return f"; in balanced state coordinates (xi = {scaling} xi_b): {why}"


def _attempts(attempts: Sequence[Mapping[str, Any]]) -> str:
    return "; ".join(f"{a['structure']}: {a['status']}" for a in attempts)


def _orders(attempts: Sequence[Mapping[str, Any]]) -> str:
    return "; ".join(
        f"order {a['order']}{', ' + a['coefficients'] if 'coefficients' in a else ''}: "
        f"{a['status']}"
        for a in attempts
    )


def _words(cause: LMICause, facts: Mapping[str, Any]) -> str:
    if cause is LMICause.CERTIFIED:
        return ""
    if cause is LMICause.REFUSED:
        return f"not attempted: {facts['refusal']}"
    if cause is LMICause.NOT_FINITE:
        return (
            "the error dynamics' matrices leave the float range (an entry of A - L C, the "
            "sector's vertex loop or the channels beyond 1.8e308): no certificate can be "
            "computed or verified in floating point"
        )
    if cause is LMICause.ERROR_MATRIX_UNSTABLE:
        where = (
            "near the origin the soft threshold is zero (dead zone), so the error follows "
            "e+ = F e and "
            if facts["channels"]
            else ""
        )
        return (
            f"the linear error matrix F = A - L C is not stable: {facts['decision']}; "
            f"{where}the origin is not asymptotically stable"
        )
    if cause is LMICause.ERROR_MATRIX_UNDECIDED:
        return (
            f"the computed spectral radius of F = A - L C is {facts['radius']:.12g}, and its "
            f"stability cannot be decided: {facts['decision']}; no certificate is attempted"
        )
    if cause is LMICause.VERTEX_WITHIN_ROUNDING:
        q = facts["q"]
        return (
            f"the linear loop phi = {q:g} w that the sector [0, {q:g}] contains has spectral "
            f"radius within rounding of 1 (computed {facts['radius']:.12g}; "
            f"{facts['decision']}): a sector certificate would have a margin below what "
            f"floating point can verify"
        )
    if cause is LMICause.IDENTITY_IN_SECTOR:
        rho = facts["radius"]
        how = (
            "proved in exact arithmetic"
            if facts.get("rigorous", True)
            else "by a floating-point estimate, not proved"
        )
        decided = f", {how} (that loop as F: {facts['decision']})" if facts.get("decision") else ""
        return (
            f"with shrink = 1 the sector [0, 1] contains the identity, and the linear loop it "
            f"then contains (computed spectral radius {sig(rho, 6)}) is not asymptotically "
            f"stable{decided}. It has an eigenvalue at 1 whenever A does (e = v, a_hat = -C v, "
            f"or -O_tau v over a window), so no sector certificate can exist, which does not "
            f"mean the observer is unstable. Shrink < 1 (the elastic-net observer) is what "
            f"makes a certificate possible"
        )
    if cause is LMICause.VERTEX_UNSTABLE:
        q = facts["q"]
        return (
            f"the sector [0, {q:g}] contains the linear map phi = {q:g} w, whose closed loop is "
            f"not asymptotically stable ({facts['decision']}); no sector certificate can exist"
        )
    if cause is LMICause.CORNER_UNSTABLE:
        return corner_reason(facts["corner"])
    if cause is LMICause.NO_NONLINEARITY:
        return "no nonlinearity"
    if cause is LMICause.CIRCLE_NOT_VERIFIED:
        return (
            "no circle-criterion certificate was found or verified (LMI "
            f"{_attempts(facts['attempts'])})"
        )
    if cause is LMICause.DISSIPATION_NOT_VERIFIED:
        return (
            f"no dissipation certificate was found or verified (LMI {_attempts(facts['attempts'])})"
        )
    if cause is LMICause.ZAMES_FALB_NOT_VERIFIED:
        return f"no Zames-Falb certificate was found or verified ({_orders(facts['attempts'])})"
    if cause is LMICause.ZAMES_FALB_NO_DISSIPATION:
        return f"no Zames-Falb dissipation certificate (order {facts['order']}: {facts['status']})"
    if cause is LMICause.ZAMES_FALB_GAIN_NOT_VERIFIED:
        return f"the Zames-Falb gain was not verified: {verify_text(facts['problem'])}"
    if cause is LMICause.P_OUT_OF_RANGE:
        return "the certificate's P leaves the float range in its balanced coordinates"
    if cause is LMICause.NOT_SCALED_BACK:
        return "the certificate does not scale back exactly"
    if cause is LMICause.NO_BASE:
        return "no circle certificate to build on"
    if cause is LMICause.DISSIPATION_OUT_OF_RANGE:
        return "the dissipation matrix of the circle certificate leaves the float range"
    if cause is LMICause.NO_FINITE_GAIN:
        return (
            "no finite gain from the circle certificate (the Schur complement in the attack "
            "is not defined for any scaling tried)"
        )
    if cause is LMICause.GAIN_NOT_VERIFIED:
        return f"gain not verified: {verify_text(facts['problem'])}"
    raise ValueError(f"no words for {cause!r}")  # pragma: no cover - every cause has words


def reason(cause: LMICause, facts: Mapping[str, Any]) -> str:
    """Why a certificate of ``cause`` came out as it did (empty for a certified one), with the
    notes it gathered (``facts["notes"]``: balanced retries, a second multiplier) after."""
    return _words(cause, facts) + "".join(facts.get("notes", ()))


def verify_text(problem: VerifyProblem | None) -> str:
    """Why a recomputed certificate is not verified, in one clause (empty for None: a verified
    certificate has no problem)."""
    if problem is None:
        return ""
    f, code = problem.facts, problem.code
    if code is VerifyCode.NON_FINITE:
        return "the certificate has non-finite entries"
    if code is VerifyCode.NEGATIVE_MULTIPLIER:
        return f"a multiplier is negative ({f['value']:.2e})"
    if code is VerifyCode.CHANNEL_SHORT:
        return (
            f"channel {f['channel']}: m0 = {f['m0']:.3e} is not above the sum of the delayed "
            f"coefficients' magnitudes {f['total']:.3e}"
        )
    if code is VerifyCode.NOT_CLEARLY_DEFINITE:
        return f"P is not clearly positive definite (lambda_min {f['smallest']:.2e})"
    if code is VerifyCode.CHOLESKY_FAILED:
        return "P fails the Cholesky test"
    if code is VerifyCode.MARGIN_NOT_CLEAR:
        return (
            f"the recomputed LMI has largest eigenvalue {-f['margin']:.2e} ||P||, not below "
            f"-{f['clear']:g} x the error bound {f['bound']:.2e}"
        )
    raise ValueError(f"no words for {code}")  # pragma: no cover - every code has words
