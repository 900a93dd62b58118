"""The words of the thesis's chain of assumptions: every sentence written from an ``AssumptionCode``.

``ssecert.stability.thesis`` decides each item (Assumptions 1-3, Lemma 1,
the epsilon bound) on a code and the numbers behind it; this module alone
writes an item's reason (the numbers) and its finding (what a failing item
means for the thesis's theorem, in one clause), read through
``AssumptionResult.reason`` and ``AssumptionResult.finding``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..base.format import factor_above, readable, sig
from .outcomes import AssumptionCode as Code
from .outcomes import SearchStop, SeriesCode, SeriesFailure, StopCode

__all__ = ["finding", "reason", "search_stop", "series_failure", "why_not_evaluated"]

_PI = "Pi(a) = -sum F^(-l-1) L1 Psi_q^l(a)"


def _singular(why: str = "") -> str:
    """What a singular F means for the thesis's proof, in one clause."""
    return (
        f"Lemma 1 needs F = A + L1 C (= A - L C) invertible, and this gain makes it "
        f"singular{why}, so the map Pi its proof rests on does not exist"
    )


def _times(worst: float) -> str:
    """How far Assumption 3's left side exceeds a_hat' Q a_hat."""
    if worst >= 1e4:
        return f"exceeds a_hat' Q a_hat by a factor {factor_above(worst)}"
    return f"is {readable(worst, versus=1.0)} times a_hat' Q a_hat"


def _factor(facts: Mapping[str, Any]) -> str:
    """By how much the sampled ratio exceeds the claimed Lipschitz constant."""
    claimed = facts["claimed"]
    return factor_above(facts["ratio"] / claimed) if claimed > 0 else "without bound"


def reason(code: Code, facts: Mapping[str, Any]) -> str:
    """The numbers behind an item of ``code``."""
    f = facts
    if code is Code.NOT_ATTEMPTED:
        return f"not attempted: {f['refusal']}"
    if code is Code.NOT_CHECKED:
        return "observability not checked"
    if code is Code.OBSERVABLE:
        return "(A, C) is observable (see the observability check)"
    if code is Code.NOT_OBSERVABLE:
        return "(A, C) is not observable (see the observability check)"
    if code is Code.SHRINKAGE:
        return (
            "With Q = I (p x p; the thesis's n x n is a typo): Psi_q(0) = 0; |Psi_q(s)_i| = "
            f"q max(|s_i| - lambda, 0) < |s_i| for s_i != 0 (q = {f['q']:g}, lambda = "
            f"{f['lam']:g}), so Psi_q(s)' Q Psi_q(s) < s' Q s for s != 0; and Psi_q is Lipschitz "
            "with constant q because soft thresholding is 1-Lipschitz. The property (5.21) "
            "Psi_q(s)' Q Psi_q(s) <= q^2 s' Q s also holds for this diagonal Q (it can fail for a "
            "non-diagonal Q)."
        )
    if code is Code.F_AT_FLOAT_FLOOR:
        return (
            f"F = A + L1 C has smallest singular value {readable(f['smallest'])}, not small "
            f"against its own scale but at the bottom of the floating-point range: its inverse "
            f"(the series of Pi) cannot be formed in floating point, so Lemma 1 is not checked."
        )
    if code is Code.F_DEADBEAT:
        return (
            f"a deadbeat gain makes F = A + L1 C nilpotent, hence singular, so {_PI} does not "
            f"exist and the change of variable eta = e - Pi(a_hat) of the proof is unavailable "
            f"(the printed gain is the rounding of a deadbeat gain: its F is singular to "
            f"rounding, smallest singular value {readable(f['smallest'])})."
        )
    if code is Code.F_SINGULAR_TO_ROUNDING:
        return (
            f"F = A + L1 C is singular to rounding (smallest singular value "
            f"{readable(f['smallest'])}) but not shown singular in exact arithmetic, so whether "
            f"Pi exists (and its Lipschitz constant) cannot be decided in floating point."
        )
    if code is Code.F_SINGULAR:
        return (
            f"F = A + L1 C is singular (an exact kernel vector of F formed from the spec's data; "
            f"smallest computed singular value {readable(f['smallest'])}; every nilpotent F, as "
            f"a deadbeat gain makes it, is singular), so {_PI} does not exist and the change of "
            f"variable eta = e - Pi(a_hat) of the proof is unavailable."
        )
    if code is Code.LIPSCHITZ_EXCEEDED:
        return (
            f"the claimed Lipschitz constant ||L1|| / |lambda_max(F) - q| = "
            f"{readable(f['claimed'])} is exceeded by a factor {_factor(f)}: |Pi(a1) - Pi(a2)| "
            f"/ |a1 - a2| = {readable(f['ratio'])} for the pair in the counterexample"
        )
    if code is Code.LIPSCHITZ_PROVEN:
        return (
            f"Pi exists (the series is finite) and is Lipschitz with constant <= "
            f"{readable(f['correct'])} (= ||L1|| ||F^-1|| / (1 - q ||F^-1||)) <= the claimed "
            f"{readable(f['claimed'])}"
        )
    if code is Code.LIPSCHITZ_NOT_PROVEN:
        found = (
            f"sampling found ratios up to {readable(f['ratio'])}"
            if f.get("ratio") is not None
            else "no ratio could be sampled: "
            + why_not_evaluated(f["failure"], f["stopped"], "no pair could be evaluated")
        )
        return (
            f"Pi exists, but the claimed constant {readable(f['claimed'])} is not proven: the "
            f"series gives {readable(f['correct'])}; {found}"
        )
    if code is Code.NO_PI:
        if f["lemma_fails"]:
            return "it is stated in terms of Pi from Lemma 1, which does not exist for this gain"
        return "it is stated in terms of Pi from Lemma 1, which could not be formed here"
    if code is Code.NOT_CONTRACTING:
        return (
            f"for the a_hat in the counterexample the left side {_times(f['worst'])}, so no "
            f"rho'' < 1 works"
        )
    if code is Code.CONTRACTING:
        return (
            f"proven with rho'' = {readable(f['rho'], versus=1.0)} < 1 from |Psi_q(v)| <= q |v| "
            f"and the Lipschitz bound of Pi"
        )
    if code is Code.NOT_EVALUATED:
        why = why_not_evaluated(f["failure"], f["stopped"], "the ratio is not finite")
        return f"no proof, and no sample could be evaluated: {why}"
    if code is Code.NO_PROOF:
        return (
            f"no counterexample found (largest ratio found {readable(f['worst'])}) but no proof "
            f"either"
        )
    if code is Code.NEEDS_LEMMA:
        return "the bound (5.20) needs Lemma 1 and Assumption 3, which are not established here"
    if code is Code.F_NOT_CERTIFIED:
        return "F is not certified stable, so no P exists"
    star = sig(f["star"], versus=f["step"])
    if code is Code.STEP_WITHIN:
        return f"step = {f['step']:g} <= epsilon* = {star} (corrected constants)"
    return f"step = {f['step']:g} exceeds epsilon* = {star}; the bound is sufficient, not necessary"


