"""The words of the gain synthesis: how a solve ended, written from its code and numbers.

``ssecert.design.synthesis`` decides on the solve (a gain or none) and records how it ended as
a ``SynthesisCode``; this module alone writes the sentence (``GainSynthesis.status``), so that
rewording it changes no decision.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .outcomes import SynthesisCode

if TYPE_CHECKING:
    from ..budget import Refusal

__all__ = ["status_text"]


def status_text(
    code: SynthesisCode, solver: str, refusal: Refusal | None, rows: int, decay: float | None
) -> str:
    """How a synthesis ended: the solver's status when it ran to the end, else why not.

    Examples
    --------
    >>> from ssecert.design.outcomes import SynthesisCode
    >>> status_text(SynthesisCode.NO_DECAY, "", None, 0, 0.25)
    'no decay above 0.25 is feasible'
    """
    if code in (SynthesisCode.SOLVED, SynthesisCode.NOT_SOLVED):
        return solver
    if code is SynthesisCode.REFUSED:
        need, limit = (refusal.need, refusal.limit) if refusal is not None else (0.0, 0.0)
        return (
            f"refused: the synthesis LMI has {rows} rows; its interior-point system needs about "
            f"{need / 2**30:.3g} GiB, over the memory budget of {limit / 2**30:.3g} GiB"
        )
    if code is SynthesisCode.SOLVER_FAILED:
        return f"solver failed ({solver})"
    if code is SynthesisCode.NOT_FINITE:
        return "the solver's gain is not finite"
    if code is SynthesisCode.TIME_LIMIT:
        return "the time limit ended the bisection"
    return f"no decay above {decay:.3g} is feasible"
