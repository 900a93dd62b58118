"""The cost model: estimates recorded and quoted, and the time budget of the eigenspace search."""

import math

import numpy as np
import pytest

from ssecert import System
from ssecert.structure import enumeration, sparse
from ssecert.structure.cost import calibrate, level_seconds, verdict_cost, workers_for
from ssecert.structure.outcomes import IrrepresentableCode, ProblemCode, SparseCode
from ssecert.structure.sparse import sparse_observability
from ssecert.structure.sparse_messages import problem_texts


def _generic(n: int, p: int, seed: int = 0) -> System:
    return System(np.eye(n), np.random.default_rng(seed).standard_normal((p, n)))


def test_rates_are_positive_and_cached():
    rates = calibrate(5)
    assert rates.per_set > 0 and rates.per_element > 0
    assert calibrate(5) is rates  # measured once per process
    assert level_seconds(20, 3, 5) > level_seconds(20, 2, 5) > 0
    assert level_seconds(20, 21, 5) == 0.0


def test_workers_for_a_budget():
    assert workers_for(10.0, 5.0) == 2
    assert workers_for(0.1, 5.0) == 1
    assert workers_for(10.0, None) is None and workers_for(10.0, 0.0) is None


def test_a_large_enumeration_records_its_estimate_and_time(monkeypatch):
    monkeypatch.setattr(enumeration, "CALIBRATE_ABOVE", 1000)
    check = sparse_observability(_generic(4, 20), 2, method="enumeration", time_budget=None)
    cost = check.evidence["cost_estimate"]
    assert cost["sets_for_verdict"] == sum(math.comb(20, k) for k in range(5))
    assert cost["seconds_for_verdict"] > 0 and cost["measured_seconds_for_verdict"] > 0
    assert cost["worker_threads"] == 1 and cost["rates"]["n"] == 4


class _Threads:
    def __init__(self, threads: int) -> None:
        self.threads = threads

    def nthreads(self) -> dict[str, int]:
        return {f"w{i}": 1 for i in range(self.threads)}


def test_the_estimate_on_workers_shares_only_the_levels_the_workers_run():
    # p = 30, up to 6 removed (n = 10): every level under 1,000,000 sets runs in-process
    alone = verdict_cost(30, 10, 6, None, None)["seconds_for_verdict"]
    assert verdict_cost(30, 10, 6, _Threads(2), None)["seconds_for_verdict"] == alone
    # p = 40: the 3,838,380 sets of 6 are shared by two threads, the smaller levels are not
    big = level_seconds(40, 6, 10, critical=True)
    rest = sum(level_seconds(40, k, 10) for k in range(6))
    spread = verdict_cost(40, 10, 6, _Threads(2), None)["seconds_for_verdict"]
    assert spread == pytest.approx(rest + big / 2, rel=0.01)
    assert verdict_cost(40, 10, 6, _Threads(4), None)["seconds_for_verdict"] == pytest.approx(
        rest + big / 4, rel=0.01
    )


def test_a_small_enumeration_is_not_calibrated():
    check = sparse_observability(_generic(3, 8), 1, method="enumeration")
    assert "cost_estimate" not in check.evidence


def test_a_refusal_over_the_set_budget_quotes_the_time_it_would_take(sparse_problems):
    check = sparse_observability(_generic(4, 40), 2, method="enumeration", max_sets=1000)
    assert check.verdict.value == "inconclusive" and check.code is SparseCode.UNDECIDED
    [[problems]] = sparse_problems
    (refusal,) = [p for p in problems if p.code is ProblemCode.SET_BUDGET]
    # the seconds the rest of the verdict's sets would take here, quoted in its words
    # (tests/test_problem_messages.py)
    assert refusal.facts["max_sets"] == 1000 and refusal.facts["seconds"] > 0
    assert check.evidence["methods_tried"][0]["problems"] == problem_texts(problems)


