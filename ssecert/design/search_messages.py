"""The words of ``ssecert design``'s choices: why a decay was imposed, from its rule and numbers,
why no design was certified, and how the synthesised design compares with the spec's own.

``ssecert.design.search`` chooses the decay on numbers (``DecayChoice``: a ``DecayCode`` and the
front's figures); this module alone writes the sentence, so that rewording it changes no choice.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from .outcomes import DecayChoice, DecayCode

__all__ = ["WORSE_RTOL", "comparison_summary", "comparison_words", "decay_text", "no_design_text"]

# a synthesised design is worse where its mean error over the horizon is more than 5% larger
# than the spec's own design's, better where more than 5% smaller, else no worse (a tie)
WORSE_RTOL = 0.05
_TIE = f"within {WORSE_RTOL:.0%}"

_NO_POINTS = "its solves failed, did not verify, or ran past its share of the time budget"


def decay_text(choice: DecayChoice) -> str:
    """Why the decay ``choice.alpha`` is imposed.

    Examples
    --------
    >>> from ssecert.design.outcomes import DecayChoice, DecayCode
    >>> decay_text(DecayChoice(0.36, DecayCode.TWICE_AS_FAST, 0.94, True, contraction=0.8))
    ... # doctest: +NORMALIZE_WHITESPACE
    "decay 0.36 per step imposed, the trade-off front's smallest certified gain whose decay
    is clearly faster than the plant's: error contraction 0.8 per step <= rho(A)^2 = 0.8836
    (the plant's own state: rho(A) = 0.94)"
    """
    code, rho, alpha = choice.code, choice.plant_radius, choice.alpha
    if code is DecayCode.TOO_FEW_POINTS:
        return (
            f"decay {alpha:g} per step imposed: the trade-off front has fewer than two "
            f"verified points ({_NO_POINTS})"
        )
    if code is DecayCode.NO_NOISE_BOUND:
        return (
            f"decay {alpha:g} per step imposed: no point of the trade-off front has a "
            f"certified ultimate error bound under the noise ({_NO_POINTS})"
        )
    if code is DecayCode.NO_NOISE:
        then = "" if choice.then is None else f"{decay_text(choice.then)}; "
        return f"{then}the noise bound is 0 at every point of the front (no noise)"
    contraction = choice.contraction if choice.contraction is not None else float("nan")
    if code is DecayCode.TWICE_AS_FAST:
        return (
            f"decay {alpha:.3g} per step imposed, the trade-off front's smallest "
            f"certified gain whose decay is clearly faster than the plant's: error "
            f"contraction {contraction:.4g} per step <= rho(A)^2 = "
            f"{rho**2:.4g} (the plant's own state: rho(A) = {rho:.4g})"
        )
    if code in (DecayCode.KNEE, DecayCode.FEW_FASTER):
        why = (
            f"the plant is not stable (rho(A) = {rho:.6g}): every certified decay is "
            "faster than its own"
            if not choice.plant_stable
            else f"no certified contraction reaches rho(A)^2 = {rho**2:.4g} (the "
            f"fastest: {choice.fastest:.4g})"
        )
        n = choice.faster
        where = (
            "the knee of the trade-off front"
            if code is DecayCode.KNEE
            else f"the smallest certified gain of the {n} verified point"
            f"{'' if n == 1 else 's'} of the front faster than the plant (too few for a knee)"
        )
        return (
            f"decay {alpha:.3g} per step imposed, {where} (error contraction "
            f"{contraction:.4g} per step; {why})"
        )
    if code is DecayCode.FASTEST:
        return (
            f"decay {alpha:.3g} per step imposed, the fastest the trade-off front "
            f"certifies (error contraction {contraction:.4g} per step); none is faster "
            f"than the plant's own (rho(A) = {rho:.4g})"
        )
    if code is DecayCode.SMALLEST_NOISE_BOUND:
        n = choice.faster if choice.faster < choice.verified else choice.verified
        among = f"the {n} verified point{'' if n == 1 else 's'} of the front" + (
            " faster than the plant" if choice.faster < choice.verified else ""
        )
    else:  # FASTEST_NOISE_BOUND
        among = f"the fastest of the front, none being faster than the plant (rho(A) = {rho:.4g})"
    bound = choice.noise_bound if choice.noise_bound is not None else float("nan")
    return (
        f"decay {alpha:.3g} per step imposed, the smallest certified ultimate error "
        f"bound under noise ({bound:.3g} for the grid's middle design at that "
        f"decay) of {among} (error contraction {contraction:.4g} per step)"
    )


def no_design_text(
    kind: str, tried: int, rejections: Sequence[str], modes: Sequence[complex | float]
) -> str:
    """Why no design of ``kind`` was certified: the ``tried`` candidates' distinct
    ``rejections`` and the plant's unobservable modes that are not stable (``modes``).

    Examples
    --------
    >>> no_design_text("dsso", 4, ["observer_stability inconclusive"], [])
    'no dsso design of the 4 tried was certified: observer_stability inconclusive'
    """
    reason = f"no {kind} design of the {tried} tried was certified: {'; '.join(rejections)}"
    if modes:
        reason += (
            f"; the plant has an unobservable mode that is not stable (eigenvalue "
            f"{', '.join(f'{m:.4g}' for m in modes)}): no observer's error can converge"
        )
    return reason


def comparison_words(comparison: str) -> str:
    """A scenario's comparison (better, no worse, worse) with the tolerance it rests on.

    >>> comparison_words("no worse"), comparison_words("better")
    ('no worse (within 5%)', 'better (more than 5% smaller)')
    """
    rule = {
        "better": f"more than {WORSE_RTOL:.0%} smaller",
        "no worse": _TIE,
        "worse": f"more than {WORSE_RTOL:.0%} larger",
    }.get(comparison)
    return comparison if rule is None else f"{comparison} ({rule})"


def comparison_summary(
    own: bool,
    scenarios: int,
    compared: int,
    worse: Sequence[str],
    apart: Sequence[str],
    noise: tuple[float, float] | None,
    region: tuple[float, float] | None = None,
) -> str:
    """How the synthesised design's simulated error compares with the spec's own design's.

    Parameters
    ----------
    own : bool
        Whether the spec has an observer of its own.
    scenarios : int
        The scenarios the synthesised design ran.
    compared : int
        Those both designs simulated to a finite error.
    worse : sequence of str
        The compared scenarios where the synthesised design's error is worse.
    apart : sequence of str
        The scenarios not compared (skipped, a simulation that overflowed, or one whose
        errors are the floats' rounding of an unstable plant's huge state).
    noise : tuple of float or None
        The certified ultimate errors under the noise (the spec's own design's, the
        synthesised one's) when the spec's own is the smaller, else None.
    region : tuple of float or None
        The certified regions of attraction (the spec's own design's, the synthesised
        one's, 0 for none, inf for a design whose observer_stability holds) when the spec's
        own is the larger, else None.

    Examples
    --------
    >>> summary = comparison_summary(True, 0, 0, [], [], None, (math.inf, 7.071))
    >>> print(summary)  # doctest: +NORMALIZE_WHITESPACE
    The spec has no scenarios: the designs were not simulated. The spec's own design has the
    larger certified region of attraction (every initial error: its observer_stability
    holds, against radius 7.071).
    """
    if not own:
        summary = "The spec has no observer of its own: the synthesised design alone is shown."
    elif not scenarios:
        summary = "The spec has no scenarios: the designs were not simulated."
    elif not compared:
        summary = "No scenario was simulated to a finite, resolved error for both designs."
    elif worse:
        summary = (
            f"The synthesised design's mean error ||x_hat - x|| over the horizon is worse than "
            f"the spec's own design's (more than {WORSE_RTOL:.0%} larger) in {len(worse)} of "
            f"{compared} scenarios compared ({', '.join(worse)}); no worse ({_TIE}, or "
            "smaller) in the others (same seeds: the same plant trajectories and attacks)."
        )
    else:
        summary = (
            f"The synthesised design's mean error ||x_hat - x|| over the horizon is no worse "
            f"({_TIE}, or smaller) than the spec's own design's in every one of the "
            f"{compared} scenarios compared (same seeds: the same plant trajectories and "
            "attacks)."
        )
    if own and apart:
        summary += (
            f" Not compared ({', '.join(apart)}): a scenario skipped, a simulation that "
            "overflowed, or errors that are the floats' rounding of an unstable plant's state "
            "(see the scenario's notes), for at least one of the designs."
        )
    if noise is not None:
        theirs, ours = noise
        summary += (
            f" The spec's own design has the smaller certified ultimate error under the noise "
            f"({theirs:.4g} against {ours:.4g})."
        )
    if region is not None:
        theirs, ours = region
        against = f"{ours:.4g}{' (none certified)' if ours == 0 else ''}"
        summary += (
            " The spec's own design has the larger certified region of attraction ("
            + (
                f"every initial error: its observer_stability holds, against radius {against}"
                if math.isinf(theirs)
                else f"radius {theirs:.4g} against {against}"
            )
            + ")."
        )
    return summary
