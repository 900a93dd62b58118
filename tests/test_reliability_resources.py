"""Bounded memory and time, and no internal error on a valid design.

Every request either runs within a stated budget or is refused up front
with the estimate: inconclusive checks (analyses that cannot be afforded) or
a one-line error with exit status 2 (simulations that cannot be run).  A
search or solve that cannot finish ends in an inconclusive result with the
actual reason.  No test here allocates more than a few hundred megabytes.
"""

import json
import math
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from ssecert import System, analyze, irrepresentable, sparse_observability, spec_from_dict
from ssecert.budget import (
    Budget,
    Refusal,
    Resource,
    ResourceLimitError,
    bounded_comb,
    parse_bytes,
)
from ssecert.certify import certify
from ssecert.cli import main
from ssecert.examples import load_example
from ssecert.observers import build_observer
from ssecert.results import to_jsonable
from ssecert.simulation.engine import simulate_scenario, simulate_spec
from ssecert.stability import checks as stability_checks
from ssecert.stability import counterexample_search, lmi, region, thesis_messages
from ssecert.stability.checks import observer_checks
from ssecert.stability.outcomes import AssumptionCode, LMICause, LMICode, SeriesCode
from ssecert.stability.thesis import SeriesError, pi_map, thesis_assumptions
from ssecert.stability.thesis_messages import series_failure
from ssecert.structure.attacks import WITNESS_MAX_STEPS
from ssecert.structure.outcomes import IrrepresentableCode

KINDS = ("luenberger", "ogd", "sso", "dsso", "elastic_net")
EXTREMES = (1e-8, 1e-4, 0.01, 0.1, 0.5, 1.0, 2.0, 10.0, 1e3)


def _number(rng):
    if rng.random() < 0.4:
        return float(rng.choice(EXTREMES))
    return float(np.exp(rng.uniform(np.log(1e-8), np.log(1e3))))


def random_design(seed, kind):
    """A valid spec: n <= 8, p <= 10, stable or unstable plant, extreme observer settings."""
    rng = np.random.default_rng(seed)
    n, p = int(rng.integers(1, 9)), int(rng.integers(1, 11))
    style = rng.choice(["random", "diag", "identity", "rotation", "jordan"])
    rho = float(rng.choice([0.3, 0.9, 0.999, 1.0, 1.03, 1.5, 3.0]))
    if style == "random":
        A = rng.standard_normal((n, n))
        A *= rho / max(np.abs(np.linalg.eigvals(A)).max(), 1e-9)
    elif style == "diag":
        A = np.diag(rng.uniform(-rho, rho, n))
    elif style == "identity":
        A = rho * np.eye(n)
    elif style == "rotation":
        A = rho * np.eye(n)
        for i in range(0, n - 1, 2):
            t = rng.uniform(0, np.pi)
            A[i : i + 2, i : i + 2] = rho * np.array(
                [[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]]
            )
    else:
        A = rho * np.eye(n) + np.diag(np.ones(n - 1), 1)
    C = rng.standard_normal((p, n)) * float(rng.choice([1e-3, 0.1, 1.0, 10.0, 1e3]))
    if rng.random() < 0.2:
        C[rng.integers(0, p)] = 0.0
    observer = {"kind": kind}
    if kind in ("luenberger", "dsso", "elastic_net"):
        gain = str(rng.choice(["deadbeat", "place", "pinv", "matrix"]))
        observer["gain"] = (
            (rng.standard_normal((n, p)) * _number(rng)).tolist() if gain == "matrix" else gain
        )
        if gain == "place":
            observer["poles"] = [float(x) for x in rng.uniform(-0.9, 0.9, n)]
    if kind != "luenberger":
        observer["step"] = _number(rng)
    if kind in ("sso", "dsso", "elastic_net"):
        observer["threshold"] = _number(rng)
    if kind == "elastic_net":
        observer["shrink"] = float(rng.choice([1e-8, 0.1, 0.5, 0.9, 1 - 1e-8]))
    if kind == "sso" and rng.random() < 0.5:
        observer["window"] = int(rng.integers(1, 4))
    return {
        "name": f"random{seed}",
        "system": {"A": A.tolist(), "C": C.tolist()},
        "attack": {"max_attacked": int(rng.integers(0, p + 1))},
        "observer": observer,
    }


