"""The words of the region of attraction: every sentence written from a ``Region``.

``ssecert.stability.roa`` and ``ssecert.stability.piecewise`` return
``Region`` outcomes (a radius, a ``RegionCode`` and the numbers behind
them); this module alone turns them into the reason, the summary and the
JSON record of the ``region_of_attraction`` check, so that rewording a
sentence here changes no verdict.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..observers.lure import scaling_text
from ..results import Check, Verdict
from .outcomes import Region, RegionCode
from .piecewise import MAX_CHANNELS, MAX_STATES

__all__ = [
    "global_region_check",
    "inner_steps_region_check",
    "lure_region_check",
    "reason",
    "record",
    "refused_region_check",
]

TITLE = "Certified region of attraction"
_NONE = "No region of attraction is certified: "


def reason(region: Region) -> str:
    """Why ``region`` certifies no radius (empty for a certified one)."""
    facts = region.facts
    code = region.code
    if code is RegionCode.NOT_ATTEMPTED:
        if "channels" in facts:  # the piecewise search's own limits
            return (
                f"not attempted: {facts['channels']} soft-threshold channels and "
                f"{facts['states']} error states (the piecewise search handles up to "
                f"{MAX_CHANNELS} and {MAX_STATES})"
            )
        refusal = str(facts["refusal"])
        return refusal if facts.get("as_given") else f"not attempted: {refusal}"
    if code is RegionCode.NO_DEAD_ZONE:
        return (
            "the observer has no soft threshold"
            if facts.get("piecewise")
            else "the observer has no dead zone (no soft threshold)"
        )
    if code in (RegionCode.DEAD_ZONE_UNSTABLE, RegionCode.NO_VERIFIED_LYAPUNOV):
        dynamics = (
            "xi+ = A xi, whose eigenvalues are those of F = A - L C and 0"
            if facts.get("error_block")
            else "xi+ = A xi"
        )
        why = "is not stable" if code is RegionCode.DEAD_ZONE_UNSTABLE else "has no verified P"
        return f"the linear dynamics of the dead zone ({dynamics}) {why}: {facts['lyapunov']}"
    if code is RegionCode.LEVEL_OUT_OF_RANGE and facts.get("unreached"):
        return (
            "no threshold input depends on the error (every row of the dead zone's inputs is "
            "zero), so no level bounds a region; this check claims none"
        )
    if code is RegionCode.LEVEL_OUT_OF_RANGE:
        return (
            "the dead zone's level set is out of floating-point range "
            f"(threshold {facts['threshold']:.3g})"
        )
    if code is RegionCode.NO_INVARIANT_SET:
        return "the dead zone holds no invariant sublevel set"
    if code is RegionCode.EXACT_RECHECK_FAILED:
        return f"the region did not survive its exact re-check ({', '.join(facts['refuted'])})"
    if code is RegionCode.REPLAY_LEFT_SET:
        return (
            "a simulated initial error on the certified sphere left the invariant set (please "
            "report this design)"
        )
    if code is RegionCode.BALL_OUT_OF_RANGE:
        return "the ball searched is out of floating-point range"
    if code is RegionCode.WITHIN_FLOOR:
        return f"every radius tried is within {facts['floor']:.4g}"
    if code is RegionCode.MAPS_OUT_OF_RANGE:
        return "the regions' maps are out of floating-point range"
    if code is RegionCode.NO_PIECEWISE_FUNCTION:
        return "no piecewise-quadratic Lyapunov function verified"
    if code is RegionCode.PIECEWISE_REPLAY_FAILED:
        return (
            "a simulated initial error inside the certified radius did not converge (please "
            "report this design)"
        )
    if code is RegionCode.SIMULATOR_REPLAY_FAILED:
        return "a simulated initial error inside the radius left the dead zone"
    return ""


def record(region: Region) -> dict[str, Any]:
    """The region as the certificate's JSON shows it: the radius, for a radius of 0 whether the
    dead zone is unstable (where its Lyapunov analysis was the reason) and the reason, then
    the evidence (a nested ``Region`` as its own record, without its radius)."""
    out: dict[str, Any] = {"radius": region.radius}
    if region.radius <= 0:
        if region.unstable is not None:
            out["unstable"] = region.unstable
        out["reason"] = reason(region)
    for key, value in region.evidence.items():
        out[key] = _without_radius(record(value)) if isinstance(value, Region) else value
    return out


def _without_radius(rec: Mapping[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in rec.items() if k != "radius"}


def _check(region: Region, proved: str, method: str, evidence: Mapping[str, Any]) -> Check:
    """The region_of_attraction check of ``region``: holds with the sentence ``proved``,
    otherwise the reason (fails only where the dead zone is proved unstable)."""
    verdict = region.verdict
    summary = proved if verdict is Verdict.HOLDS else f"{_NONE}{reason(region)}."
    return Check(
        id="region_of_attraction",
        title=TITLE,
        verdict=verdict,
        summary=summary,
        value=region.radius,
        margin=evidence.get("lyapunov_margin", evidence.get("margin")),
        method=method,
        required=False,
        fields={"radius": region.radius},
        evidence=evidence,
        code=region.code,
    )


def refused_region_check(region: Region) -> Check:
    """No region searched: the Lur'e model or the dead zone's model is refused by its size."""
    return _check(region, "", "dead zone (not attempted)", _without_radius(record(region)))


def lure_region_check(region: Region) -> Check:
    """The region of a design with a Lur'e model (``region_of_attraction``)."""
    evidence = _without_radius(record(region))
    radius = region.radius
    balanced = ""
    if "state_scaling" in evidence:
        balanced = (
            f" Proved in balanced coordinates xi = {scaling_text(evidence['state_scaling'])} "
            f"xi_b (the states' units differ widely) for ||e_b(0)|| <= "
            f"{evidence['balanced_radius']:.4g}, which holds whenever ||e(0)|| <= {radius:.4g}; "
            f"the other numbers are in those coordinates."
        )
    if region.code is RegionCode.PIECEWISE_CERTIFIED:
        return _check(
            region,
            f"From every initial estimation error with ||e(0)|| <= {radius:.4g} (a_hat(0) = 0) "
            f"the error converges to 0 without attack: a piecewise-quadratic Lyapunov function "
            f"over the soft threshold's regions, verified in numpy, decreases along every step "
            f"inside the ball of radius {evidence['ball']:.4g} and its sublevel set containing "
            f"those errors stays in that ball ({evidence['transitions']} transitions between "
            f"regions checked; the dead zone alone certifies {evidence['dead_zone_radius']:.4g}); "
            f"{evidence['replay']['samples']} initial errors on that sphere, simulated, converge."
            + balanced,
            "piecewise-quadratic Lyapunov function (S-procedure LMIs)",
            evidence,
        )
    return _check(
        region,
        f"From every initial estimation error with ||e(0)|| <= {radius:.4g} (a_hat(0) = 0) the "
        f"error converges to 0 without attack: the largest sublevel set of a verified "
        f"Lyapunov function of the dead zone's linear dynamics that fits in the dead zone "
        f"(|Cw_i xi| <= threshold) is invariant; {evidence.get('replay', {}).get('samples')} "
        f"initial errors on that sphere, simulated, stay in it." + balanced,
        "invariant sublevel set of the dead zone (Lyapunov)",
        evidence,
    )


