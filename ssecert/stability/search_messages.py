"""The words of the witness searches (``ssecert.stability.equilibria``, ``.periodic``): what
each looked at and found, written from its ``Searched`` record."""

from __future__ import annotations

from ..budget import format_count
from .outcomes import SearchCode, Searched

__all__ = ["searched_text"]


def searched_text(searched: Searched | None) -> str:
    """What a witness search looked at and found, in one clause (empty for None: not run)."""
    if searched is None:
        return ""
    text = _text(searched)
    return text + " (in balanced state coordinates)" if searched.balanced else text


def _text(searched: Searched) -> str:
    f, code = searched.facts, searched.code
    if code is SearchCode.NO_NONLINEARITY:
        if f.get("periodic"):
            return "no soft threshold: nothing to cycle"
        return "no nonlinearity: the only equilibrium of a stable linear map is 0"
    if code is SearchCode.REFUSED:
        return f"not searched: {f['refusal']}"
    if code is SearchCode.TOO_MANY_PATTERNS:
        return (
            f"not searched: 3^{f['m']} = {format_count(f['count'])} active/sign patterns exceed "
            f"{f['most']:,}"
        )
    if code is SearchCode.FIRST_FOUND:
        return f"{f['tried']:,} of {f['count']:,} active/sign patterns tried"
    if code is SearchCode.PATTERNS_TRIED:
        found, count = f["found"], f["count"]
        what = "equilibrium" if found == 1 else "equilibria"
        what = f"nonzero {what}" if f["nonzero"] else what
        note = (
            f"{found} {what} among the {count:,} active/sign patterns of the soft threshold"
            if found or not f["nonzero"]
            else f"none among the {count:,} active/sign patterns of the soft threshold"
        )
        if f["singular"]:
            note += f" ({f['singular']:,} with a singular or ill-conditioned system, not decided)"
        return note
    if code is SearchCode.MILP_NONE:
        if f["status"] == 2:
            what = "none (HiGHS found the patterns infeasible; a solver's claim, not re-checked)"
        elif f["status"] == 1:
            what = f"undecided (the search's time limit of {f['seconds']:g} s was reached)"
        else:
            what = f"undecided (the solver stopped: {f['message']})"
        refused = f["refused"]
        return (
            f"{what}: a mixed-integer search over the 3^{f['m']} active/sign patterns "
            f"(|w_i| <= {f['box']:g} thresholds, HiGHS)"
            + (f"; {refused} candidate pattern(s) refused by exact arithmetic" if refused else "")
        )
    if code is SearchCode.MILP_FOUND:
        return (
            f"found by a mixed-integer search over the 3^{f['m']} active/sign patterns (HiGHS), "
            "confirmed in exact arithmetic"
        )
    if code is SearchCode.MILP_REFUSED:
        ended = f"; its time limit of {f['seconds']:g} s ended it" if f["timed_out"] else ""
        return (
            f"undecided: a mixed-integer search over the 3^{f['m']} active/sign patterns found "
            f"{f['refused']} candidate patterns that exact arithmetic refused{ended}"
        )
    if code is SearchCode.LINEAR_SINGULAR:
        return "the linear error map has an eigenvalue 1: no unique equilibrium"
    if code is SearchCode.LINEAR_UNIQUE:
        return "the linear error dynamics' unique equilibrium"
    if code is SearchCode.ORBIT_FOUND:
        return (
            f"{f['samples']} initial errors simulated for {f['steps']} steps; the tail of one "
            f"repeats every {f['period']} steps and the orbit is confirmed exactly"
        )
    if code is SearchCode.NO_ORBIT:
        return (
            f"none: {f['samples']} initial errors simulated for {f['steps']} steps, "
            f"{f['alive']} neither converged nor diverged, {f['tried']} periodic tails failed "
            f"their exact confirmation"
        )
    raise ValueError(f"no words for {code}")  # pragma: no cover - every code has words