def finding(code: Code, facts: Mapping[str, Any]) -> str:
    """What a failing item of ``code`` means for the thesis's theorem, in one clause (empty for
    the others)."""
    f = facts
    if code is Code.NOT_OBSERVABLE:
        return "Assumption 1, observability of (A, C), is not met"
    if code is Code.F_DEADBEAT:
        return _singular(" (a deadbeat gain makes it nilpotent)")
    if code is Code.F_SINGULAR:
        return _singular()
    if code is Code.LIPSCHITZ_EXCEEDED:
        correct = f["correct"]
        corrected = (
            f"; the bound its proof supports, ||L1|| ||F^-1|| / (1 - q ||F^-1||), is "
            f"{readable(correct)}"
            if correct < float("inf")
            else "; the bound its proof supports is infinite here (q ||F^-1|| >= 1)"
        )
        return (
            f"Lemma 1's printed Lipschitz constant of Pi, {readable(f['claimed'])}, is exceeded "
            f"by a factor {_factor(f)} on this design{corrected}"
        )
    if code is Code.NOT_CONTRACTING:
        return (
            "Assumption 3 (the attack estimate's map contracts, with a rho'' < 1) is not met: "
            f"for the a_hat in the evidence its left side {_times(f['worst'])}"
        )
    return ""


def series_failure(failure: SeriesFailure) -> str:
    """Why a point of a counterexample search could not be evaluated."""
    f, code = failure.facts, failure.code
    if code is SeriesCode.TOO_MANY_TERMS:
        limit = (
            f" (the cached powers F^-l L1 are bounded to {f['memory_mib']} MiB)"
            if f["memory_mib"] is not None
            else ""
        )
        return (
            f"the series for Pi needs {f['needed']:.3g} terms at max |a_i| = "
            f"{f['magnitude']:.3g} (threshold {f['threshold']:g}, shrink {f['shrink']:g}); at "
            f"most {f['most']:,} are summed{limit}"
        )
    if code is SeriesCode.POWERS_OVERFLOW:
        return (
            f"the powers of F^-1 overflow after {f['terms']} terms of the series for Pi "
            f"(||F^-1|| = {f['norm_F_inv']:.3g}); max |a_i| = {f['magnitude']:.3g} needs "
            f"{f['needed']:.3g}"
        )
    if code is SeriesCode.SUM_OVERFLOW:
        return "the series for Pi overflows"
    if code is SeriesCode.RATIO_NOT_FINITE:
        return "a non-finite ratio"
    raise ValueError(f"no words for {code}")  # pragma: no cover - every code has words


def search_stop(stop: SearchStop) -> str:
    """Why a counterexample search stopped before it finished."""
    code = stop.code
    if code is StopCode.BUDGET_SAMPLING:
        return "the search budget ran out during sampling"
    if code is StopCode.BUDGET_LOCAL:
        return "the search budget ran out during the local refinement"
    if code is StopCode.BUDGET_EQUATION_5_9:
        return "the search budget ran out before the (5.9) check"
    if code is StopCode.DIMENSION:
        return (
            f"no local refinement in dimension {stop.facts['dimension']} (> {stop.facts['most']})"
        )
    raise ValueError(f"no words for {code}")  # pragma: no cover - every code has words


def why_not_evaluated(failure: SeriesFailure | None, stop: SearchStop | None, default: str) -> str:
    """The first of: why a point could not be evaluated, why the search stopped, ``default``."""
    if failure is not None:
        return series_failure(failure)
    if stop is not None:
        return search_stop(stop)
    return default
