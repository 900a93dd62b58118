"""--solver: the LMIs go to the solver named, certificates re-verified whichever solves them."""

import collections

import cvxpy as cp
import pytest

from ssecert.cli import main
from ssecert.examples import load_example
from ssecert.observers import build_observer
from ssecert.observers.lure import LureModel
from ssecert.solvers import check_solver, solve_conic, solver_name, using_solver
from ssecert.stability.checks import observer_checks
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


needs_scs = pytest.mark.skipif("SCS" not in cp.installed_solvers(), reason="SCS is not installed")


@needs_scs
def test_the_piecewise_lmi_layer_goes_to_the_chosen_solver():
    # X >= C and -X >= -C force X = C: the same problem through cvxpy, Clarabel's svec unpacked
    import numpy as np

    from ssecert.stability._conic import LMIProblem

    rng = np.random.default_rng(0)
    R = rng.standard_normal((4, 4))
    C = R @ R.T
    found = {}
    for name in ("CLARABEL", "SCS"):
        with using_solver(name):
            lp = LMIProblem()
            X = lp.block(4)
            W = lp.block(2, nonneg=True)
            lp.lmi(-C, [(X, np.eye(4), 1.0)])
            lp.lmi(C, [(X, np.eye(4), -1.0)])
            lp.lmi(-np.ones((1, 1)), [(W, np.array([[0.0], [1.0]]), 1.0)])  # W_22 >= 1
            x, info = lp.solve()
        assert x is not None and info["solver"] == name, info
        np.testing.assert_allclose(lp.matrix(x, X), C, atol=1e-4)
        assert lp.matrix(x, W)[1, 1] >= 1 - 1e-4 and np.all(lp.matrix(x, W) >= -1e-6)
        found[name] = info["status"]
    assert found == {"CLARABEL": "Solved", "SCS": "optimal"}


@pytest.mark.parametrize("name", ["CLARABEL", pytest.param("SCS", marks=needs_scs)])
def test_the_lmi_layer_maximises_a_scalar(name):
    # t I <= X <= diag(2, 3, 5): the largest t is 2, through Clarabel and through cvxpy
    import numpy as np

    from ssecert.stability._conic import LMIProblem

    with using_solver(name):
        lp = LMIProblem()
        X, t = lp.block(3), lp.scalar()
        lp.lmi(np.zeros((3, 3)), [(X, np.eye(3), 1.0)], [(t, np.eye(3), -1.0)])
        lp.lmi(np.diag([2.0, 3.0, 5.0]), [(X, np.eye(3), -1.0)])
        lp.maximize(t)
        x, info = lp.solve()
    assert x is not None and info["solver"] == name, info
    assert lp.value(x, t) == pytest.approx(2.0, abs=1e-4)


@needs_scs
def test_the_piecewise_region_is_searched_again_for_another_solver(monkeypatch):
    from ssecert.stability import piecewise

    calls = []
    monkeypatch.setattr(piecewise, "_CACHE", {})
    monkeypatch.setattr(
        piecewise, "_search", lambda *args: calls.append(solver_name()) or {"radius": 0.0}
    )
    model = _model()
    piecewise.piecewise_region(model)
    piecewise.piecewise_region(model)  # remembered
    with using_solver("SCS"):
        piecewise.piecewise_region(model)
    assert calls == ["CLARABEL", "SCS"]


@needs_scs
@pytest.mark.slow
def test_the_piecewise_region_lmis_are_solved_by_the_chosen_solver_and_verified():
    from dataclasses import replace

    from ssecert.stability import piecewise as pw

    spec = load_example("ugv")
    model = LureModel.from_design(build_observer(spec.system, {**spec.observer, "step": 0.3}))
    regions = pw._Regions(model)
    empty = pw._empty_pairs(regions, replace(model, threshold=1.0), 20.0)
    for name in ("CLARABEL", "SCS"):
        with using_solver(name):
            found = pw._attempt(model, regions, 3.0, 6.0, 100.0, empty, set())
        # the evidence row names the solver, as the other LMIs' attempts do
        assert found.record["solver"] == name
        assert found.ok and found.record["verified"], found.record  # re-verified in numpy
        assert found.margin > 100 * found.bound


@needs_scs
def test_the_method_names_the_solver_the_lmis_went_to():
    from ssecert.solvers import solver_label

    assert solver_label() == "Clarabel"
    spec = load_example("ugv")
    observer = {"kind": "elastic_net", "gain": "pinv", "step": 0.3, "threshold": 0.1,
                "shrink": 0.5}  # fmt: skip
    with using_solver("SCS"):
        assert solver_label() == "SCS"
        checks = {c.id: c for c in observer_checks(spec.system, observer)}
    assert checks["observer_stability"].method.endswith("(LMI, SCS)")
