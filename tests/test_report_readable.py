"""The report a reviewer reads: the design shown, numbers rounded, quantities named, and an
advisory check whose sufficient condition is not met not shown as a failure."""

import html
import json
import math
import re

import numpy as np
import pytest

from ssecert import spec_from_dict
from ssecert.base.format import readable
from ssecert.certify import certify
from ssecert.cli import main
from ssecert.report.html import render_report
from ssecert.report.table import render_table
from ssecert.results import QUANTITY_NAMES, Check

NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d+)?(?:e[+-]?\d+)?(?![\w.])")


@pytest.fixture(scope="module")
def ugv(tmp_path_factory):
    out = tmp_path_factory.mktemp("ugv")
    assert main(["certify", "ugv", "--out", str(out), "--no-sim"]) == 1
    return (out / "ugv.html").read_text(), json.loads((out / "ugv.json").read_text())


@pytest.fixture(scope="module")
def certified():
    """A design every check of which holds except the thesis's assumptions (a D-SSO with a
    placed gain: its Pi map grows beyond 1e155, Assumption 3 fails by a factor above 1e300)."""
    spec = spec_from_dict(
        {
            "name": "certified",
            "system": {"A": [[0.9]], "C": [[1.0], [1.0], [1.0]]},
            "attack": {"max_attacked": 1},
            "observer": {
                "kind": "dsso",
                "gain": "place",
                "poles": [0.5],
                "step": 0.5,
                "threshold": 0.1,
            },
        }
    )
    return certify(spec, simulate=False, region=False)


def _section(page, section_id):
    start = page.index(f'<section id="{section_id}">')
    return page[start : page.index("</section>", start)]


def _text(fragment):
    return html.unescape(re.sub(r"<[^>]+>", " ", fragment))


def _rows(page):
    """The summary's rows: id -> (verdict badge, value cell, margin cell) as HTML."""
    rows = {}
    for row in re.findall(r'<tr id="row-(\w+)">(.*?)</tr>', _section(page, "summary"), re.S):
        cells = re.findall(r"<td[^>]*>(.*?)</td>", row[1], re.S)
        rows[row[0]] = (cells[1], cells[2], cells[3])
    return rows


def _significant_digits(token):
    mantissa = token.lstrip("-").split("e")[0].replace(".", "").lstrip("0")
    return len(mantissa)


@pytest.mark.slow
def test_the_report_shows_the_plant_with_sensor_names(ugv):
    page, _ = ugv
    design = _section(page, "design")
    a = _text(design[design.index('id="plant-A"') : design.index('id="plant-C"')])
    assert "0.0099" in a and "0.9876" in a
    c = design[design.index('id="plant-C"') : design.index('id="attack-budget"')]
    assert re.findall(r"<tr><th>([^<]+)</th><td", c) == ["position", "velocity-a", "velocity-b"]
    assert "s = max_attacked = 1" in _text(design) and "tau = 2" in _text(design)


def test_the_report_shows_the_observer_and_its_built_gain(ugv):
    page, document = ugv
    design = _section(page, "design")
    params = _text(design[design.index('id="observer-parameters"') :])
    for key, value in (("kind", "dsso"), ("gain", "deadbeat"), ("step", "0.7")):
        assert re.search(rf"\b{key}\s+{re.escape(value)}\b", params), key
    assert re.search(r"\bthreshold\s+0\.1\b", params)
    # the deadbeat gain as built, not the word "deadbeat" only
    L = np.asarray(document["checks"]["observer_gain"]["L"])
    shown = _text(design[design.index('id="observer-L"') :])
    assert "position" in shown and "velocity-b" in shown
    for entry in L.ravel():
        assert readable(entry) in shown.split(), entry
    # and the exact entries are in the JSON, with A and C
    assert document["spec"]["system"]["A"] == [[1.0, 0.0099], [0.0, 0.9876]]
    assert document["spec"]["observer"]["step"] == 0.7


def test_summary_numbers_are_rounded_and_never_minus_zero(ugv):
    page, _ = ugv
    summary = _text(_section(page, "summary"))
    tokens = NUMBER.findall(summary)
    assert tokens
    assert "-0" not in tokens and "-0.0" not in tokens
    too_long = [t for t in tokens if _significant_digits(t) > 6]
    assert not too_long, too_long  # 0.9999999999999997 among them


@pytest.mark.slow
def test_each_summary_row_names_its_value_and_margin(ugv, certified):
    for page in (ugv[0], render_report(certified)):
        rows = _rows(page)
        assert {"observability", "sparse_observability", "observer_gain"} <= set(rows)
        for check_id, (_, value, margin) in rows.items():
            for cell in (value, margin):
                if _text(cell).strip() != "-":
                    assert re.search(r'class="qname">[^<]+<', cell), (check_id, cell)
        assert "max_removable" in rows["sparse_observability"][1]