@pytest.mark.parametrize("allowance", [(0.0, 0.0), None])
@pytest.mark.parametrize("time_budget", [0.0, None])
def test_an_eigenspace_search_past_its_allowance_gives_way_to_the_enumeration(
    time_budget, allowance, monkeypatch, sparse_problems
):
    # A = I: one eigenspace of dimension 3, whose hyperplane search auto tries first; its
    # deadline is a multiple of its predicted time (never the refinement's time budget,
    # which is 0 for "the verdict only"), here set to zero to see it give way
    from ssecert.structure import sparse

    if allowance is not None:
        monkeypatch.setattr(sparse, "SEARCH_ALLOWANCE", allowance)
    system = _generic(3, 12, seed=4)
    check = sparse_observability(system, 2, time_budget=time_budget)
    tried = check.evidence["methods_tried"]
    assert tried[0]["method"] == "eigenspace"
    if time_budget == 0.0 and allowance is not None:
        # the search's time ran out before its first hyperplane
        assert tried[0]["status"] == "budget" and tried[0]["sets_checked"] == 0
        [problem] = sparse_problems[0][0]
        assert problem.code is ProblemCode.EIGENSPACE
        assert tried[1]["method"] == "enumeration"
    else:
        assert tried[0]["status"] == "exact"
    exact = sparse_observability(system, 2, method="enumeration", time_budget=None)
    assert check.verdict == exact.verdict
    if not check.fields["max_removable_is_lower_bound"]:
        assert check.fields["max_removable"] == exact.fields["max_removable"]


def test_a_failing_irrepresentable_scan_stops_at_the_time_budget(monkeypatch):
    import functools

    from ssecert.structure import _irrepresentable_scan
    from ssecert.structure._combinatorics import colex_blocks
    from ssecert.structure.irrepresentable import irrepresentable

    # blocks of 64 supports, so that the scan can stop between them
    monkeypatch.setattr(
        _irrepresentable_scan, "colex_blocks", functools.partial(colex_blocks, chunk_bytes=1)
    )
    rng = np.random.default_rng(2)
    system = System(rng.standard_normal((3, 3)) / 2, rng.integers(-3, 4, size=(16, 3)))
    whole = irrepresentable(system, 2, time_budget=None)
    cut = irrepresentable(system, 2, time_budget=0.0)
    assert whole.verdict.value == cut.verdict.value == "fails"
    assert "value_is_lower_bound" not in whole.fields
    assert cut.fields["value_is_lower_bound"] is True
    stopped = cut.evidence["stopped_by_time_budget"]
    assert stopped["supports"] == math.comb(16, 2) and 0 < stopped["supports_checked"] < 120
    assert 1.0 < cut.value <= whole.value
    # a failing verdict cut short after the first block (its words say so: the messages' tests)
    assert cut.code is whole.code is IrrepresentableCode.ABOVE_ONE
    assert stopped["supports_checked"] == 64
    # a holding scan is never cut short
    calm = System(np.eye(1), np.ones((7, 1)))
    assert irrepresentable(calm, 1, horizon=1, time_budget=0.0).verdict.value == "holds"


def test_recording_the_versions_imports_no_library():
    # python-control alone takes seconds to import: analyze of a plant without an observer
    # must not pay for it to write its version in the meta
    import subprocess
    import sys

    code = (
        "import sys; from ssecert.analyze import environment; v = environment(); "
        "print(v['control'] != 'not installed', 'control' in sys.modules, 'cvxpy' in sys.modules)"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.split() == ["True", "False", "False"]


def test_calibration_scans_a_small_level_with_and_without_the_ranking():
    rates = calibrate(7)
    assert rates.per_set > 0 and rates.per_element > 0 and rates.critical_factor >= 1.0
    assert rates.to_dict()["critical_factor"] == rates.critical_factor


def test_auto_compares_calibrated_seconds_when_both_methods_cost(monkeypatch):
    monkeypatch.setattr(sparse, "SECONDS_MODEL_ABOVE", 0.0)
    A = np.diag([1.0, 1.0, 1.0, 0.5, 0.5, 0.25])  # eigenspaces of dimension 3, 2 and 1
    C = np.random.default_rng(3).standard_normal((14, 6))
    check = sparse_observability(System(A, C), 2, time_budget=None)
    seconds = check.evidence["cost_estimates_seconds"]
    assert set(seconds) == {"eigenspace", "enumeration"} and min(seconds.values()) > 0
    first = check.evidence["methods_tried"][0]["method"]
    assert first == min(seconds, key=seconds.get)
    assert check.verdict.value == "holds"


def test_small_questions_are_ordered_by_flops_without_calibrating():
    check = sparse_observability(_generic(4, 10), 1, time_budget=None)
    assert "cost_estimates_seconds" not in check.evidence
