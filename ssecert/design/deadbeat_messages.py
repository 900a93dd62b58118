"""The words of the deadbeat tests: every sentence written from their numbers.

``ssecert.design.deadbeat`` decides nilpotency and the printed gain's
deadbeat property on numbers (indices, norms of powers, certified radius
bounds); this module alone says why a test is not conclusive or not
verified (read through ``Nilpotency.reason`` and ``DeadbeatCheck.reason``,
which call it), so that rewording a sentence here changes no decision.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..base.format import one_plus, sig

__all__ = ["deadbeat_reason", "nilpotency_reason"]


def nilpotency_reason(
    index: int | None, norms: Sequence[float], rtol: float, scale: float, conclusive: bool
) -> str:
    """Why the floating-point power test found no index, or not a clear one (empty when it
    did)."""
    if index is None:
        return f"||(F/s)^{len(norms)}|| = {norms[-1]:.2e} exceeds {rtol:.0e} (s = {scale:.3g})"
    if conclusive:
        return ""
    previous = norms[index - 2] if index > 1 else 1.0
    return (
        f"||(F/s)^{index - 1}|| = {previous:.2e} is not clearly above {rtol:.0e} (s = {scale:.3g})"
    )


def deadbeat_reason(
    *,
    index: int | None,
    conclusive: bool,
    relative: Sequence[float],
    rtol: float,
    complete: bool,
    radius_upper: float,
    radius_lower: float,
    radius_excess: float,
) -> str:
    """Why the printed gain's exact deadbeat test is not verified (empty when it is): no
    index, an index that is not clear, a spectral radius not certified below 1."""
    reasons = []
    if index is None:
        reasons.append(
            f"||F^k|| / ||A||^k stays above {rtol:.0e} up to k = {len(relative)}"
            + (f" (smallest {min(relative):.2e})" if relative else "")
            + ("" if complete else "; the exact powers stopped at their budget")
        )
    elif not conclusive:
        reasons.append(
            f"||F^{index - 1}|| / ||A||^{index - 1} = {relative[index - 2]:.2e} is "
            f"not clearly above {rtol:.0e}"
        )
    if radius_upper >= 1:
        if radius_lower > 1 or radius_excess > 0:
            excess = max(radius_lower - 1.0, radius_excess)
            reasons.append(
                f"the printed gain is unstable: exact traces of powers of A - L C prove "
                f"spectral radius >= {one_plus(excess)}"
            )
        else:
            reasons.append(
                f"the spectral radius of the printed A - L C is not certified below 1 (exact "
                f"bound {sig(radius_upper, 6)})"
            )
    return "; ".join(reasons)
