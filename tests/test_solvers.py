"""--solver: the LMIs go to the solver named, certificates re-verified whichever solves them."""

import collections

import cvxpy as cp
import pytest

from ssecert.cli import main
from ssecert.examples import load_example
from ssecert.observers import build_observer
from ssecert.observers.lure import LureModel
from ssecert.solvers import check_solver, solve_conic, solver_name, using_solver
from ssecert.stability.lmi import circle_certificate


def _model() -> LureModel:
    spec = load_example("ugv")
    observer = {"kind": "elastic_net", "gain": "pinv", "step": 0.3, "threshold": 0.1,
                "shrink": 0.5}  # fmt: skip
    return LureModel.from_design(build_observer(spec.system, observer))


def test_the_solver_named_solves_the_lmis_and_the_verdict_is_re_verified(monkeypatch):
    calls: collections.Counter = collections.Counter()
    solve = cp.Problem.solve

    def logged(self, *args, **kwargs):
        calls[kwargs.get("solver")] += 1
        return solve(self, *args, **kwargs)

    monkeypatch.setattr(cp.Problem, "solve", logged)
    default = circle_certificate(_model())
    assert solver_name() == "CLARABEL" and set(calls) == {"CLARABEL"}
    calls.clear()
    with using_solver("scs") as name:
        assert name == "SCS" and solver_name() == "SCS"
        other = circle_certificate(_model())
    assert set(calls) == {"SCS"} and solver_name() == "CLARABEL"
    assert other.verdict == default.verdict  # both verified in numpy
    assert other.details["attempts"][0]["solver"] == "SCS"  # and the evidence says so


def test_clarabel_options_are_translated_or_left_out(monkeypatch):
    seen = {}
    monkeypatch.setattr(cp.Problem, "solve", lambda self, **kwargs: seen.update(kwargs))
    options = {"tol_gap_abs": 1e-6, "tol_feas": 1e-7, "max_iter": 60, "time_limit": 5.0}
    with using_solver("SCS"):
        solve_conic(cp.Problem(cp.Minimize(0)), **options)
    assert seen == {"solver": "SCS", "eps_abs": 1e-6, "time_limit_secs": 5.0}
    seen.clear()
    solve_conic(cp.Problem(cp.Minimize(0)), **options)
    assert seen == {"solver": "CLARABEL", **options}


@pytest.mark.parametrize(
    ("name", "fragment"),
    [("highs", "does not solve semidefinite programs"), ("nosuch", "is not a cvxpy solver")],
)
def test_a_solver_that_cannot_solve_the_lmis_is_refused(name, fragment, capsys):
    with pytest.raises(ValueError, match=fragment):
        check_solver(name)
    assert main(["analyze", "notes-example-2", "--solver", name]) == 2
    err = capsys.readouterr().err
    assert f"--solver {name}: solver '{name}' {fragment}" in err
    assert "the installed solvers for the LMIs are CLARABEL" in err
