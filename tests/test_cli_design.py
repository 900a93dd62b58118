"""``ssecert design``: a certified observer synthesised, certified, simulated beside the
spec's own design, and written as a spec file, a report and a certificate."""

from __future__ import annotations

import json

import pytest

from ssecert import load_spec
from ssecert.cli import main
from ssecert.design.search_messages import comparison_summary


@pytest.mark.slow
def test_design_writes_a_spec_report_and_certificate_that_certify_reproduces(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    status = main(
        ["design", "ugv", "--out", str(out), "--runs", "4", "--json", str(out / "r.json")]
    )
    printed = capsys.readouterr().out
    # a design is written, and its certificate fails: the plant is not 2-sparse observable
    assert status == 1, printed
    assert "verdict of the written design's certificate: FAILS (exit status 1)" in printed
    assert sorted(p.name for p in out.iterdir()) == [
        "r.json", "ugv-design.html", "ugv-design.json", "ugv-design.toml"
    ]  # fmt: skip
    result = json.loads((out / "r.json").read_text())
    assert result["kind"] == "elastic_net" and result["complete"]
    assert len(result["candidates"]) == 20
    assert "not 2-sparse observable" in printed and "removing position" in printed
    designs = {d["design"]: d for d in result["comparison"]["designs"]}
    assert designs["spec"]["observer_stability"] == "inconclusive"  # the thesis's D-SSO
    assert designs["synthesised"]["observer_stability"] == "holds"
    assert designs["synthesised"]["iss_gain_value"] == pytest.approx(result["gamma"], rel=1e-12)
    assert f"{result['gamma']:.4g}" in printed
    # the report says, scenario by scenario, where the synthesised design is worse
    for row in result["comparison"]["scenarios"]:
        mine, theirs = row["synthesised"]["mean_error"], row["spec"]["mean_error"]
        assert (row["comparison"] == "worse") == (mine > theirs * 1.05 + 1e-12)
        assert (row["scenario"] in result["comparison"]["worse_in"]) == (
            row["comparison"] == "worse"
        )
    html = (out / "ugv-design.html").read_text()
    assert 'id="design-comparison"' in html and "the spec&#39;s design" in html
    certificate = json.loads((out / "ugv-design.json").read_text())
    assert certificate["design_comparison"] == result["comparison"]
    # the written spec, certified again as a user would, gives the same verdicts and gain
    again = tmp_path / "again"
    again.mkdir()
    status = main(["certify", str(out / "ugv-design.toml"), "--out", str(again), "--no-sim"])
    assert status == 1  # the plant is not 2-sparse observable: the certificate fails
    capsys.readouterr()
    redone = json.loads((again / "ugv-design.json").read_text())
    checks, mine = redone["checks"], certificate["checks"]
    assert {k: c["verdict"] for k, c in checks.items()} == {
        k: c["verdict"] for k, c in mine.items()
    }
    assert checks["iss_gain"]["value"] == pytest.approx(result["gamma"], rel=1e-9)
    assert load_spec(out / "ugv-design.toml").name == "ugv-design"


def test_a_dsso_on_an_integrator_gets_no_design_and_a_hint(tmp_path, capsys):
    status = main(["design", "ugv", "--observer", "dsso", "--out", str(tmp_path)])
    printed = capsys.readouterr().out
    assert status == 1 and "no dsso design" in printed and "--observer elastic-net" in printed
    assert "--objective roa" in printed
    assert list(tmp_path.iterdir()) == []  # nothing written


@pytest.mark.slow
def test_the_roa_objective_designs_a_dsso(tmp_path, capsys):
    status = main(["design", "ugv", "--objective", "roa", "--out", str(tmp_path), "--runs", "2",
                   "--json", "-"])  # fmt: skip
    captured = capsys.readouterr()
    assert status == 1, captured.err  # written; the UGV is not 2-sparse observable
    result = json.loads(captured.out)
    assert result["kind"] == "dsso" and result["radius"] > 10.0
    designs = {d["design"]: d for d in result["comparison"]["designs"]}
    assert designs["synthesised"]["region_of_attraction_value"] == pytest.approx(result["radius"])
    assert designs["spec"]["region_of_attraction_value"] < result["radius"]
    assert main(["design", "ugv", "--objective", "roa", "--observer", "elastic-net"]) == 2
    assert "--objective roa is for --observer dsso" in capsys.readouterr().err


@pytest.mark.slow
def test_the_time_budget_ends_the_search_and_says_so(tmp_path, capsys):
    status = main(
        ["design", "ugv", "--out", str(tmp_path), "--time-budget", "0", "--runs", "2"]
    )  # fmt: skip
    printed = capsys.readouterr().out
    assert status == 1 and "1 candidates" in printed  # written; the certificate fails
    assert "the time budget of 0 s ended the search" in printed


def test_an_unknown_kind_is_refused(capsys):
    assert main(["design", "ugv", "--observer", "sso"]) == 2
    assert "--observer" in capsys.readouterr().err


def test_the_help_names_every_kind(capsys):
    with pytest.raises(SystemExit):
        main(["design", "--help"])
    printed = capsys.readouterr().out
    assert "--observer KIND" in printed and "elastic-net (default" in printed
    assert "luenberger" in printed


@pytest.mark.slow
def test_a_plant_file_designs_with_the_number_of_attacked_sensors(tmp_path, capsys):
    import numpy as np

    plant = tmp_path / "plant.npz"
    np.savez(plant, A=np.array([[0.9, 0.1], [0.0, 0.8]]), C=np.array([[1.0, 0.0], [0.0, 1.0],
             [1.0, 1.0]]))  # fmt: skip
    assert main(["design", str(plant), "--out", str(tmp_path)]) == 2
    assert "--max-attacked" in capsys.readouterr().err
    status = main(["design", str(plant), "--max-attacked", "1", "--out", str(tmp_path)])
    printed = capsys.readouterr().out
    # written: the observer is certified, but removing sensor 0 and 2 leaves (A, [0 1])
    # unobservable, so 1 attacked sensor cannot be corrected and the certificate fails
    assert status == 1 and (tmp_path / "plant-design.toml").exists()
    assert "verdict of the written design's certificate: FAILS (exit status 1)" in printed
    assert "has no observer of its own" in printed


def test_json_may_not_overwrite_what_design_writes(tmp_path, capsys):
    for name in ("ugv-design.json", "ugv-design.toml"):
        status = main(["design", "ugv", "--out", str(tmp_path), "--json", str(tmp_path / name)])
        assert status == 2 and "give another path" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_the_report_reproduces_the_design_command_and_names_the_certificate_alone(tmp_path, capsys):
    argv = ["design", "ugv", "--out", str(tmp_path), "--runs", "2", "--seed", "3",
            "--time-budget", "0"]  # fmt: skip
    assert main(argv) == 1  # the design is written; its certificate fails
    capsys.readouterr()
    certificate = json.loads((tmp_path / "ugv-design.json").read_text())
    assert certificate["reproduce"] == "ssecert " + " ".join(argv)
    alone = [n for n in certificate["notes"] if "certificate of the written spec" in n]
    assert alone and "--seed 3 --runs 2 --out ANOTHER_FOLDER" in alone[0]


@pytest.mark.slow
def test_the_rate_objective_designs_a_luenberger_observer_for_a_chain(tmp_path, capsys):
    spec = tmp_path / "chain.toml"
    spec.write_text(
        'name = "chain"\n[system]\nA = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.3, -0.2, 0.9]]\n'
        "C = [[1.0, 0.0, 0.0]]\n[attack]\nmax_attacked = 0\nhorizon = 3\n"
    )
    status = main(["design", str(spec), "--observer", "luenberger", "--objective", "rate",
                   "--out", str(tmp_path), "--json", str(tmp_path / "r.json")])  # fmt: skip
    printed = capsys.readouterr().out
    assert status == 0, printed
    result = json.loads((tmp_path / "r.json").read_text())
    assert result["decay"] > 0.5 and result["candidates"][0]["synthesis_certificate"]["verified"]


@pytest.mark.slow
def test_an_unobservable_unstable_plant_gets_the_reason(tmp_path, capsys):
    spec = tmp_path / "unobs.toml"
    spec.write_text(
        'name = "unobs"\n[system]\nA = [[1.2, 0.0], [0.0, 0.5]]\nC = [[0.0, 1.0], [0.0, 2.0]]\n'
        "[attack]\nmax_attacked = 0\nhorizon = 2\n"
    )
    status = main(["design", str(spec), "--out", str(tmp_path)])
    printed = capsys.readouterr().out
    assert status == 1 and list(tmp_path.iterdir()) == [spec]
    assert "not observable even with every sensor" in printed
    assert "unobservable mode that is not stable (eigenvalue 1.2)" in printed
    # an earlier run's files in --out are left, and named, not taken for this run's
    earlier = tmp_path / "unobs-design.toml"
    earlier.write_text("# earlier\n")
    assert main(["design", str(spec), "--out", str(tmp_path)]) == 1
    assert str(earlier) in capsys.readouterr().out and earlier.read_text() == "# earlier\n"


_OWN_DSSO = (
    'name = "own"\n[system]\nA = [[1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.5]]\n'
    "C = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 0.0], "
    "[0.0, 1.0, 1.0], [1.0, 0.0, 1.0]]\n[attack]\nmax_attacked = 1\n"
    '[observer]\nkind = "dsso"\ngain = "deadbeat"\nstep = 0.05\nthreshold = 1.0\n'
)


@pytest.mark.slow
def test_the_comparison_says_when_the_spec_design_has_the_larger_region(tmp_path, capsys):
    # a D-SSO with step 0.05 has a dead zone twice as wide as the grid's smallest step gives
    spec = tmp_path / "own.toml"
    spec.write_text(_OWN_DSSO)
    out = tmp_path / "out"
    main(["design", str(spec), "--objective", "roa", "--out", str(out), "--json", "-"])
    comparison = json.loads(capsys.readouterr().out)["comparison"]
    designs = {d["design"]: d for d in comparison["designs"]}
    theirs = designs["spec"]["region_of_attraction_value"]
    ours = designs["synthesised"]["region_of_attraction_value"]
    assert theirs > ours > 0
    # (no scenarios: the summary says so, then which region is larger)
    assert comparison["summary"] == comparison_summary(True, 0, 0, [], [], None, (theirs, ours))


def test_a_globally_stable_design_is_not_said_to_have_the_smaller_region(tmp_path, capsys):
    # the D-SSO's region is certified (radius 14.14); a Luenberger design whose
    # observer_stability holds converges from every initial error, and has no region check
    spec = tmp_path / "own.toml"
    spec.write_text(_OWN_DSSO)
    main(["design", str(spec), "--observer", "luenberger", "--out", str(tmp_path / "out"),
          "--json", "-"])  # fmt: skip
    comparison = json.loads(capsys.readouterr().out)["comparison"]
    designs = {d["design"]: d for d in comparison["designs"]}
    assert designs["spec"]["region_of_attraction_value"] > 0
    assert designs["synthesised"]["observer_stability"] == "holds"
    assert "region_of_attraction" not in designs["synthesised"]
    assert comparison["summary"] == comparison_summary(True, 0, 0, [], [], None, None)
