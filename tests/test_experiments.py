"""``ssecert reproduce``: the registry of the documents' experiments, the agreement line
computed from the numbers, and the report."""

import json
import re

import pytest

from ssecert.cli import main
from ssecert.experiments import (
    Agreement,
    Experiment,
    Match,
    Outcome,
    Result,
    Settings,
    agreement,
    all_experiments,
    render_reproduce,
    reproduce_json,
    run_experiments,
)

# every table, figure and worked example of the five documents
EXPECTED = (
    [f"lasso.fig{i}" for i in range(1, 5)]
    + [f"thesis.fig6_{i}" for i in range(1, 8)]
    + [f"notes.example{i}" for i in range(4)]
    + ["pruning.fig1", "pruning.fig2", "pruning.table1"]
    + [f"sise.fig{i}" for i in range(1, 5)]
)


def test_every_table_figure_and_example_has_an_id_in_document_order():
    assert list(all_experiments()) == EXPECTED
    runnable = {i for i, e in all_experiments().items() if e.run is not None}
    assert runnable >= {
        "notes.example0",
        "sise.fig1",
        "sise.fig3",
        "pruning.fig1",
        "thesis.fig6_2",
        "thesis.fig6_5",
        "lasso.fig1",
        "lasso.fig2",
        "pruning.table1",
        "pruning.fig2",
        "lasso.fig3",
        "lasso.fig4",
        "sise.fig4",
        "thesis.fig6_7",
        "thesis.fig6_1",
        "thesis.fig6_6",
    }
    for entry in all_experiments().values():
        assert re.match(r"^[a-z]+\.(fig|table|example)\d", entry.id)
        assert entry.where and entry.measures
        assert entry.run is not None or entry.why_not  # one not run says why


@pytest.mark.parametrize(
    "ours, match",
    [
        ({"error": 0.1, "exact": True}, Match.REPRODUCED),
        ({"error": 0.104, "exact": True}, Match.REPRODUCED),
        ({"error": 0.13, "exact": True}, Match.CLOSE),
        ({"error": 0.3, "exact": True}, Match.DIFFERS),
        ({"error": 0.1, "exact": False}, Match.DIFFERS),
        ({"other": 1.0}, Match.NOT_COMPARABLE),
        ({"error": None, "exact": None}, Match.NOT_COMPARABLE),
    ],
)
def test_the_agreement_line_follows_the_numbers(ours, match):
    line = agreement({"error": 0.1, "exact": True}, ours)
    assert line.match is match
    assert line.words.startswith(match.value)


def test_the_agreement_line_names_what_differs_and_by_how_much():
    line = agreement({"error": 0.1, "rate": 2.0}, {"error": 0.1, "rate": 3.0})
    assert (line.worst, line.by) == ("rate", 0.5)
    assert "rate" in line.words and "50%" in line.words
    claims = agreement({"exact": True, "fragile": True}, {"exact": True, "fragile": False})
    assert claims.disagree == ("fragile",)
    # a document's 0 and ours not: an infinite relative gap, unless a floor is given
    assert agreement({"e": 0.0}, {"e": 1e-9}).match is Match.DIFFERS
    assert agreement({"e": 0.0}, {"e": 1e-9}, floor=1e-6).match is Match.REPRODUCED


def test_the_notes_examples_reproduce_and_a_wrong_claim_would_differ():
    outcomes = run_experiments([f"notes.example{i}" for i in range(4)])
    assert [o.agreement.match for o in outcomes] == [Match.REPRODUCED] * 4
    example2 = outcomes[2].result
    assert example2 is not None and example2.ours["sparsest C z"] == 2
    # the same numbers against a document that said otherwise
    wrong = Result(paper={**example2.paper, "corrects h = 1": True}, ours=example2.ours)
    assert agreement(wrong.paper, wrong.ours).match is Match.DIFFERS


def test_the_report_holds_every_experiment_with_the_same_keys():
    outcomes = run_experiments(["notes.example3"], Settings(seed=3))
    never = Experiment("notes.example9", "nowhere", "nothing", None, why_not="a test entry")
    line = Agreement(Match.NOT_RUN, "not run: a test entry")
    outcomes.append(Outcome(never, None, line, 0.0, Settings(seed=3)))
    data = json.loads(reproduce_json(outcomes))["experiments"]
    assert list(data) == ["notes.example3", "notes.example9"]
    for entry in data.values():
        assert set(entry) >= {"document", "where", "paper", "ours", "agreement", "unstated",
                              "command", "seconds"}  # fmt: skip
    assert data["notes.example3"]["paper"].keys() == data["notes.example3"]["ours"].keys()
    assert data["notes.example3"]["command"] == "ssecert reproduce notes.example3 --seed 3"
    assert data["notes.example9"]["match"] == "not run"
    assert data["notes.example9"]["agreement"].startswith("not run: ")
    html = render_reproduce(outcomes)
    assert 'id="notes.example3"' in html and "1 reproduced" in html and "1 not run" in html


def test_settings_count_the_runs():
    assert Settings().count(5, 50) == 5
    assert Settings(quick=False).count(5, 50) == 50
    assert Settings(runs=7).count(5, 50) == 7


