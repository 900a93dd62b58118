"""Numbers in messages never land on the wrong side of the threshold they are compared with."""

import re

import numpy as np
import pytest

from ssecert import System
from ssecert.base.format import sig
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


def test_one_plus_writes_the_gap_above_one_out():
    from ssecert.base.format import one_plus

    assert one_plus(2.0**-60) == "1 + 8.67e-19"
    assert one_plus(2.0**-60, base=3) == "3 + 8.67e-19"
    assert one_plus(0.25) == "1.25" and one_plus(1e-7) == "1 + 1e-07"


def _exact_luenberger(A: float, gain: float):
    from ssecert.analyze import analyze
    from ssecert.spec import spec_from_dict

    spec = spec_from_dict(
        {
            "name": "exact",
            "system": {"A": [[A]], "C": [[1.0]]},
            "attack": {"max_attacked": 0},
            "observer": {"kind": "luenberger", "gain": [[gain]]},
        }
    )
    return analyze(spec)


def _shown(cert) -> dict[str, str]:
    """What the terminal table, the HTML report and the notebook card show of each check."""
    from ssecert.report.cells import value_text
    from ssecert.report.html import certificate_fragment
    from ssecert.report.table import render_table

    table, html = render_table(cert), certificate_fragment(cert)
    return {"table": table, "html": html, **{c.id: value_text(c) for c in cert.checks}}


def test_a_radius_bound_one_minus_2_to_the_minus_60_is_not_shown_as_one():
    # F = 1 - 2^-60 exactly: the float A - L C is 1.0, the exact powers bound rho by 1 - 8.67e-19
    cert = _exact_luenberger(1.0, 2.0**-60)
    shown = _shown(cert)
    for check in ("observer_gain", "observer_stability"):
        assert cert[check].verdict.value == "holds"
        assert cert[check].margin == pytest.approx(2.0**-60, rel=1e-12)
        assert shown[check] == "1 - 8.67e-19", shown[check]
        assert "1 - 8.67e-19 < 1" in cert[check].summary
    for where in ("table", "html"):
        text = shown[where].replace("</span> <span class='qnum'>", " = ")
        assert "spectral radius bound of A - L C = 1 - 8.67e-19" in text
        assert not re.search(r"A - L C = 1(?! - 8\.67e-19)", text), text  # never a bare 1


def test_an_exact_trace_1_plus_2_to_the_minus_60_is_shown_with_its_excess():
    # A = 1 + 2^-52, L C = 2^-52 - 2^-60: F = 1 + 2^-60 exactly, the float A - L C is 1.0
    cert = _exact_luenberger(1.0 + 2.0**-52, 2.0**-52 - 2.0**-60)
    gain = cert["observer_gain"]
    assert gain.verdict.value == "fails" and gain.method == "exact powers of A - L C"
    assert "|trace F^1| = 1 + 8.67e-19 > n = 1" in gain.summary, gain.summary
    assert "spectral radius is at least 1 + 8.67e-19 > 1" in gain.summary
    assert ">= n" not in gain.summary and "at least 1:" not in gain.summary
    assert gain.evidence["exact_decision"]["spectral_radius_excess"] == pytest.approx(
        2.0**-60, rel=1e-12
    )
    assert gain.value_name == "spectral radius lower bound of A - L C"
    assert _shown(cert)["observer_gain"] == "1 + 8.67e-19"
    for check in ("observer_stability", "iss_gain"):
        assert "|trace F^1| = 1 + 8.67e-19 > n = 1" in cert[check].summary