def inner_steps_region_check(region: Region, channels: int) -> Check:
    """The region of a design known only in its dead zone (an SSO with several inner steps per
    sample), replayed through the observer's own simulator."""
    evidence = _without_radius(record(region))
    return _check(
        region,
        f"From every initial estimation error with ||e(0)|| <= {region.radius:.4g} (a_hat(0) = "
        f"0) the error converges to 0 without attack: while every inner step's soft threshold "
        f"stays in its dead zone the error follows e+ = A (I - step S' S)^m e, and the largest "
        f"sublevel set of its verified Lyapunov function inside all {channels} dead-zone slabs "
        f"is invariant; {evidence.get('replay', {}).get('samples')} initial errors on that "
        f"sphere, run through the observer's own simulator, keep a_hat = 0 and converge.",
        "invariant sublevel set of the dead zone of every inner step (Lyapunov)",
        evidence,
    )


def global_region_check(alone: Check, region: Region) -> Check:
    """Every initial error: observer_stability's certificate is global; ``alone`` is the check
    of the dead zone (and piecewise function) alone, ``region`` its outcome."""
    words = f"{alone.value:.4g}." if region.radius > 0 else f"no radius: {reason(region)}."
    return Check(
        id=alone.id,
        title=alone.title,
        verdict=Verdict.HOLDS,
        summary="From every initial error the error converges to 0 without attack: "
        f"observer_stability's certificate is global. (Its dead zone alone certifies {words})",
        value=float("inf"),
        margin=alone.margin,
        method=alone.method if region.radius > 0 else "observer_stability's global certificate",
        required=alone.required,
        fields={"radius": float("inf")},
        evidence={**alone.evidence, "dead_zone_radius": alone.value},
    )
