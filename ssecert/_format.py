"""Numbers in messages: short, but never on the wrong side of the threshold they are compared with."""

from __future__ import annotations

import math

__all__ = ["sig", "distance", "one_minus"]


def sig(x: float, digits: int = 4, versus: float = 1.0) -> str:
    """``x`` in ``digits`` significant digits, more when fewer would misplace it against ``versus``.

    A spectral radius of 0.9999994 printed with four digits reads "1", and an
    irrepresentable constant of 1 - 2^-40 reads "1 < 1".  Digits are added
    until the printed number lies on the same side of ``versus`` as ``x``
    (at most 17, which round-trips every double).

    Examples
    --------
    >>> sig(0.9999994)
    '0.999999'
    >>> sig(0.5), sig(1.0), sig(2.0, versus=2.0000001)
    ('0.5', '1', '2')
    """
    x = float(x)
    text = f"{x:.{digits}g}"
    if not math.isfinite(x) or x == versus:
        return text
    side = x > versus
    while digits < 17:
        shown = float(text)
        if shown != versus and (shown > versus) == side:
            break
        digits += 1
        text = f"{x:.{digits}g}"
    return text


def distance(x: float | None) -> str:
    """A relative distance to degeneracy: computed values below the rounding level say so.

    A PBH singular value computed as 0 (or 1e-17) at a computed eigenvalue
    only says the distance is at most about the rounding level; the exact
    data may still be non-degenerate, so "0" would claim too much.

    Examples
    --------
    A distance above it is also given in units of eps, so that "within floating-point
    precision" can be read against it.

    >>> distance(0.0), distance(3.1e-12)
    ('below the rounding level 2.2e-16', '3.1e-12, 1.4e+04 eps')
    """
    eps = 2.0**-52
    if x is None:
        return "unknown"
    if not x >= eps:  # also NaN
        return f"below the rounding level {eps:.1e}"
    return f"{x:.1e}, {x / eps:.2g} eps"


def one_minus(gap: float) -> str:
    """The number 1 - gap in words that show how far below 1 it is.

    A factor 1 - 1.65e-7 printed with six digits reads "1"; below a gap of 1e-3 the gap is
    written out.

    Examples
    --------
    >>> one_minus(1.65e-7), one_minus(0.25)
    ('1 - 1.65e-07', '0.75')
    """
    gap = float(gap)
    if math.isfinite(gap) and 0 < gap < 1e-3:
        return f"1 - {gap:.3g}"
    return sig(1.0 - gap, 6)
