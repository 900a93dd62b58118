"""Numbers in messages: short, but never on the wrong side of the threshold they are compared with."""

from __future__ import annotations

import math

__all__ = ["sig"]


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
