"""``ssecert design``: a certified observer synthesised and written as a spec file."""

from __future__ import annotations

import json

import pytest

from ssecert import analyze, load_spec
from ssecert.cli import main


def test_design_writes_a_spec_that_certifies_with_the_printed_gain(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    status = main(
        ["design", "ugv", "--observer", "elastic-net", "--out", str(out),
         "--json", str(out / "r.json")]
    )  # fmt: skip
    printed = capsys.readouterr().out
    assert status == 0, printed
    result = json.loads((out / "r.json").read_text())
    assert result["complete"] and len(result["candidates"]) == 20
    assert "not 2-sparse observable" in printed and "removing position" in printed
    assert result["spec_design"]["stability"] == "inconclusive"  # the thesis's D-SSO
    cert = analyze(load_spec(out / "ugv-design.toml"))
    assert cert["observer_stability"].verdict.value == "holds"
    assert cert["iss_gain"].value == pytest.approx(result["gamma"], rel=1e-9)
    assert f"{result['gamma']:.4g}" in printed


def test_a_dsso_on_an_integrator_gets_no_design_and_a_hint(tmp_path, capsys):
    status = main(["design", "ugv", "--out", str(tmp_path)])
    printed = capsys.readouterr().out
    assert status == 1 and "no dsso design" in printed and "--observer elastic-net" in printed
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_the_time_budget_ends_the_search_and_says_so(tmp_path, capsys):
    status = main(
        ["design", "ugv", "--observer", "elastic-net", "--out", str(tmp_path),
         "--time-budget", "0"]
    )  # fmt: skip
    printed = capsys.readouterr().out
    assert status == 1 and "the time budget ended the search" in printed


def test_an_unknown_kind_is_refused(capsys):
    assert main(["design", "ugv", "--observer", "sso"]) == 2
    assert "--observer" in capsys.readouterr().err


def test_a_plant_file_designs_with_the_number_of_attacked_sensors(tmp_path, capsys):
    import numpy as np

    plant = tmp_path / "plant.npz"
    np.savez(plant, A=np.array([[0.9, 0.1], [0.0, 0.8]]), C=np.array([[1.0, 0.0], [0.0, 1.0],
             [1.0, 1.0]]))  # fmt: skip
    assert main(["design", str(plant), "--out", str(tmp_path)]) == 2
    assert "--max-attacked" in capsys.readouterr().err
    status = main(["design", str(plant), "--max-attacked", "1", "--out", str(tmp_path)])
    assert status == 0 and (tmp_path / "plant-design.toml").exists()
