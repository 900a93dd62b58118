"""Numbers in messages never land on the wrong side of the threshold they are compared with."""

import numpy as np
import pytest

from ssecert import System
from ssecert._format import sig
from ssecert.observers import build_observer
from ssecert.stability.checks import observer_gain_check


@pytest.mark.parametrize("x", [1 - 6e-7, 1 - 2**-40, 1 + 2**-52, 1 - 2**-53, 0.99995, 1.00005])
def test_sig_keeps_the_side_of_one(x):
    shown = float(sig(x))
    assert shown != 1.0 and (shown > 1.0) == (x > 1.0)


@pytest.mark.parametrize("x, versus", [(0.1, 0.1 + 1e-12), (2.5, 2.5 - 1e-9), (-1 + 1e-9, -1.0)])
def test_sig_keeps_the_side_of_any_threshold(x, versus):
    shown = float(sig(x, versus=versus))
    assert shown != versus and (shown > versus) == (x > versus)


def test_sig_is_short_away_from_the_threshold():
    assert sig(0.5) == "0.5" and sig(1.0) == "1" and sig(123456.0) == "1.235e+05"
    assert sig(float("inf")) == "inf" and sig(float("nan")) == "nan"


def test_a_radius_just_below_one_is_not_printed_as_one():
    system = System(A=np.array([[1.0]]), C=np.array([[1.0]]), name="slow")
    design = build_observer(system, {"kind": "luenberger", "gain": np.array([[6e-7]])})
    check = observer_gain_check(design)
    assert check.verdict.value == "holds"
    assert "spectral radius 1)" not in check.summary and "by 1 per" not in check.summary
    assert "0.999999" in check.summary, check.summary


def test_the_terminal_table_keeps_the_sign_of_infinity():
    from ssecert.report.table import _fmt

    assert (_fmt(float("inf")), _fmt(float("-inf")), _fmt(float("nan"))) == ("inf", "-inf", "-")