def test_the_terminal_table_names_quantities_and_rounds(certified):
    table = render_table(certified.certificate)
    lines = table.splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("check "))
    rows = lines[head + 2 : lines.index("* advisory: reported, does not change the exit status")]
    for row in rows:
        cells = re.split(r"\s{2,}", row)
        for cell in cells[2:4]:
            assert cell == "-" or re.match(r"[^=]+ = \S", cell), row
        for token in NUMBER.findall(" ".join(cells[2:4])):
            assert _significant_digits(token) <= 6 and token != "-0", row
    thesis = next(r for r in rows if r.startswith("thesis_assumptions"))
    assert "does not apply" in thesis and "FAILS" not in thesis
    assert "spectral radius of A - L C = 0.5" in table


def test_a_certified_design_s_thesis_check_is_not_a_red_failure(certified):
    cert = certified.certificate
    assert cert.verdict.value == "holds"
    thesis = cert["thesis_assumptions"]
    # the answer to the check's own question is kept; it does not apply to the design
    assert thesis.verdict.value == "fails" and not thesis.applies and not thesis.required
    page = render_report(certified)
    badge = _rows(page)["thesis_assumptions"][0]
    assert "does not apply" in badge and "badge fails" not in badge
    assert 'data-verdict="fails"' in badge
    # its meaning is said, in observer_messages.thesis_summary's words (test_observer_messages)
    assert thesis.fields["items"]["assumption_3"] == "fails"
    document = certified.to_dict()["checks"]["thesis_assumptions"]
    assert document["verdict"] == "fails" and document["applies"] is False


def test_the_json_keeps_every_digit_and_names_the_quantities(ugv):
    page, document = ugv
    gain = document["checks"]["observer_gain"]
    upper = gain["spectral_radius"]
    assert gain["margin"] == 1.0 - upper and gain["margin"] != 1.0  # not rounded
    # the UGV's printed A - L C vanishes to rounding, not exactly (its exact radius is 2.2e-16)
    assert gain["value_name"] == "steps to vanish (to rounding)"
    assert gain["margin_name"] == "1 - spectral radius bound"
    for check_id, check in document["checks"].items():
        assert {"value_name", "margin_name", "applies"} <= set(check), check_id
    assert document["checks"]["observability"]["value_name"] == QUANTITY_NAMES["observability"][0]
    # the report rounds it, with the exact value on hover
    assert f'title="{gain["margin"]!r}"' in page


@pytest.mark.slow
def test_a_stack_of_matrices_in_the_evidence_is_shown_as_matrices(ugv):
    # the piecewise-quadratic region's functions: one (N + 1) x (N + 1) matrix per region
    page, document = ugv
    functions = document["checks"]["region_of_attraction"]["evidence"]["certificate"]["functions"]
    shape = " x ".join(str(d) for d in np.shape(functions))
    assert f"<summary>{shape} array</summary>" in page
    # no nested list of numbers written out raw
    assert not re.search(r"\[\[-?[\d.e+-]+, -?\d", _text(page))


def test_a_large_plant_is_shown_truncated_with_its_shape():
    rng = np.random.default_rng(0)
    spec = spec_from_dict(
        {
            "name": "large",
            "system": {
                "A": (0.3 * rng.standard_normal((15, 15))).tolist(),
                "C": rng.standard_normal((13, 15)).tolist(),
            },
            "attack": {"max_attacked": 0},
        }
    )
    result = certify(spec, simulate=False, region=False)
    design = _section(render_report(result), "design")
    assert "A is 15 x 15: its first 12 x 12 entries are shown" in _text(design)
    assert "C is 13 x 15: its first 12 x 12 entries are shown" in _text(design)
    assert len(re.findall(r"<tr><th>x\d+</th>", design)) == 12
    assert "no [observer] section" in _text(design)


@pytest.mark.parametrize(
    "x, shown",
    [
        (0.9999999999999997, "1"),
        (-0.0, "0"),
        (2.77556e-17, "2.8e-17"),
        (0.786123, "0.7861"),
        (4.895e120, "4.895e120"),
        (math.inf, "inf"),
    ],
)
def test_readable_numbers(x, shown):
    assert readable(x) == shown


def test_a_value_compared_with_one_keeps_its_side():
    assert readable(0.9999999999999997, versus=1.0) == "1 - 3.3e-16"
    assert readable(1 + 2**-40, versus=1.0).startswith("1 + ")
    assert readable(0.5, versus=1.0) == "0.5"


def test_applies_false_is_only_for_an_advisory_check_that_fails():
    with pytest.raises(ValueError, match="advisory"):
        Check(id="x", title="x", verdict="fails", summary="s", applies=False)
    with pytest.raises(ValueError, match="advisory"):
        Check(id="x", title="x", verdict="holds", summary="s", required=False, applies=False)
    check = Check(id="x", title="x", verdict="fails", summary="s", required=False, applies=False)
    assert check.to_dict()["applies"] is False
