"""The agreement line of an experiment, computed from the numbers it compares."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum

__all__ = ["Agreement", "Match", "agreement"]


class Match(Enum):
    """How our numbers compare with the document's."""

    REPRODUCED = "reproduced"
    CLOSE = "close"
    DIFFERS = "differs"
    NOT_COMPARABLE = "not comparable"
    NOT_RUN = "not run"


@dataclass(frozen=True)
class Agreement:
    """``match`` and the sentence that says it; ``worst`` the key furthest from the
    document's and ``by`` its relative difference (numbers), ``disagree`` the claims ours do
    not reproduce."""

    match: Match
    words: str
    worst: str | None = None
    by: float | None = None
    disagree: tuple[str, ...] = ()


def _number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def agreement(
    paper: Mapping[str, object],
    ours: Mapping[str, object],
    *,
    rtol: float = 0.05,
    close: float = 0.5,
    floor: float = 0.0,
) -> Agreement:
    """Compare our values with the document's, key by key.

    A number is reproduced within ``rtol`` of the document's (relative to
    the larger of its magnitude and ``floor``) and close within ``close``;
    a claim (bool) is reproduced when ours is the same.  Keys that either
    side leaves out (or None) are not compared.

    Examples
    --------
    >>> agreement({"error": 0.10, "exact": True}, {"error": 0.102, "exact": True}).words
    'reproduced: 2 values, every number within 5% (the furthest, error, by 2%)'
    >>> agreement({"sparsest": 2, "exact": True}, {"sparsest": 2, "exact": True}).words
    'reproduced: 2 values, each the same'
    >>> agreement({"error": 0.10}, {"error": 0.3}).match
    <Match.DIFFERS: 'differs'>
    """
    keys = [
        k
        for k in paper
        if k in ours
        and paper[k] is not None
        and ours[k] is not None
        and (_number(paper[k]) == _number(ours[k]))
    ]
    if not keys:
        return Agreement(Match.NOT_COMPARABLE, "not comparable: no value reported by both")
    claims = [k for k in keys if not _number(paper[k])]
    disagree = tuple(k for k in claims if bool(paper[k]) != bool(ours[k]))
    gaps = {}
    for k in keys:
        if _number(paper[k]):
            a, b = float(paper[k]), float(ours[k])  # type: ignore[arg-type]
            scale = max(abs(a), floor)
            gaps[k] = 0.0 if a == b else (math.inf if scale == 0 else abs(b - a) / scale)
    worst = max(gaps, key=lambda k: gaps[k]) if gaps else None
    by = gaps[worst] if worst is not None else None
    counted = f"{len(keys)} value{'s' if len(keys) != 1 else ''}"
    furthest = "" if worst is None else f" (the furthest, {worst}, by {_percent(by)})"
    if disagree:
        return Agreement(
            Match.DIFFERS,
            f"differs: ours does not reproduce {', '.join(disagree)}"
            + ("" if not by else f"; the furthest number, {worst}, by {_percent(by)}"),
            worst,
            by,
            disagree,
        )
    if by is None or by == 0:
        same = "the same" if len(keys) == 1 else "each the same"
        return Agreement(Match.REPRODUCED, f"reproduced: {counted}, {same}", worst, by)
    if by <= rtol:
        within = f", every number within {_percent(rtol)}"
        return Agreement(Match.REPRODUCED, f"reproduced: {counted}{within}{furthest}", worst, by)
    if by <= close:
        return Agreement(
            Match.CLOSE, f"close: {counted} within {_percent(close)}{furthest}", worst, by
        )
    return Agreement(
        Match.DIFFERS, f"differs: {worst} by {_percent(by)} ({counted} compared)", worst, by
    )


def _percent(x: float | None) -> str:
    if x is None:
        return "-"
    if math.isinf(x):
        return "an infinite factor (the document's value is 0)"
    percent = 100 * x
    return f"{percent:.0f}%" if percent >= 10 else f"{percent:.2g}%"
