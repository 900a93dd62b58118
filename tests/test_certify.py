"""ssecert certify: files, JSON contract, exit status, Jupyter rendering."""

import json
import re
from pathlib import Path

import pytest

from ssecert import analyze
from ssecert.certify import certify
from ssecert.cli import main
from ssecert.examples import load_example
from ssecert.report.json import certify_json
from ssecert.spec import spec_from_dict

ARCHITECTURE = (Path(__file__).resolve().parents[1] / "docs" / "architecture.md").read_text()


def _documented(start: str, end: str) -> set[str]:
    """The names docs/architecture.md puts in backticks from ``start`` to ``end``, leaving out
    what is in parentheses (the parts of a key)."""
    begin = ARCHITECTURE.index(start) + len(start)
    text = ARCHITECTURE[begin : ARCHITECTURE.index(end, begin) + len(end)]
    text = re.sub(r"\s+", " ", text)
    while re.search(r"\([^()]*\)", text):
        text = re.sub(r"\([^()]*\)", "", text)
    return set(re.findall(r"`([^`]+)`", text))


def _analyze_keys() -> set[str]:
    """The top-level keys of the JSON the document gives as {"ssecert_version", ...}."""
    start = ARCHITECTURE.index("- JSON: `{") + len("- JSON: `{")
    text, depth, top = ARCHITECTURE[start:], 0, ""
    for char in text[: text.index("}`")]:
        depth += {"{": 1, "}": -1}.get(char, 0)
        top += char if depth == 0 and char != "}" else ""
    return set(re.findall(r'"([^"]+)"', top))


CERTIFY_KEYS = _documented("`certify` adds", "`spec`")


def test_the_documented_json_keys_are_parsed():
    # what this module pins: if the document's sentences change shape, the parsing says so
    assert _analyze_keys() == {"ssecert_version", "system", "verdict", "checks", "meta"}
    assert {"simulations", "certified_region", "spec", "notes"} <= CERTIFY_KEYS


@pytest.mark.slow
def test_certify_without_spec_writes_the_ugv_report(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = main(["certify"])
    out = capsys.readouterr().out
    assert code == 1
    html = (tmp_path / "reports" / "ugv.html").read_text()
    data = json.loads((tmp_path / "reports" / "ugv.json").read_text())
    assert "<!DOCTYPE html>" in html
    # self-contained: nothing is loaded from elsewhere, no scripts
    import re

    assert not re.search(r'(src|href)\s*=\s*"(https?:|//)', html)
    assert "<script" not in html and "@import" not in html
    assert data["verdict"] == "fails"
    assert data["checks"]["sparse_observability"]["breaking_set"] == [0]
    # every key docs/architecture.md names, and no other (no notes: nothing was skipped)
    assert set(data) == _analyze_keys() | CERTIFY_KEYS - {"notes"}
    sims = data["simulations"]
    assert set(sims) == {"constant-velocity-a", "stealthy"}
    for sim in sims.values():
        assert {"observer", "runs", "steps", "final", "series"} <= set(sim)
        assert {"relative_error_mean", "relative_error_q90", "support_error_mean"} <= set(
            sim["final"]
        )
    assert data["reproduce"] == "ssecert certify"
    assert "verdict: FAILS (exit status 1)" in out and "reports/ugv.html" in out
    assert not list((tmp_path / "reports").glob("*.tmp"))


def test_no_sim_json_to_stdout(tmp_path, capsys):
    code = main(["certify", "notes-example-3", "--no-sim", "--out", str(tmp_path), "--json", "-"])
    captured = capsys.readouterr()
    data = json.loads(captured.out)
    assert code == 0 and data["verdict"] == "holds"
    assert data["simulations"] == {}
    assert "verdict:" in captured.err
    assert (tmp_path / "notes-example-3.html").exists()


@pytest.mark.slow
def test_automatic_stealthy_scenario_and_seed(tmp_path):
    spec = load_example("ugv")
    spec = spec.__class__(**{**spec.__dict__, "scenarios": spec.scenarios[:1]})
    result = certify(spec, seed=3, runs=4, steps=30)
    assert "stealthy (automatic)" in result.simulations
    assert result.simulations["constant-velocity-a"].seed == 3
    assert result.stealthy["residual"] < 1e-9
    sims = json.loads(certify_json(result))["simulations"]
    assert set(sims) == {"constant-velocity-a", "stealthy (automatic)"}
    scenario_keys = _documented("`simulations` (by scenario name:", ";")
    assert scenario_keys >= {"observer", "final", "series"}
    assert all(set(sim) == scenario_keys for sim in sims.values())


def test_the_json_of_a_plant_without_sparse_observability_has_the_documented_keys():
    # no observer: no simulation, no region, a note saying so; the stealthy attack is the witness
    spec = spec_from_dict(
        {
            "name": "breakable",
            "system": {"A": [[0.5, 0.0], [1.0, 0.7]], "C": [[0.0, 1.0], [1.0, 0.0], [1.0, 0.0]]},
            "attack": {"max_attacked": 1},
        }
    )
    data = json.loads(certify_json(certify(spec)))
    assert data["verdict"] == "fails" and data["simulations"] == {} and data["notes"]
    assert set(data) == _analyze_keys() | CERTIFY_KEYS - {"certified_region"}
    witness_keys = _documented("the `witness` of a failing sparse_observability:", ";")
    assert witness_keys == {"z", "sensors_a", "sensors_b", "attack_a", "attack_b"}
    assert witness_keys <= set(data["checks"]["sparse_observability"]["witness"])


def test_bad_out_folder_is_a_usage_error(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["certify", "notes-example-0", "--no-sim", "--out", str(blocker)]) == 2
    assert "--out" in capsys.readouterr().err


def test_results_render_in_jupyter():
    cert = analyze(load_example("notes-example-2"))
    html = cert._repr_html_()
    assert "sparse_observability" in html and "fails" in html
    card = cert["sparse_observability"]._repr_html_()
    assert "max_removable = 1" in card
    full = certify(load_example("notes-example-2"), simulate=False)._repr_html_()
    assert "why-not-correctable" in full and "<html" not in full


@pytest.mark.slow
def test_the_run_times_are_in_meta_timings_only(tmp_path):
    cert = analyze(load_example("random-n15-p30"), time_budget=0.5)
    timings = cert.meta["timings"]
    steps = ("eigenvalues", "observability", "sparse_observability", "irrepresentable")
    assert all(timings[step] >= 0 for step in steps)
    split = timings["sparse_observability.to_verdict"] + timings["sparse_observability.refinement"]
    assert (
        abs(split - timings["sparse_observability"])
        <= 0.01 * timings["sparse_observability"] + 1e-3
    )
    assert timings["analyze"] >= sum(timings[step] for step in steps) * 0.99
    # certify keeps them beside the solver and simulation times it moves to meta.timings
    assert main(["certify", "ugv", "--out", str(tmp_path), "--seed", "0"]) == 1
    doc = json.loads((tmp_path / "ugv.json").read_text())
    assert "observer_checks" in doc["meta"]["timings"] and "timing" not in doc["meta"]
    # each observer check's seconds, within the observer checks' whole
    timings = doc["meta"]["timings"]
    ids = ["observer_gain", "observer_stability", "iss_gain", "thesis_assumptions",
           "region_of_attraction"]  # fmt: skip
    each = [timings[f"observer_checks.{k}"] for k in ids]
    assert all(t >= 0 for t in each)
    assert sum(each) <= timings["observer_checks"] * 1.01 + 0.01
