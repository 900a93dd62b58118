"""The words of the observer's noise bound: the ``observer_noise_bound`` check.

``ssecert.stability.noise_gain.linear_noise_bound`` returns a ``NoiseGain``
(numbers and a ``NoiseGainCode``); this module builds the check from a
linear observer's design and writes what a user reads.
"""

from __future__ import annotations

import math
from typing import Any

from ..base.format import readable
from ..noise import MeasurementNoise
from ..observers import ObserverDesign
from ..results import Check, Verdict
from .noise_gain import NoiseGain, NoiseGainCode, linear_noise_bound

__all__ = ["observer_noise_check", "reason", "applies_to"]

TITLE = "Ultimate error of the observer under noise"
VALUE_NAME = "certified ultimate bound of ||x_hat - x||_2"
METHOD = (
    "worst-case series sum_j |F^j L| eta in interval arithmetic, tail bounded by a power of F "
    "below 1 in norm"
)


def applies_to(design: ObserverDesign) -> bool:
    """Whether the observer is linear (no attack estimate, one sample at a time)."""
    return not design.sparse and design.window == 1


def reason(found: NoiseGain) -> str:
    """Why no bound is certified (empty for a certified one)."""
    if found.code is NoiseGainCode.NOT_CONTRACTIVE:
        return (
            "no power of F = A - L C is proved below 1 in norm within "
            f"{found.facts.get('max_terms', 0):,} steps (observer_gain decides its stability)"
        )
    if found.code is NoiseGainCode.OUT_OF_RANGE:
        return (
            "F, L or the noise bounds leave the floating-point range, or their rounding is unknown"
        )
    return ""


def _tightness(found: NoiseGain) -> str:
    """How close the bound is to the worst case reached, in words computed from both."""
    if found.lower <= 0:
        return ""
    if readable(found.lower) == readable(found.bound_inf):
        return ": the bound is the exact worst case to the digits shown"
    return f" (the worst case lies between, within {readable(found.bound_inf / found.lower)}x)"


def observer_noise_check(design: ObserverDesign, noise: MeasurementNoise) -> Check:
    """The ``observer_noise_bound`` check (advisory) of a linear observer: without attack, the
    error e+ = F e + L n eventually stays within the certified bound."""
    F = design.error_matrix
    kind = design.observer_kind
    rounding_F = kind.exact_error(design).rounding(F)
    rounding_L = kind.gain_rounding(design)
    found = linear_noise_bound(F, design.L, noise.eta, rounding_F=rounding_F, rounding_L=rounding_L)
    fields: dict[str, Any] = {
        "ultimate_bound": found.bound_2,
        "ultimate_bound_inf": found.bound_inf,
        "componentwise": found.componentwise,
        "lower_bound": found.lower,
        "noise": noise.to_dict(),
    }
    evidence: dict[str, Any] = {
        "reached_componentwise": found.reached,
        "terms": found.terms,
        "contraction_power": found.power,
        "contraction_bound": found.contraction,
        "tail_bound": found.tail,
        "rounding_F": rounding_F,
        "rounding_L": rounding_L,
        "code": found.code.value,
    }
    common: dict[str, Any] = {
        "id": "observer_noise_bound",
        "title": TITLE,
        "method": METHOD,
        "required": False,
        "value_name": VALUE_NAME,
        "fields": fields,
        "evidence": evidence,
    }
    if found.code is not NoiseGainCode.CERTIFIED:
        return Check(
            verdict=Verdict.INCONCLUSIVE,
            summary=f"No ultimate error bound under noise is certified: {reason(found)}.",
            value=math.inf,
            **common,
        )
    eta = noise.eta
    each = (
        f"{readable(float(eta[0]))} on every sample of every sensor"
        if eta.size and bool((eta == eta[0]).all())
        else "the spec's bound on every sample of each sensor"
    )
    per_sample = "" if noise.norm == "inf" else " (a window's 2-norm bound bounds each sample)"
    return Check(
        verdict=Verdict.HOLDS,
        summary=f"Without attack and with noise within {each}{per_sample}, the estimation "
        f"error eventually stays within {readable(found.bound_2)} (2-norm; each component within "
        f"{readable(found.bound_inf)} at most), whatever the initial error. Some noise within "
        f"the bounds drives a component to {readable(found.lower)}{_tightness(found)}.",
        value=found.bound_2,
        **common,
    )