def _write(tmp_path, text, name="spec.toml"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def _run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _ugv_like(n=2):
    """A plant whose first sensor is a single point of failure (sparse observability fails)."""
    A = np.eye(n)
    C = np.vstack([np.eye(n)[:1], np.eye(n)[1:], np.eye(n)[1:]])
    return A, C


# ---------------------------------------------------------------------------
# 1. no internal error on a valid design

D2 = """name = "d2"
[system]
A = [[-1.03]]
C = [[0.11]]
[attack]
max_attacked = 0
[observer]
kind = "sso"
step = 1
threshold = 1
"""


def test_d2_sso_on_unstable_plant_is_not_an_internal_error(tmp_path, capsys):
    code, out, err = _run(capsys, "analyze", _write(tmp_path, D2), "--json", "-")
    assert code in (0, 1, 3), err
    doc = json.loads(out)
    thesis = doc["checks"]["thesis_assumptions"]
    # the series for Pi needs more terms than are summed at the far points of the search:
    # reported as evaluations that could not be done, not as an exception
    items = thesis["evidence"]
    assert set(items) >= {"lemma_1", "assumption_3", "epsilon_bound"}
    assert doc["checks"]["observer_stability"]["verdict"] == "fails"  # |F| = 1.0175 > 1


def test_pi_map_reports_why_the_series_cannot_be_summed():
    F_inv, L1 = np.array([[1 / -1.0175]]), np.array([[0.1133]])
    with pytest.raises(SeriesError, match="needs 2e\\+04 terms at max \\|a_i\\| = 2e\\+04"):
        pi_map(np.array([[2e4]]), F_inv, L1, 1.0, 1.0)
    with pytest.raises(SeriesError, match="overflow"):
        pi_map(np.array([[5e3]]), np.array([[1e3]]), L1, 1.0, 1.0)
    assert np.all(np.isfinite(pi_map(np.array([[5.0]]), F_inv, L1, 1.0, 1.0)))


SERIES_DESIGNS = json.loads(
    (Path(__file__).parent / "data" / "thesis_series_designs.json").read_text()
)


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(SERIES_DESIGNS)))
def test_sso_designs_whose_thesis_search_once_raised(index, monkeypatch):
    """Random SSO designs whose Assumption 3 search raised "the series for Pi did not
    terminate"; the far points of the search are now counted, with the reason."""
    # the reasons as typed values, read where their words are written
    seen = []

    def recording(failure):
        seen.append(failure)
        return series_failure(failure)

    monkeypatch.setattr(thesis_messages, "series_failure", recording)
    monkeypatch.setattr(counterexample_search, "series_failure", recording)
    spec = spec_from_dict(SERIES_DESIGNS[index])
    design = build_observer(spec.system, spec.observer)
    start = time.perf_counter()
    verdict, items = thesis_assumptions(design, observability_holds=True)
    assert time.perf_counter() - start < 20
    assert verdict in ("holds", "fails", "inconclusive")
    failures = [
        d.get("first_failure") or d.get("search", {}).get("first_failure")
        for d in (i.details for i in items)
        if isinstance(d, dict)
    ]
    codes = {series_failure(failure): failure.code for failure in seen}
    for reason in filter(None, failures):
        assert codes[reason] in (
            SeriesCode.TOO_MANY_TERMS,
            SeriesCode.POWERS_OVERFLOW,
            SeriesCode.SUM_OVERFLOW,
        )


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(12))
def test_random_designs_of_every_kind_analyze_without_exception(seed):
    spec = spec_from_dict(random_design(seed, KINDS[seed % 5]))
    start = time.perf_counter()
    cert = analyze(spec)
    assert time.perf_counter() - start < 60
    json.dumps(cert.to_dict(), allow_nan=False)
    for check in cert.checks:
        assert check.verdict.value in ("holds", "fails", "inconclusive")
        if check.verdict.value == "inconclusive":
            assert check.summary


# ---------------------------------------------------------------------------
# 2. solver failures are inconclusive with the reason, never holds


def _elastic_net_model():
    spec = load_example("ugv")
    design = build_observer(
        spec.system,
        {
            "kind": "elastic_net",
            "gain": "place",
            "poles": [0.5, 0.6],
            "step": 0.05,
            "threshold": 0.1,
            "shrink": 0.5,
        },
    )
    return design, lmi.LureModel.from_design(design)


