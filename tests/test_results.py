"""Check/Certificate behaviour and strict JSON."""

import json
import math

import numpy as np
import pytest

from ssecert import Certificate, Check, System, Verdict
from ssecert.report.json import certificate_json, write_json
from ssecert.results import to_jsonable


def _check(id_, verdict, required=True):
    return Check(id=id_, title=id_, verdict=verdict, summary="s", required=required)


@pytest.mark.parametrize(
    "verdicts, overall, code",
    [
        (["holds", "holds"], "holds", 0),
        (["holds", "fails"], "fails", 1),
        (["inconclusive", "holds"], "inconclusive", 3),
        (["inconclusive", "fails"], "fails", 1),
    ],
)
def test_overall_verdict_and_exit_code(verdicts, overall, code):
    checks = [_check(f"c{i}", v) for i, v in enumerate(verdicts)]
    cert = Certificate(System([[1.0]], [[1.0]]), checks)
    assert cert.verdict.value == overall and cert.exit_code == code


def test_advisory_checks_do_not_change_the_exit_status():
    cert = Certificate(
        System([[1.0]], [[1.0]]), [_check("a", "holds"), _check("b", "fails", required=False)]
    )
    assert cert.verdict is Verdict.HOLDS and cert.exit_code == 0


def test_duplicate_ids_refused():
    with pytest.raises(ValueError, match="unique"):
        Certificate(System([[1.0]], [[1.0]]), [_check("a", "holds"), _check("a", "holds")])


def test_to_jsonable_handles_numpy_complex_and_non_finite():
    out = to_jsonable(
        {
            "a": np.arange(3),
            "b": np.float64(math.inf),
            "c": 1 + 2j,
            "d": np.nan,
            "e": (np.int64(3), np.bool_(True)),
        }
    )
    assert out == {
        "a": [0, 1, 2],
        "b": "Infinity",
        "c": {"re": 1.0, "im": 2.0},
        "d": "NaN",
        "e": [3, True],
    }
    assert float(out["b"]) == math.inf


def test_certificate_json_is_strict_and_written_atomically(tmp_path):
    # the two checks every certificate has, one with a non-finite value
    check = Check(
        id="observability", title="x", verdict="fails", summary="s", value=math.inf,
        evidence={"m": np.eye(2)}, fields={"observability_index": None},
    )  # fmt: skip
    sparse = Check(
        id="sparse_observability", title="y", verdict="fails", summary="s",
        fields={"max_removable": -1, "max_removable_is_lower_bound": False,
                "max_correctable": -1, "breaking_set": []},
    )  # fmt: skip
    cert = Certificate(System([[1.0]], [[1.0]]), [check, sparse])
    text = certificate_json(cert)
    data = json.loads(text, parse_constant=lambda c: pytest.fail(f"non-strict literal {c}"))
    assert data["checks"]["observability"]["value"] == "Infinity"
    path = write_json(cert, tmp_path / "out.json")
    assert json.loads(path.read_text()) == data
    assert [p.name for p in tmp_path.iterdir()] == ["out.json"]
