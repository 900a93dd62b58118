"""``pytest proofs_checks``: every claim's check gives the verdict recorded for it.

A verdict that changes (a check that now finds a counterexample to a claim
recorded as holding, or none to one recorded as failing) fails its test, with
the finding's explanation.
"""

from __future__ import annotations

import json

import pytest

from proofs_checks import all_claims, run_claim

CLAIMS = all_claims()


@pytest.mark.parametrize("claim_id", list(CLAIMS))
def test_the_recorded_verdict(claim_id):
    outcome = run_claim(claim_id)
    finding = outcome.finding
    assert finding.verdict == CLAIMS[claim_id].recorded, finding.explanation
    entry = outcome.to_dict()
    json.dumps(entry, allow_nan=False)  # strict JSON, as audit.json is written
    if finding.verdict != "holds":
        counterexample = entry["evidence"]["counterexample"]
        assert isinstance(counterexample, dict) and counterexample
        assert entry["evidence"]["reproduce"] == f"ssecert audit --claim {claim_id}"