def _failing_solve(mode):
    import cvxpy as cp

    def solve(self, *args, **kwargs):
        if mode == "raise":
            raise cp.error.SolverError("Clarabel failed (simulated)")
        if mode == "nan":
            for var in self.variables():
                var._value = np.full(var.shape, np.nan)
            self._status = "optimal"
            return 0.0
        self._status = mode  # a status, and no values
        return None

    return solve


@pytest.mark.slow
@pytest.mark.parametrize(
    "mode", ["raise", "infeasible_inaccurate", "solver_error", "optimal", "nan"]
)
def test_lmi_solver_failures_are_inconclusive(monkeypatch, mode):
    import cvxpy as cp

    design, model = _elastic_net_model()
    assert lmi.circle_certificate(model).verdict == "holds"  # with a working solver
    monkeypatch.setattr(cp.Problem, "solve", _failing_solve(mode))
    circle = lmi.circle_certificate(model)
    iss = lmi.iss_certificate(model)
    for cert in (circle, iss):
        assert cert.verdict == "inconclusive"
        expected = {
            "raise": "SolverError: Clarabel failed",
            "nan": "no finite values",
            "optimal": "no finite values",
        }.get(mode, mode)
        assert expected in cert.reason
    grid = region.region_map(design, [0.5, 0.9], [0.05])
    assert set(grid.verdicts.ravel()) == {"inconclusive"}
    checks = {
        c.id: c
        for c in observer_checks(
            design.system,
            {
                "kind": "elastic_net",
                "gain": "place",
                "poles": [0.5, 0.6],
                "step": 0.05,
                "threshold": 0.1,
                "shrink": 0.5,
            },
        )
    }
    assert checks["observer_stability"].verdict.value == "inconclusive"
    assert checks["observer_stability"].code is LMICause.CIRCLE_NOT_VERIFIED
    assert checks["iss_gain"].verdict.value == "inconclusive"


def test_solver_failure_in_the_cli_is_exit_3_not_4(monkeypatch, tmp_path, capsys):
    import cvxpy as cp

    monkeypatch.setattr(cp.Problem, "solve", _failing_solve("raise"))
    spec = _write(
        tmp_path,
        """name = "en"
[system]
A = [[0.5, 0.1], [0.0, 0.6]]
C = [[1, 0], [0, 1], [1, 1], [1, -1], [2, 1]]
[attack]
max_attacked = 1
[observer]
kind = "elastic_net"
gain = "pinv"
step = 0.05
threshold = 0.1
shrink = 0.5
""",
    )
    code, out, err = _run(capsys, "analyze", spec, "--json", "-")
    assert code == 3, err
    stab = json.loads(out)["checks"]["observer_stability"]
    assert stab["verdict"] == "inconclusive"
    # every solve raised, and each attempt records the solver's error as its status
    statuses = {a["status"] for a in stab["evidence"]["attempts"]}
    assert statuses == {"solver error: SolverError: Clarabel failed (simulated)"}


def test_iss_gain_from_a_circle_certificate_survives_singular_schur_blocks():
    _, model = _elastic_net_model()
    circle = lmi.circle_certificate(model)
    broken = lmi.LMICertificate(
        "holds",
        "circle",
        P=np.zeros_like(circle.P),
        multipliers=circle.multipliers,
        decay=circle.decay,
        code=LMICode.VERIFIED,
    )
    cert = lmi.iss_from_circle(model, broken)
    assert cert.verdict == "inconclusive" and cert.reason


# ---------------------------------------------------------------------------
# 3. bounded resources

PLANT3 = """name = "plant3"
[system]
A = [[0.9, 0.1, 0.0], [0.0, 0.8, 0.1], [0.0, 0.0, 0.7]]
C = [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]]
[attack]
max_attacked = 1
"""


