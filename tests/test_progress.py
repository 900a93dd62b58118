"""What the command shows on stderr while it works (ssecert.cli.progress): the stages with
their elapsed time once past a second, the sets done; nothing of it in the results."""

from __future__ import annotations

import io
import json
import time

import pytest

from ssecert.budget import Laps, stage, watching_stages
from ssecert.cli import main
from ssecert.cli import progress as shown


class _Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_stages_nest_and_laps_tell_their_steps():
    told: list[tuple[str, str]] = []

    class Listener:
        def begin(self, name: str) -> None:
            told.append(("begin", name))

        def end(self, name: str, seconds: float) -> None:
            told.append(("end", name))

    clock = Laps()
    clock.begin("unseen")  # no listener: nothing told, nothing kept
    clock.lap("unseen", None)
    with watching_stages(Listener()):
        clock.begin("observer_checks")
        with stage("piecewise LMIs"):
            pass
        clock.lap("observer_checks", None)
        clock.lap("not begun", None)  # a lap without begin tells no end
    assert told == [
        ("begin", "observer_checks"),
        ("begin", "piecewise LMIs"),
        ("end", "piecewise LMIs"),
        ("end", "observer_checks"),
    ]
    assert set(clock.seconds) == {"unseen", "observer_checks", "not begun"}


def test_off_a_terminal_a_stage_gets_a_line_once_it_passes_a_second():
    clock, out = _Clock(), io.StringIO()
    display = shown._Display(out, lines=True, clock=clock)
    display.begin("observer_checks")
    display.begin("region_of_attraction")
    clock.now += 0.5
    display.tick()
    assert out.getvalue() == ""  # nothing under a second
    clock.now += 0.7
    display.tick()
    display.tick()  # each stage once
    assert out.getvalue().splitlines() == [
        "ssecert: observer checks: running for 1.2 s",
        "ssecert: observer checks > region of attraction: running for 1.2 s",
    ]
    display.begin("piecewise LMIs, radius 10")
    display.end("observer_checks", 3.0)  # an outer stage's end closes what it left open
    assert display.stack == []
    display.end("never begun", 1.0)  # ignored
    clock.now += 5.0
    display.tick()
    assert len(out.getvalue().splitlines()) == 2


def test_the_commands_own_stages_follow_each_other():
    clock, out = _Clock(), io.StringIO()
    display = shown._Display(out, lines=True, clock=clock)
    display.say("structural checks and certificates")
    display.begin("observer_checks")
    display.say("simulating scenario stealthy")  # ends the previous one and what it holds
    assert [item[0] for item in display.stack] == ["simulating scenario stealthy"]


def test_on_a_terminal_rich_draws_the_stages_past_a_second_and_the_sets(monkeypatch):
    clock, terminal = _Clock(), _Terminal()
    display = shown._Display(terminal, live=True, clock=clock)
    with display.showing():
        with stage("observability"):
            pass
        display.begin("sparse_observability")
        display("sparse_observability", 0, 1000)
        display.progress.refresh()
        assert "sparse observability" not in terminal.getvalue()  # under a second
        clock.now += 4.0
        display("sparse_observability", 250, 1000)
        display.progress.refresh()
        drawn = terminal.getvalue()
        assert "sparse observability" in drawn and "0:00:04" in drawn
        assert "sets checked" in drawn and "250/1,000" in drawn
        assert "observability" not in drawn.replace("sparse observability", "")  # fast: not shown
        display.end("sparse_observability", 4.0)
    assert display.progress is None  # stopped, and the display cleared


def test_what_shows_where():
    def kinds(**options):
        display = shown.stage_display(**options)
        return display.live, display.lines

    # tests capture stderr: not a terminal
    assert kinds() == (False, False)
    assert kinds(verbose=True) == (False, True)
    assert kinds(quiet=True) == (False, False)


def _slow_observability(monkeypatch, seconds: float) -> None:
    import importlib

    analyze_module = importlib.import_module("ssecert.analyze")  # the module, not the function
    real = analyze_module.observability

    def slow(*args, **kwargs):
        time.sleep(seconds)
        return real(*args, **kwargs)

    monkeypatch.setattr(analyze_module, "observability", slow)
    monkeypatch.setattr(shown, "AFTER", 0.02)
    monkeypatch.setattr(shown, "TICK", 0.01)


def test_verbose_names_a_slow_stage_on_stderr_and_nothing_else_changes(
    monkeypatch, tmp_path, capsys
):
    _slow_observability(monkeypatch, 0.15)
    target = tmp_path / "c.json"
    documents = []
    assert main(["analyze", "notes-example-2", "--json", str(target)]) == 1
    documents.append(json.loads(target.read_text()))
    plain_out, plain_err = capsys.readouterr()
    assert plain_err == ""  # off a terminal, without --verbose: nothing
    assert main(["analyze", "notes-example-2", "--verbose", "--json", str(target)]) == 1
    documents.append(json.loads(target.read_text()))
    out, err = capsys.readouterr()
    assert "ssecert: observability: running for" in err
    assert out == plain_out  # stdout is the same
    for document in documents:
        document["meta"].pop("timings")
        document["meta"].pop("date")
    assert documents[0] == documents[1]  # and so is the certificate
    assert main(["analyze", "notes-example-2", "--quiet", "--json", str(target)]) == 1
    assert capsys.readouterr() == ("", "")


@pytest.mark.parametrize(
    "command", [pytest.param(["certify", "--no-sim"], marks=pytest.mark.slow), ["simulate"]]
)
def test_the_other_commands_show_their_stages_under_verbose(monkeypatch, tmp_path, capsys, command):
    import ssecert.simulation.engine as engine

    monkeypatch.setattr(shown, "AFTER", 0.0)
    monkeypatch.setattr(shown, "TICK", 0.01)
    real = engine.simulate_scenario

    def slow(*args, **kwargs):
        time.sleep(0.1)
        return real(*args, **kwargs)

    monkeypatch.setattr(engine, "simulate_scenario", slow)
    name, *options = command
    args = [name, "notes-example-0", *options, "--verbose"]
    if name == "certify":
        args += ["--out", str(tmp_path)]
    else:
        args = [name, "ugv", "--runs", "2", "--steps", "5", "--verbose"]
    main(args)
    err = capsys.readouterr().err
    if name == "certify":
        assert "ssecert: structural checks and certificates..." in err
        assert "ssecert: writing the report..." in err
    else:
        assert "ssecert: scenario constant-velocity-a: running for" in err
