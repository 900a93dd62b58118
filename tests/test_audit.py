"""``ssecert audit``: every claim the audit must decide is registered, and the files it writes."""

import json

import pytest

from proofs_checks import Finding, all_claims
from ssecert.cli import main

# the numbered claims of the reference documents the audit decides (more may be registered)
REQUIRED = [
    "lasso.eq2",
    "lasso.uniqueness",
    "lasso.thm1",
    "lasso.eq17",
    "lasso.eq20",
    "lasso.example1",
    "lasso.sso_is_ista",
    "thesis.thm3",
    "thesis.deadbeat_n_steps",
    "thesis.prop3",
    "thesis.dsso_is_ijam",
    "thesis.ista_ijam_converge",
    "thesis.assumption2",
    "thesis.eq5_21",
    "thesis.lemma1",
    "thesis.psi_lipschitz",
    "thesis.l2_choice",
    "thesis.thm6",
    "thesis.thm7",
    "thesis.thm8",
    "thesis.young",
    "notes.prop1",
    "notes.examples0_3",
    "notes.q_ge_2h_plus_n",
    "notes.ista_descent",
    "notes.ogd_stability",
    "notes.constant_attack",
    "pruning.thm2_1",
    "pruning.lemma3_1",
    "pruning.ppv",
    "pruning.fifty_percent",
    "sise.lasso_support_size",
    "sise.near_oracle",
]


def test_every_required_claim_has_a_check():
    claims = all_claims()
    assert [c for c in REQUIRED if c not in claims] == []
    for claim in claims.values():
        assert claim.statement and claim.where.startswith(("000", "001", "002", "003", "004"))


def test_the_audit_writes_json_and_html_with_counterexamples(tmp_path, capsys):
    ids = ["lasso.eq20", "thesis.young", "notes.ogd_stability"]
    argv = ["audit", "--out", str(tmp_path / "out")]
    for claim_id in ids:
        argv += ["--claim", claim_id]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "lasso.eq20: fails" in printed and "counterexample: {" in printed
    doc = json.loads((tmp_path / "out" / "audit.json").read_text())
    assert list(doc["claims"]) == ids
    for claim_id, entry in doc["claims"].items():
        assert {"verdict", "statement", "where", "evidence"} <= set(entry)
        assert entry["evidence"]["reproduce"] == f"ssecert audit --claim {claim_id}"
        if entry["verdict"] != "holds":
            counterexample = entry["evidence"]["counterexample"]
            assert counterexample["shows"] and len(counterexample) > 1
    assert doc["claims"]["notes.ogd_stability"]["evidence"]["condition"]
    html = (tmp_path / "out" / "audit.html").read_text()
    assert html.count('class="claim v-') == 3 and "ssecert audit --claim lasso.eq20" in html
    assert "<script" not in html


def test_an_unknown_claim_is_a_usage_error(tmp_path, capsys):
    assert main(["audit", "--out", str(tmp_path), "--claim", "lasso.nope"]) == 2
    err = capsys.readouterr().err
    assert "--claim lasso.nope: no such claim" in err and "lasso.eq2" in err
    assert not list(tmp_path.iterdir())


def test_a_finding_without_its_evidence_is_refused():
    with pytest.raises(ValueError, match="counterexample"):
        Finding("fails", "a claim fails", {"method": "exhaustive"})
    with pytest.raises(ValueError, match="condition"):
        Finding("conditional", "needs more", {"method": "symbolic"}, counterexample={"A": 1})
    with pytest.raises(ValueError, match="method"):
        Finding("holds", "fine", {})
    with pytest.raises(ValueError, match="plain JSON"):
        Finding("fails", "bad", {"method": "randomised"}, counterexample={"A": object()})


@pytest.mark.slow
def test_a_claim_alone_prints_without_touching_the_reports_folder(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    claim = next(iter(all_claims()))
    assert main(["audit", "--claim", claim]) == 0
    out = capsys.readouterr().out
    assert f"\n{claim}: " in out and "audit written" not in out
    assert not (tmp_path / "reports").exists()