@pytest.mark.slow
@pytest.mark.parametrize("where", ["option", "spec"])
def test_huge_horizon_is_inconclusive_with_the_estimate(tmp_path, capsys, where):
    """Within the spec's limit (10,000 steps) the irrepresentable check of this plant would
    need about 9.6 GB: it is inconclusive and says so, the rest is decided."""
    horizon = "10000"
    text = PLANT3 + (f"horizon = {horizon}\n" if where == "spec" else "")
    argv = ["analyze", _write(tmp_path, text), "--json", "-"]
    if where == "option":
        argv += ["--horizon", horizon]
    start = time.perf_counter()
    code, out, err = _run(capsys, *argv)
    assert time.perf_counter() - start < 20
    assert code in (0, 1, 3), err
    irr = json.loads(out)["checks"]["irrepresentable"]
    assert irr["verdict"] == "inconclusive"
    # refused by the memory budget of 2 GiB (its words and the --horizon hint of a horizon
    # longer than n: tests/test_irrepresentable_messages.py)
    estimate, budget = irr["evidence"]["estimate"], irr["evidence"]["budget"]
    assert budget["memory_bytes"] == 2 * 2**30 < estimate["bytes"]
    assert irr["horizon"] == 10_000  # longer than n = 3: the words name --horizon


@pytest.mark.parametrize("where", ["option", "spec"])
@pytest.mark.parametrize("horizon", ["10000000", "1000000000000"])
def test_horizon_beyond_the_limit_is_refused(tmp_path, capsys, where, horizon):
    text = PLANT3 + (f"horizon = {horizon}\n" if where == "spec" else "")
    argv = ["analyze", _write(tmp_path, text), "--json", "-"]
    if where == "option":
        argv += ["--horizon", horizon]
    code, out, err = _run(capsys, *argv)
    assert code == 2 and out == ""
    assert ("--horizon" if where == "option" else "attack.horizon") in err
    assert "10,000" in err and err.count("\n") == 1


def test_stealthy_witness_is_bounded_for_a_huge_horizon():
    A, C = _ugv_like(3)
    check = sparse_observability(System(A, C), 1, horizon=10**9)
    assert check.verdict.value == "fails"
    witness = check.witness
    assert witness["verified"]
    assert np.asarray(witness["attack_a"]).shape == (WITNESS_MAX_STEPS, 5)
    assert witness["horizon"] == 10**9 and "Cayley-Hamilton" in witness["truncated"]


@pytest.mark.parametrize("method", ["auto", "enumeration", "eigenspace"])
def test_s_far_above_p_returns_at_once(method):
    rng = np.random.default_rng(0)
    plant = System(np.eye(4), rng.standard_normal((6, 4)))
    start = time.perf_counter()
    sparse = sparse_observability(plant, 10**12, method=method)
    irr = irrepresentable(plant, 10**12)
    assert time.perf_counter() - start < 5
    assert sparse.verdict.value == "fails" and irr.verdict.value == "fails"
    assert irr.code is IrrepresentableCode.SUPPORT_TOO_LARGE


@pytest.mark.slow
def test_s_far_above_p_through_analyze_and_certify(tmp_path, capsys):
    spec = (
        PLANT3.replace("max_attacked = 1", "max_attacked = 1000000000000")
        + """
[observer]
kind = "elastic_net"
gain = "pinv"
step = 0.1
threshold = 0.1
shrink = 0.5
[[scenario]]
name = "stealthy"
attack = "stealthy"
steps = 20
runs = 2
"""
    )
    start = time.perf_counter()
    code, out, err = _run(
        capsys, "certify", _write(tmp_path, spec), "--out", str(tmp_path), "--json", "-"
    )
    assert time.perf_counter() - start < 60
    assert code == 1, err
    doc = json.loads(out)
    assert doc["checks"]["sparse_observability"]["verdict"] == "fails"


def test_astronomically_many_supports_respect_the_budget():
    rng = np.random.default_rng(1)
    plant = System(0.5 * np.eye(2), rng.standard_normal((400, 2)))
    start = time.perf_counter()
    check = irrepresentable(plant, 200, horizon=1)
    assert time.perf_counter() - start < 2
    assert check.code is IrrepresentableCode.TOO_MANY_SUPPORTS
    # C(400, 200) ~ 1e119, stated (in scientific notation: the messages' tests), never formed
    # in a loop
    assert check.evidence["supports"] is None and check.evidence["supports_log10"] > 119
    entrywise = irrepresentable(plant, 10**6, horizon=10**6, mode="entrywise")
    assert entrywise.verdict.value == "inconclusive"
    # 499,500 supports are countable but too much work (about 5 minutes): refused at once
    wide = System(0.5 * np.eye(5), rng.standard_normal((1000, 5)))
    start = time.perf_counter()
    work = irrepresentable(wide, 2)
    assert time.perf_counter() - start < 2
    assert work.code is IrrepresentableCode.OVER_BUDGET and work.evidence["supports"] == 499_500
    assert work.evidence["estimate"]["flops"] > 1e12


