"""ssecert certify: files, JSON contract, exit status, Jupyter rendering."""

import json

from ssecert import analyze
from ssecert.certify import certify
from ssecert.cli import main
from ssecert.examples import load_example


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


def test_automatic_stealthy_scenario_and_seed(tmp_path):
    spec = load_example("ugv")
    spec = spec.__class__(**{**spec.__dict__, "scenarios": spec.scenarios[:1]})
    result = certify(spec, seed=3, runs=4, steps=30)
    assert "stealthy (automatic)" in result.simulations
    assert result.simulations["constant-velocity-a"].seed == 3
    assert result.stealthy["residual"] < 1e-9


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
