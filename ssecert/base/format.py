"""Numbers in messages: short, but never on the wrong side of the threshold they are compared with."""

from __future__ import annotations

import math
import re

__all__ = ["sig", "distance", "one_minus", "one_plus", "readable", "factor_above"]

# below this magnitude a number is shown with two significant digits: its digits are rounding
# noise, or it is read as "tiny" only
TINY = 1e-4


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


def one_plus(gap: float, base: int = 1) -> str:
    """The number base + gap in words that show how far above ``base`` it is.

    An exact trace 1 + 2^-60 is the float 1; below a relative gap of 1e-3 the gap is written
    out, as ``one_minus`` writes it below 1.

    Examples
    --------
    >>> one_plus(2.0**-60), one_plus(0.25), one_plus(1.7e-18, base=2)
    ('1 + 8.67e-19', '1.25', '2 + 1.7e-18')
    """
    gap = float(gap)
    if math.isfinite(gap) and 0 < gap < 1e-3 * base:
        return f"{base} + {gap:.3g}"
    return sig(base + gap, 6, versus=float(base))


def _exponent(text: str) -> str:
    """Python's exponent written as people write it: 1e+156 -> 1e156, 2.8e-05 -> 2.8e-5."""
    return re.sub(r"e([+-])0*(\d)", lambda m: "e" + ("-" if m[1] == "-" else "") + m[2], text)


def readable(x: float, digits: int = 4, *, versus: float | None = None) -> str:
    """``x`` as a report shows it: ``digits`` significant digits, never "-0", tiny numbers short.

    The exact value stays in the JSON; this is what a reader sees beside it.

    - 0 and -0 read "0"; a magnitude below 1e-4 gets two significant digits
      (2.77556e-17 reads "2.8e-17": next to quantities of order 1 its digits are noise);
    - exponents are written without "+" and leading zeros (1e156, 3.3e-16);
    - with ``versus`` (the number ``x`` is compared with), a number that would round onto or
      across it is written as its distance from it: a spectral radius 0.9999999999999997 with
      ``versus=1`` reads "1 - 3.3e-16", and never "1".

    Parameters
    ----------
    x : float
    digits : int, default 4
        Significant digits of numbers of magnitude 1e-4 and above.
    versus : float, optional
        The threshold whose side ``x`` lies on is the finding.

    Returns
    -------
    str

    Examples
    --------
    >>> readable(0.786123), readable(-0.0), readable(2.77556e-17), readable(4.895e120)
    ('0.7861', '0', '2.8e-17', '4.895e120')
    >>> readable(0.9999999999999997), readable(0.9999999999999997, versus=1.0)
    ('1', '1 - 3.3e-16')
    >>> readable(1.00000002, versus=1.0), readable(2.0000001, versus=2.0)
    ('1 + 2e-8', '2 + 1e-7')
    """
    x = float(x)
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    if x == 0:
        return "0"
    if abs(x) < TINY:
        text = f"{x:.2g}"
    else:
        text = f"{x:.{digits}g}"
    if versus is not None and x != versus:
        shown = float(text)
        if shown == versus or (shown > versus) != (x > versus):
            gap = abs(x - versus)
            sign = "+" if x > versus else "-"
            return f"{readable(versus, digits)} {sign} {_exponent(f'{gap:.2g}')}"
    return _exponent(text)


def factor_above(ratio: float) -> str:
    """How many times a bound is exceeded, in words: a large factor by its power of ten.

    Examples
    --------
    >>> factor_above(2.268 / 0.7313), factor_above(6.645e305)
    ('3.101', 'above 1e305')
    """
    ratio = float(ratio)
    if math.isfinite(ratio) and ratio >= 1e4:
        return f"above 1e{math.floor(math.log10(ratio))}"
    return readable(ratio)