@pytest.mark.slow
def test_irrepresentable_stays_within_a_small_memory_budget():
    rng = np.random.default_rng(2)
    A = rng.standard_normal((6, 6))
    plant = System(0.9 * A / np.abs(np.linalg.eigvals(A)).max(), rng.standard_normal((8, 6)))
    small = Budget(memory=48 * 2**20)
    reference = irrepresentable(plant, 2, horizon=300)
    tracemalloc.start()
    bounded = irrepresentable(plant, 2, horizon=300, budget=small)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert bounded.verdict == reference.verdict
    assert bounded.value == pytest.approx(reference.value, rel=1e-9)
    assert peak < small.memory
    refused = irrepresentable(plant, 2, horizon=3000, budget=small)
    assert refused.code is IrrepresentableCode.OVER_BUDGET
    assert refused.evidence["estimate"]["bytes"] > small.memory


SSO_WINDOW = """name = "window"
[system]
A = {A}
C = {C}
[attack]
max_attacked = 1
[observer]
kind = "sso"
step = 0.01
threshold = 0.1
window = {window}
"""


def _window_spec(window):
    rng = np.random.default_rng(1)
    A = rng.standard_normal((12, 12))
    A *= 0.95 / np.abs(np.linalg.eigvals(A)).max()
    C = rng.standard_normal((3, 12))
    return spec_from_dict(
        {
            "name": "window",
            "system": {"A": A.tolist(), "C": C.tolist()},
            "attack": {"max_attacked": 1},
            "observer": {"kind": "sso", "step": 0.01, "threshold": 0.1, "window": window},
        }
    )


@pytest.mark.slow
def test_sso_window_50_lmi_is_refused_with_the_estimate():
    spec = _window_spec(50)
    design = build_observer(spec.system, spec.observer)
    model = lmi.LureModel.from_design(design)
    nbytes, _ = lmi.lmi_cost(model, "circle", "block-diagonal")
    assert 4 * 2**30 < nbytes < 12 * 2**30  # measured: 6.9 GB
    checks = {c.id: c for c in observer_checks(spec.system, spec.observer)}
    stab = checks["observer_stability"]
    assert stab.verdict.value == "inconclusive"
    # refused by the memory budget (2 GiB) with the LMI's estimate, and said so
    # no solve fits: the LMIs were not verified, each refused with its estimate
    assert stab.code is LMICause.CIRCLE_NOT_VERIFIED and model.N + model.m == 312
    refusal = lmi._solve_refusal(model, "circle", "block-diagonal", Budget())
    assert refusal.resource is Resource.MEMORY and refusal.limit == 2 * 2**30
    assert refusal.need == nbytes
    assert str(refusal) in stab.summary


def test_sso_window_too_large_to_build_is_inconclusive_not_allocated(tmp_path):
    spec = _window_spec(10**6)
    start = time.perf_counter()
    checks = {c.id: c for c in observer_checks(spec.system, spec.observer)}
    assert time.perf_counter() - start < 2
    assert checks["observer_gain"].verdict.value == "inconclusive"
    assert checks["observer_gain"].fields["L"] is None
    # the budget's refusal (its words: test_observer_messages) is what the check and the
    # certificate's notes say
    with pytest.raises(ResourceLimitError) as refused:
        build_observer(spec.system, spec.observer)
    assert str(refused.value) in checks["observer_gain"].summary
    result = certify(spec, simulate=False)
    assert sum(str(refused.value) in note for note in result.notes) == 1