def test_the_command_lists_runs_and_refuses(tmp_path, capsys):
    assert main(["reproduce", "--list"]) == 0
    listed = capsys.readouterr().out
    assert all(i in listed for i in EXPECTED)
    assert main(["reproduce", "lasso.fig9"]) == 2
    assert "lasso.fig9: no such experiment" in capsys.readouterr().err
    out = tmp_path / "out"
    assert main(["reproduce", "notes.example1", "--out", str(out)]) == 0
    assert "notes.example1  reproduced" in capsys.readouterr().out
    data = json.loads((out / "reproduce.json").read_text())
    assert list(data["experiments"]) == ["notes.example1"]
    assert (out / "reproduce.html").read_text().startswith("<!DOCTYPE html>")


@pytest.mark.slow
def test_a_randomised_experiment_is_reproducible_from_its_seed():
    from ssecert.experiments import sise

    first = run_experiments(["sise.fig2"], Settings(runs=2, seed=5))[0]
    sise._summary.cache_clear()
    again = run_experiments(["sise.fig2"], Settings(runs=2, seed=5))[0]
    assert first.result is not None and again.result is not None
    assert first.result.table == again.result.table
    assert first.result.ours == again.result.ours
    assert first.command == "ssecert reproduce sise.fig2 --runs 2 --seed 5"
    other = run_experiments(["sise.fig2"], Settings(runs=2, seed=6))[0]
    assert other.result is not None and other.result.table != first.result.table


@pytest.mark.slow
def test_the_thesis_scenarios_compare_the_tuned_observers():
    outcomes = run_experiments(["thesis.fig6_2", "thesis.fig6_3"], Settings(runs=2))
    for o in outcomes:
        assert o.result is not None
        observers = [row["observer"] for row in o.result.table[1:]]
        assert observers == ["D-SSO", "elastic net", "D-SSO (6.1)"]
        assert set(o.result.ours) == set(o.result.paper)
    # no attack: every observer's error dies out and no attack is estimated
    assert outcomes[0].agreement.match is Match.REPRODUCED


def test_the_readme_table_is_written_from_the_committed_report():
    from pathlib import Path

    from ssecert.experiments import agreement_table

    root = Path(__file__).resolve().parents[1]
    report = root / "reports" / "reproduce.json"
    if not report.is_file():
        pytest.skip("needs the source tree")
    data = json.loads(report.read_text())
    assert list(data["experiments"]) == EXPECTED
    readme = (root / "README.md").read_text()
    block = readme.split("<!-- reproduce:start -->\n", 1)[1].split("<!-- reproduce:end -->")[0]
    assert block == agreement_table(data)
    # the words follow the numbers: another report gives another table
    data["experiments"]["notes.example0"]["match"] = "differs"
    assert agreement_table(data) != block


@pytest.mark.slow
def test_the_lasso_decoders_on_one_point_of_fig1():
    from ssecert.experiments.lasso import _claims, decode_runs

    pytest.importorskip("z3")
    point = decode_runs(20, 4, runs=1, seed=0, sweep=(0.001,))
    free, noisy = point["noise-free"], point["noise"]
    # a smaller lambda, a smaller bias
    assert free["Lasso, lambda = 0.001"]["error"] < free["Lasso"]["error"]
    assert free["SMT"]["failed"] == 0 and free["SMT"]["error"] < 1e-9  # exact without noise
    assert noisy["SMT"]["failed"] == 1  # no support within its tolerance under 1e-4 noise
    assert free["Lasso"]["error"] < 1e-2 and noisy["Lasso"]["error"] < 1e-2
    claims = _claims({20: point})
    assert claims["SMT exact without noise"] and claims["SMT's accuracy critical under noise"]
    assert decode_runs(20, 4, runs=1, seed=0)["noise"]["Lasso"]["error"] == noisy["Lasso"]["error"]


@pytest.mark.slow
def test_the_online_observers_of_fig4_on_a_few_runs():
    from ssecert.experiments.lasso import observers_over_time

    m = observers_over_time(1, runs=2, seed=0, steps=60)
    assert set(m) == {"SSO", "ETPL"}
    for metrics in m.values():
        assert set(metrics) == {"error", "right", "settles", "seconds", "series"}
        assert 0 <= metrics["right"] <= 1 and 0 <= metrics["settles"] <= 61
    assert observers_over_time(1, runs=2, seed=0, steps=60)["SSO"]["error"] == m["SSO"]["error"]


def test_a_result_with_a_figure_is_redrawn_in_the_report():
    from ssecert.experiments import figure

    entry = Experiment("notes.example8", "somewhere", "a curve", None)
    result = Result(
        paper={"rises": True},
        ours={"rises": True},
        figure=figure("y against x", "x", "y", {"ours": ([1, 2, 3], [1.0, 2.0, 0.0])}, log=True),
    )
    line = agreement(result.paper, result.ours)
    outcome = Outcome(entry, result, line, 0.0, Settings())
    html = render_reproduce([outcome])
    assert html.count("<svg") == 1 and "y against x" in html
    data = json.loads(reproduce_json([outcome]))["experiments"]["notes.example8"]
    assert data["figure"]["lines"]["ours"] == {"x": [1.0, 2.0, 3.0], "y": [1.0, 2.0, 0.0]}


def test_the_readme_table_gives_why_an_experiment_differs():
    from ssecert.experiments import agreement_table

    entry = {"match": "differs", "agreement": "differs: x by 50%", "why": "y is larger"}
    table = agreement_table({"experiments": {"notes.example0": entry}})
    assert "- `notes.example0`: differs: x by 50%. Why: y is larger" in table
    assert "| notes | 1 | 0 | 0 | 1 | 0 | 0 |" in table
