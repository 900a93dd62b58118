"""Regenerating the packaged examples' reports gives the committed verdicts."""

import json
from pathlib import Path

import pytest

from ssecert.certify import certify
from ssecert.examples import list_examples, load_example

REPORTS = Path(__file__).resolve().parents[1] / "reports"


def test_every_packaged_example_has_a_report():
    for name in list_examples():
        assert (REPORTS / f"{name}.html").is_file(), name
        assert (REPORTS / f"{name}.json").is_file(), name
    assert (REPORTS / "README.md").is_file()


# certifying the 14-bus system takes several seconds: a slow test
@pytest.mark.parametrize(
    "name",
    [pytest.param(n, marks=pytest.mark.slow) if n == "ieee14" else n for n in list_examples()],
)
def test_regenerating_gives_the_same_verdicts(name):
    committed = json.loads((REPORTS / f"{name}.json").read_text())
    result = certify(load_example(name), seed=0, simulate=False, region=False)
    fresh = result.to_dict()
    assert fresh["verdict"] == committed["verdict"]
    assert {k: v["verdict"] for k, v in fresh["checks"].items()} == {
        k: v["verdict"] for k, v in committed["checks"].items()
    }


def test_the_committed_audit_has_every_claim_with_its_recorded_verdict():
    from proofs_checks import all_claims

    doc = json.loads((REPORTS / "audit.json").read_text(encoding="utf-8"))
    claims = all_claims()
    assert list(doc["claims"]) == list(claims)
    assert {i: e["verdict"] for i, e in doc["claims"].items()} == {
        i: c.recorded for i, c in claims.items()
    }
    assert (REPORTS / "audit.html").read_text(encoding="utf-8").count('class="claim v-') == len(
        claims
    )