def test_small_budget_refuses_the_lure_model_and_the_region_map():
    spec = _window_spec(60)
    tiny = Budget(memory=2**20)
    checks = {c.id: c for c in observer_checks(spec.system, spec.observer, budget=tiny)}
    stab = checks["observer_stability"]
    assert stab.verdict.value == "inconclusive" and stab.code is LMICause.REFUSED
    design = build_observer(spec.system, spec.observer)
    refusal = stability_checks._lure_model_refusal(design, tiny)
    assert refusal.resource is Resource.MEMORY and refusal.limit == 2**20
    assert str(refusal) in stab.summary
    en = load_example("ugv")
    design = build_observer(
        en.system,
        {
            "kind": "elastic_net",
            "gain": "place",
            "poles": [0.5, 0.6],
            "step": 0.05,
            "threshold": 0.1,
            "shrink": 0.5,
        },
    )
    from ssecert.certify import _region, _region_grid, _region_refusal

    notes = []
    assert _region(design, notes, lambda message: None, Budget(work=1e6)) is None
    # not mapped: the work budget refuses the grid, and the one note gives the refusal
    refusal = _region_refusal(design, *_region_grid(design), Budget(work=1e6))
    assert refusal.resource is Resource.WORK and refusal.need > refusal.limit == 1e6
    assert len(notes) == 1 and notes[0].endswith(str(refusal))


def test_thesis_checks_refuse_huge_attack_estimates():
    spec = _window_spec(10)
    design = build_observer(spec.system, spec.observer)
    verdict, items = thesis_assumptions(design, budget=Budget(memory=2**20))
    codes = {i.name: i.code for i in items}
    assert verdict == "inconclusive" and codes["lemma_1"] is AssumptionCode.NOT_ATTEMPTED
    lemma = next(i for i in items if i.name == "lemma_1")
    refusal = lemma.facts["refusal"]  # what was refused, and the numbers
    assert refusal.resource is Resource.MEMORY and refusal.limit == 2**20 < refusal.need
    assert refusal.what == "checking Lemma 1 and Assumption 3 with 30 attack-estimate entries"


SCENARIO_SPEC = """name = "sim"
[system]
A = [[0.9, 0.1], [0.0, 0.8]]
C = [[1, 0], [0, 1], [1, 1]]
[attack]
max_attacked = 1
[observer]
kind = "elastic_net"
gain = "pinv"
step = 0.1
threshold = 0.1
shrink = 0.5
[[scenario]]
name = "constant"
attack = "constant"
sensors = [1]
runs = {runs}
steps = {steps}
"""


def test_simulate_refuses_runs_times_steps_up_front(tmp_path, capsys):
    path = _write(tmp_path, SCENARIO_SPEC.format(runs=1000000000, steps=100000000))
    start = time.perf_counter()
    code, out, err = _run(capsys, "simulate", path)
    assert time.perf_counter() - start < 5
    assert code == 2
    assert err.count("\n") == 1 and "scenario[0].runs and scenario[0].steps" in err
    assert "needs about" in err
    small = _write(tmp_path, SCENARIO_SPEC.format(runs=2, steps=10), "small.toml")
    code, out, err = _run(capsys, "simulate", small, "--steps", "1000000000")
    assert code == 2 and "--steps" in err and "scenario[0].runs" in err
    window = _write(
        tmp_path,
        SCENARIO_SPEC.format(runs=2, steps=10)
        .replace('kind = "elastic_net"\ngain = "pinv"', 'kind = "sso"')
        .replace("shrink = 0.5", "window = 1000000"),
        "window.toml",
    )
    code, out, err = _run(capsys, "simulate", window)
    assert code == 2 and err.count("\n") == 1
    assert "window.toml: observer.window = 1,000,000" in err and "TiB" in err


def test_certify_skips_a_scenario_over_the_budget(tmp_path):
    from ssecert import load_spec

    spec = load_spec(_write(tmp_path, SCENARIO_SPEC.format(runs=1000000000, steps=100000000)))
    result = certify(spec, region=False)
    skipped = result.simulations["constant"]
    assert "needs about" in skipped["skipped"] and "memory budget" in skipped["skipped"]


@pytest.mark.slow
def test_simulation_chunks_fit_a_small_memory_budget(tmp_path):
    from ssecert import load_spec

    spec = load_spec(_write(tmp_path, SCENARIO_SPEC.format(runs=64, steps=1500)))
    design = build_observer(spec.system, spec.observer)
    full = simulate_scenario(design, spec.scenarios[0])
    small = Budget(memory=8 * 2**20)
    tracemalloc.start()
    bounded = simulate_scenario(design, spec.scenarios[0], budget=small)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert peak < small.memory
    np.testing.assert_allclose(bounded.relative_error, full.relative_error, rtol=1e-12, atol=1e-12)
    with pytest.raises(ResourceLimitError, match="needs about"):
        simulate_spec(spec, steps=10**9)


