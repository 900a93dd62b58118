"""What a report shows of a check's verdict, value and margin: the terminal table and the HTML
report alike.

Numbers are rounded for people (``ssecert.base.format.readable``); the JSON keeps them exact.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..base.format import readable
from ..results import Check

__all__ = ["verdict_label", "verdict_class", "number", "value_text", "margin_text", "named"]

#: The number a check's value is compared with, where the side of it is the finding (a spectral
#: radius of 1 - 3e-16 must not read "1"); margins are compared with 0.
VALUE_VERSUS: Mapping[str, float] = {
    "irrepresentable": 1.0,
    "observer_gain": 1.0,
    "observer_stability": 1.0,
}

DOES_NOT_APPLY = "does not apply"


def verdict_label(check: Check) -> str:
    """The verdict as shown: "does not apply" for an advisory check whose sufficient condition
    is not met (``Check.applies``), else the verdict's name."""
    return check.verdict.value if check.applies else DOES_NOT_APPLY


def verdict_class(check: Check) -> str:
    """The CSS class of the verdict's badge (neutral for a check that does not apply)."""
    return check.verdict.value if check.applies else "not-applicable"


def number(value: Any, digits: int = 4, *, versus: float | None = None) -> str:
    """A scalar as a report shows it: rounded floats, integers and words as they are, "-" for
    None and NaN.

    Examples
    --------
    >>> number(0.9999999999999997), number(-0.0), number(None), number(3), number(float("inf"))
    ('1', '0', '-', '3', 'inf')
    >>> number({"re": 0.5, "im": -2.77556e-17})
    '0.5 - 2.8e-17j'
    """
    if value is None:
        return "-"
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return "-" if math.isnan(v) else readable(v, digits, versus=versus)
    if isinstance(value, Mapping) and set(value) == {"re", "im"}:
        value = complex(float(value["re"]), float(value["im"]))
    if isinstance(value, (complex, np.complexfloating)):
        real, imag = float(value.real), float(value.imag)
        if imag == 0:
            return readable(real, digits, versus=versus)
        sign = "-" if imag < 0 else "+"
        return f"{readable(real, digits)} {sign} {readable(abs(imag), digits)}j"
    return str(value)


def value_text(check: Check) -> str:
    """The check's headline value, rounded ("-" when it has none), or its words
    (``Check.value_text``) where the float cannot show the side of the threshold it is on."""
    return check.value_text or number(check.value, versus=VALUE_VERSUS.get(check.id))


def margin_text(check: Check) -> str:
    """The check's margin, rounded ("-" when it has none); one that rounds onto 1 without being
    1 (1 - a spectral radius of 2.2e-16) as its distance from it."""
    text = number(check.margin, versus=0.0)
    if text == "1" and check.margin is not None and float(check.margin) != 1.0:
        return number(check.margin, versus=1.0)
    return text


def named(name: str, text: str) -> str:
    """``name = text`` when there is a number to name, else the text alone ("-").

    >>> named("spectral radius of A - L C", "0.786"), named("LMI margin", "-")
    ('spectral radius of A - L C = 0.786', '-')
    """
    return f"{name} = {text}" if name and text != "-" else text