def test_budget_options_on_the_command_line(tmp_path, capsys):
    path = _write(tmp_path, PLANT3)
    code, out, err = _run(capsys, "analyze", path, "--memory-budget", "lots")
    assert code == 2 and "--memory-budget" in err and "512M" in err
    code, out, err = _run(
        capsys, "analyze", path, "--horizon", "3000", "--memory-budget", "8M", "--json", "-"
    )
    assert code in (0, 1, 3), err
    irr = json.loads(out)["checks"]["irrepresentable"]
    assert irr["verdict"] == "inconclusive"
    budget = irr["evidence"]["budget"]
    assert budget["memory_bytes"] == 8 * 2**20 < irr["evidence"]["estimate"]["bytes"]
    assert parse_bytes("8G") == 8 * 2**30
    assert bounded_comb(10**12, 10**6, 10**9) is None and bounded_comb(6, 3, 100) == 20
    assert math.isfinite(Budget().memory)


def test_long_horizon_on_an_unstable_plant_does_not_change_the_sparse_verdict():
    """The witness of an unstable plant overflows after a few hundred steps; the steps
    before the overflow (at least n) decide it, so the verdict does not depend on tau."""
    plant = System([[3.0, 0.0], [0.0, 0.5]], [[1, 0], [0, 1], [0, 1]])
    short = sparse_observability(plant, 1, horizon=2)
    long = sparse_observability(plant, 1, horizon=700)
    assert short.verdict.value == long.verdict.value == "fails"
    witness = long.witness
    assert witness["verified"] and witness["steps"] < 700
    assert "overflow in floating point" in witness["truncated"]
    assert np.all(np.isfinite(np.asarray(witness["attack_a"], dtype=float)))


def test_an_sso_with_a_billion_inner_steps_is_refused_by_simulate_naming_the_field(tmp_path):
    # its Python loop of inner steps was not in the work estimate: 1 run x 1 step ran for hours
    import json
    import subprocess
    import sys

    spec = {
        "name": "inner",
        "system": {"A": [[0.5, 0.1], [0.0, 0.6]], "C": [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]},
        "attack": {"max_attacked": 1},
        "observer": {"kind": "sso", "step": 0.1, "threshold": 0.1, "inner_steps": 10**9},
        "scenario": [{"name": "x", "attack": "constant", "sensors": [1], "steps": 1, "runs": 1}],
    }
    path = tmp_path / "inner.json"
    path.write_text(json.dumps(spec))
    done = subprocess.run(
        [sys.executable, "-m", "ssecert", "simulate", str(path)],
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert "observer.inner_steps" in done.stderr and "work budget" in done.stderr


def test_a_refusal_carries_what_it_refused_and_its_numbers():
    # code reads the resource and the numbers; the words are written once, from them
    budget = Budget(memory=2**30, work=1e9)
    assert budget.check("a small step", nbytes=2**20, flops=1e6) is None
    memory = budget.check("a big matrix", nbytes=3 * 2**30, flops=1e15)  # memory first
    assert (memory.resource, memory.need, memory.limit) == (Resource.MEMORY, 3 * 2**30, 2**30)
    assert str(memory) == (
        "a big matrix needs about 3 GiB of memory, over the memory budget of 1 GiB "
        "(--memory-budget)"
    )
    work = budget.check("a long loop", flops=2.5e9)
    assert (work.resource, work.need, work.limit) == (Resource.WORK, 2.5e9, 1e9)
    assert str(work) == budget.refusal("a long loop", flops=2.5e9)
    with pytest.raises(ResourceLimitError) as raised:
        budget.require("a long loop", flops=2.5e9)
    assert str(raised.value) == str(work)
    rows = Refusal("the order-2 LMI", Resource.ROWS, 900, 600)
    assert str(rows) == "the order-2 LMI has 900 rows, more than 600"
    assert to_jsonable({"refusal": rows}) == {"refusal": str(rows)}  # JSON keeps the sentence
