"""s-sparse observability: both methods against each other and against planted truth."""

import itertools
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from planted import exact_rank, planted

from ssecert import System, analyze, scan_removals, sparse_observability
from ssecert.examples import load_example
from ssecert.structure import sparse_messages
from ssecert.structure.observability import unobservable_residual
from ssecert.structure.outcomes import ProblemCode, RecheckCode, RecheckProblem, SparseCode

KINDS = ("distinct", "jordan", "identity", "mixed")


@pytest.mark.parametrize(
    "name, max_removable, breaking_set, verdict",
    [
        ("notes-example-0", 0, [0], "fails"),
        ("notes-example-1", 0, [2], "fails"),
        ("notes-example-2", 1, [0, 2], "fails"),
        ("notes-example-3", 2, [0, 1, 2], "holds"),
        ("ugv", 0, [0], "fails"),
        ("lasso-example-1", 2, [0, 1, 2], "holds"),
    ],
)
@pytest.mark.parametrize("method", ["auto", "enumeration", "eigenspace"])
def test_documented_examples(name, max_removable, breaking_set, verdict, method):
    spec = load_example(name)
    check = sparse_observability(spec.system, spec.max_attacked, method=method)
    assert check.verdict.value == verdict
    assert check.fields["max_removable"] == max_removable
    assert check.fields["breaking_set"] == breaking_set
    assert check.fields["max_correctable"] == max_removable // 2
    assert check.fields["max_removable_is_lower_bound"] is False


def test_random_thesis_plant_tolerates_three_attacks():
    spec = load_example("random-n15-p30")
    check = sparse_observability(spec.system, spec.max_attacked)
    assert check.verdict.value == "holds"
    assert check.fields["max_removable"] == 29
    assert check.margin is not None and check.margin > 0


def _truth_check(pl, seed, method):
    system = System(pl.A, pl.C)
    for s in (0, 1, 2):
        check = sparse_observability(system, s, method=method)
        assert check.verdict.value != "inconclusive", (seed, pl.description, check.summary)
        assert check.fields["max_removable"] == pl.max_removable, (seed, pl.description)
        assert tuple(check.fields["breaking_set"]) == pl.breaking_set, (seed, pl.description)
        expected = "holds" if 2 * s <= pl.max_removable else "fails"
        assert check.verdict.value == expected
        if expected == "fails":
            w = check.witness
            assert w["verified"] and w["residual"] < 1e-8
            assert len(w["sensors_a"]) <= s and len(w["sensors_b"]) <= s
            assert sorted(w["sensors_a"] + w["sensors_b"]) == list(pl.breaking_set)


def _consistent(check, pl, s, context):
    """Never wrong: a decided verdict matches the truth; a lower bound never exceeds it; a
    breaking set is reported only when it is the planted one; an inconclusive answer says why."""
    value = check.verdict.value
    if value == "inconclusive":
        return False
    assert value == ("holds" if 2 * s <= pl.max_removable else "fails"), context
    mr = check.fields["max_removable"]
    if check.fields.get("max_removable_is_upper_bound"):
        # a certain breaking set past smaller sets within precision of breaking
        assert check.fields["max_removable_at_least"] <= pl.max_removable <= mr, context
        assert check.witness["verified"], context
    elif check.fields["max_removable_is_lower_bound"]:
        assert mr <= pl.max_removable and check.fields["breaking_set"] is None, context
    else:
        assert mr == pl.max_removable, context
        assert tuple(check.fields["breaking_set"]) == pl.breaking_set, context
    return True


@pytest.mark.parametrize("seed", range(300))
def test_methods_agree_with_planted_truth(seed, sparse_problems):
    """Hundreds of plants with a planted smallest breaking set of known size.

    Integer similarities keep the data exact, and both methods must then decide and
    find the planted answer.  An orthogonal similarity (every third seed) rounds the
    planted structure away by about eps: the exact data are then within precision of
    the planted plant, and a method may say so (inconclusive, or a lower bound) but is
    never wrong.
    """
    rng = np.random.default_rng(seed)
    integer = seed % 3 != 0
    pl = planted(rng, KINDS[seed % 4], integer=integer)
    for method in ("enumeration", "eigenspace"):
        system = System(pl.A, pl.C)
        check = sparse_observability(system, 1, method=method)
        context = (seed, method, pl.description, check.summary)
        decided = _consistent(check, pl, 1, context)
        if integer:
            assert decided and not check.fields["max_removable_is_lower_bound"], context
            assert not check.fields.get("max_removable_is_upper_bound"), context
        elif not decided:
            problems = {p.code for tried in sparse_problems[-1] for p in tried}
            assert check.code is SparseCode.UNDECIDED, context
            assert problems & WITHIN_PRECISION_OR_BORDERLINE, (context, problems)


# the problems of a plant within the precision of the rank decisions, or borderline there
WITHIN_PRECISION_OR_BORDERLINE = {
    ProblemCode.WITHIN_PRECISION,
    ProblemCode.NOT_EXACT,
    ProblemCode.BORDERLINE_SUBSPACE,
    ProblemCode.BORDERLINE_SETS,
}


def _never_wrong(pl, seed, method):
    """A method may be inconclusive (borderline in floating point) but never wrong."""
    system = System(pl.A, pl.C)
    decided = True
    for s in (0, 1, 2):
        check = sparse_observability(system, s, method=method)
        decided &= _consistent(check, pl, s, (seed, pl.description, method, s, check.summary))
    return decided


@pytest.mark.slow
@given(seed=st.integers(0, 2**32 - 1), kind=st.sampled_from(KINDS), integer=st.booleans())
def test_methods_agree_property(seed, kind, integer):
    """Neither method is ever wrong; on exact (integer) data auto always decides.

    With a floating-point similarity (integer=False) A = Q M Q^T differs from
    the planted M by about eps: the exact data are then not the planted plant,
    and an answer that hinges on that difference is inconclusive, honestly.
    """
    pl = planted(np.random.default_rng(seed), kind, integer=integer)
    decided = [_never_wrong(pl, seed, m) for m in ("enumeration", "eigenspace", "auto")]
    if integer:
        assert decided[2], (seed, pl.description)
        _truth_check(pl, seed, "auto")


def test_planted_breaking_sizes_are_varied():
    """The generator plants small breaking sets, not the generic p - 1."""
    sizes = {
        planted(np.random.default_rng(seed), KINDS[seed % 4]).max_removable for seed in range(200)
    }
    assert {-1, 0, 1, 2} <= sizes


def test_witness_reproduces_identical_outputs():
    spec = load_example("notes-example-2")
    check = sparse_observability(spec.system, 1, horizon=4)
    w = check.witness
    A, C = spec.system.A, spec.system.C
    x0 = np.array([0.3, -1.2, 2.0])
    z = np.array(w["z"])
    xa, xb = x0.copy(), x0 + z
    for k in range(4):
        ya = C @ xa + np.array(w["attack_a"][k])
        yb = C @ xb + np.array(w["attack_b"][k])
        np.testing.assert_allclose(ya, yb, atol=1e-12)
        xa, xb = A @ xa, A @ xb
    assert np.linalg.norm(z) == pytest.approx(1.0)
    assert w["sensors_a"] == [0] and w["sensors_b"] == [2]
    attacked_a = np.flatnonzero(np.abs(np.array(w["attack_a"])).sum(axis=0))
    assert set(attacked_a) <= {0}


def test_undetectable_attack_when_breaking_set_fits_in_s():
    spec = load_example("ugv")
    w = sparse_observability(spec.system, 1).witness
    assert w["sensors_b"] == [] and w["sensors_a"] == [0]
    assert "undetectable" in w["meaning"]
    assert np.allclose(w["attack_b"], 0.0)


def test_unobservable_plant_is_an_answer():
    system = System(np.eye(3), [[1.0, 0, 0], [0, 1.0, 0]])
    for method in ("enumeration", "eigenspace"):
        check = sparse_observability(system, 0, method=method)
        assert check.verdict.value == "fails"
        assert check.fields["max_removable"] == -1
        assert check.fields["max_correctable"] == -1
        assert check.fields["breaking_set"] == []
        z = np.array(check.witness["z"])
        assert unobservable_residual(system.A, system.C, z) < 1e-12


def test_more_attacked_than_sensors_fails_with_witness():
    system = System(np.eye(2), np.eye(2))
    check = sparse_observability(system, 5)
    assert check.verdict.value == "fails"
    assert check.witness["verified"]


def test_generic_plants_lose_nothing_by_removing_sensors():
    rng = np.random.default_rng(7)
    for n, p in [(3, 5), (6, 9), (15, 30)]:
        system = System(rng.standard_normal((n, n)), rng.standard_normal((p, n)))
        for method in ("enumeration", "eigenspace"):
            check = sparse_observability(system, 2, method=method)
            assert check.fields["max_removable"] == p - 1
            assert check.verdict.value == "holds"


def test_budget_gives_lower_bound_or_inconclusive():
    # A = I, n = 3, p = 8 generic integer rows: max_removable = 8 - 3 = 5
    rng = np.random.default_rng(3)
    C = rng.integers(-4, 5, size=(8, 3)).astype(float)
    system = System(np.eye(3), C)
    exact = sparse_observability(system, 1, method="enumeration")
    assert exact.fields["max_removable_is_lower_bound"] is False
    truth = exact.fields["max_removable"]
    # budget enough for sets of up to 2 sensors (1 + 8 + 28 = 37) but not all
    limited = sparse_observability(system, 1, method="enumeration", max_sets=40)
    assert limited.verdict.value == "holds"
    assert limited.fields["max_removable_is_lower_bound"] is True
    assert 2 <= limited.fields["max_removable"] <= truth
    starved = sparse_observability(system, 2, method="enumeration", max_sets=10)
    assert starved.verdict.value == "inconclusive" and starved.code is SparseCode.UNDECIDED
    # the summary names the sets still needed (and --max-sets: tests/test_problem_messages.py)
    needed = starved.fields["sets_needed"]
    assert needed == sum(math.comb(8, k) for k in (2, 3, 4))  # the levels up to 2s not run
    reasons = [r for tried in starved.evidence["methods_tried"] for r in tried["problems"]]
    assert starved.summary == sparse_messages.undecided_summary(reasons, needed)


@pytest.mark.slow
def test_scan_removals_matches_exact_rank_reference():
    """Every set of removed sensors decided as an exact rational rank would."""
    rng = np.random.default_rng(11)
    for trial in range(12):
        pl = planted(rng, KINDS[trial % 4], integer=True)
        A = np.round(pl.A).astype(int)
        C = np.round(pl.C).astype(int)
        n, p = A.shape[0], C.shape[0]
        blocks = [C]
        for _ in range(n - 1):
            blocks.append(blocks[-1] @ A)
        for size in range(p + 1):
            scan = scan_removals(System(A, C), size, prune=False)
            expected = []
            for removed in itertools.combinations(range(p), size):
                keep = [i for i in range(p) if i not in removed]
                rows = [list(map(int, b[i])) for b in blocks for i in keep]
                if exact_rank(rows) < n:
                    expected.append(removed)
            assert list(scan.breaking_sets) == expected, (trial, size)
            assert scan.borderline == 0


def test_progress_is_reported_during_enumeration():
    calls = []
    system = System(np.eye(3), np.random.default_rng(1).integers(-3, 4, size=(7, 3)))
    sparse_observability(
        system, 1, method="enumeration", progress=lambda d, t: calls.append((d, t))
    )
    assert calls and all(0 < d <= t for d, t in calls)


@pytest.mark.slow
def test_eigenspace_answers_large_generic_plant():
    rng = np.random.default_rng(0)
    system = System(rng.standard_normal((50, 50)), rng.standard_normal((1000, 50)))
    check = sparse_observability(system, 3, method="eigenspace")
    assert check.fields["max_removable"] == 999
    assert check.verdict.value == "holds"


def test_analyze_reports_the_documented_examples():
    cert = analyze(load_example("ugv"))
    assert cert.verdict.value == "fails" and cert.exit_code == 1
    assert cert["sparse_observability"].fields["breaking_set"] == [0]
    assert not cert["irrepresentable"].required


@pytest.mark.parametrize("bad", [-1, 1.5, "2", True])
def test_bad_max_attacked(bad):
    with pytest.raises((TypeError, ValueError), match="max_attacked"):
        sparse_observability(System([[1.0]], [[1.0]]), bad)


def test_bad_method_and_budget():
    system = System([[1.0]], [[1.0]])
    with pytest.raises(ValueError, match="method"):
        sparse_observability(system, 0, method="pbh")
    with pytest.raises(ValueError, match="max_sets"):
        sparse_observability(system, 0, max_sets=0)


def test_time_budget_settles_the_verdict_first_and_bounds_the_refinement(sparse_problems):
    # a static plant with 12 generic sensors: max_removable = 12 - 3 = 9 exactly
    rng = np.random.default_rng(0)
    system = System(np.eye(3), rng.standard_normal((12, 3)))
    exact = sparse_observability(system, 1, method="enumeration", time_budget=None)
    assert exact.fields["max_removable"] == 9 and not exact.fields["max_removable_is_lower_bound"]
    quick = sparse_observability(system, 1, method="enumeration", time_budget=0.0)
    assert quick.verdict.value == "holds"  # every set of up to 2s = 2 sensors was checked
    assert quick.fields["max_removable_is_lower_bound"]
    assert quick.fields["max_removable"] == 2
    assert quick.code is SparseCode.LOWER_BOUND
    # the refinement stopped at the time budget of 0 s (its words point to --exact:
    # tests/test_problem_messages.py)
    [[problems]] = sparse_problems[1:]
    stopped = [p for p in problems if p.code in TIME_BUDGET]
    assert stopped and all(p.facts["budget"] == 0.0 for p in stopped)
    assert quick.evidence["stopped_by_time_budget"]["time_budget_seconds"] == 0.0


TIME_BUDGET = {ProblemCode.TIME_BEFORE_LEVEL, ProblemCode.TIME_WITHIN_LEVEL}


def test_time_budget_stops_auto_from_trying_another_method(monkeypatch):
    # auto orders the methods by cost; once the enumeration settles the verdict within the
    # time budget, the other method (which would only refine max_removable) is not run
    sparse = __import__("ssecert.structure.sparse", fromlist=["_estimates"])
    monkeypatch.setattr(
        sparse, "_estimates", lambda *args: {"enumeration": 1.0, "eigenspace": 1e12}
    )
    rng = np.random.default_rng(0)
    system = System(np.eye(3), rng.standard_normal((12, 3)))
    quick = sparse_observability(system, 1, time_budget=0.0)
    assert [t["method"] for t in quick.evidence["methods_tried"]] == ["enumeration"]
    assert quick.fields["max_removable_is_lower_bound"]


def test_time_budget_never_cuts_a_failing_verdict_short():
    # sensors 0 and 1 see the same row: removing 2 sensors breaks the plant, s = 1 fails
    C = np.vstack([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 1.0], [1.0, 1.0]])
    check = sparse_observability(System(np.eye(2), C), 2, time_budget=0.0)
    assert check.verdict.value == "fails" and not check.fields["max_removable_is_lower_bound"]


def test_time_budget_is_validated():
    with pytest.raises(ValueError, match="time_budget must be >= 0"):
        sparse_observability(System(np.eye(2), np.eye(2)), 0, time_budget=-1.0)


class _Screen:
    """A screened batch of a level for ``_keep_closest``: ranks from ``offset``, subsets by
    row, lower bounds of the proxies (exact where ``exact``) and the proxies on demand."""

    def __init__(self, offset: int, subsets: np.ndarray, proxy: np.ndarray, rng) -> None:
        self.offset, self._subsets, self._proxy = offset, subsets, proxy
        self.exact = rng.random(proxy.size) < 0.3
        self.low = np.where(self.exact, proxy, proxy - rng.integers(0, 3, proxy.size))
        self.asked = np.zeros(proxy.size, dtype=bool)

    def subsets(self, rows: np.ndarray) -> np.ndarray:
        return self._subsets[rows]

    def below(self, threshold: float, most: int | None = None) -> tuple[np.ndarray, bool]:
        from ssecert.structure._combinatorics import ScreenedBatch

        return ScreenedBatch.below(self, threshold, most)  # type: ignore[arg-type]

    def proxies(self, rows: np.ndarray, shift: float) -> np.ndarray:
        self.asked[rows[~self.exact[rows]]] = True
        self.low[rows] = self._proxy[rows]
        self.exact[rows] = True
        return self.low[rows]


@pytest.mark.parametrize("seed", range(20))
def test_the_closest_sets_kept_block_by_block_are_the_smallest_overall(seed):
    """The proxies are asked only where the lower bound allows a set in, and the sets kept are
    the smallest (proxy, position) whatever the bounds."""
    from ssecert.structure._level_scan import _CRITICAL, _keep_closest

    rng = np.random.default_rng(seed)
    q, k = 9, 3
    rest = np.arange(q)
    candidates: list = []
    everything = []
    sizes = rng.integers(1, 30, rng.integers(1, 6))
    total = int(sizes.sum())
    # the ranges of a level arrive from the last ranks down, blocks ascending within each
    offset = total
    for size in sizes.tolist():
        offset -= size
        # few distinct values, so that ties between and within blocks are common
        proxy = rng.integers(0, 4, size).astype(float)
        subsets = np.array([np.sort(rng.choice(q, k, replace=False)) for _ in range(size)])
        threshold = candidates[-1][0] if len(candidates) >= _CRITICAL else np.inf
        screen = _Screen(offset, subsets, proxy, rng)
        low = screen.low.copy()
        _keep_closest(candidates, screen, 0.0, rest, total)
        assert not np.any(screen.asked & (low > threshold))
        for j in range(size):
            kept = tuple(int(i) for i in rest if i not in set(subsets[j].tolist()))
            everything.append((float(proxy[j]), total - 1 - offset - j, kept))
    assert candidates == sorted(everything)[:_CRITICAL]


def test_a_zero_time_budget_leaves_the_eigenspace_method_its_verdict():
    """--time-budget 0 means no refinement past the verdict; the eigenspace method gives the
    verdict and the exact value at once, so it is not cut off (it was, at once, and the
    enumeration answered 'at least 6' for an exact 24)."""
    rng = np.random.default_rng(3)
    n, p = 12, 30
    A = np.diag(np.r_[[0.5] * 4, np.linspace(0.1, 0.9, n - 4)])
    C = rng.standard_normal((p, n)) * (rng.random((p, n)) < 0.85)
    plain = sparse_observability(System(A, C), 3)
    zero = sparse_observability(System(A, C), 3, time_budget=0.0)
    assert plain.fields["method"] == zero.fields["method"] == "eigenspace"
    assert plain.fields["max_removable"] == zero.fields["max_removable"] == 24
    assert not zero.fields["max_removable_is_lower_bound"]


def test_the_check_says_why_by_a_code():
    """The check's code gives its verdict: a confirmed breaking set, the exact max_removable,
    a lower bound (the verdict only), a budget that decides nothing."""
    rng = np.random.default_rng(0)
    plant = System(np.eye(6), rng.standard_normal((14, 6)))
    cases = [
        (sparse_observability(load_example("notes-example-2").system, 1), SparseCode.BREAKING_SET),
        (sparse_observability(load_example("notes-example-3").system, 1),
         SparseCode.EXACT_MAX_REMOVABLE),
        (sparse_observability(plant, 2, method="enumeration", time_budget=0),
         SparseCode.LOWER_BOUND),
        (sparse_observability(plant, 2, method="enumeration", max_sets=50), SparseCode.UNDECIDED),
    ]  # fmt: skip
    for check, code in cases:
        assert check.code is code and check.verdict is code.verdict, check.summary
    assert cases[2][0].fields["max_removable_is_lower_bound"]
    assert cases[0][0].fields["breaking_set"] is not None


def test_every_recheck_problem_has_words():
    facts = {"kept": (0, 2), "pbh": False, "staircase": True, "eigenvalue": "1", "removed": 2}
    for code in RecheckCode:
        for deficient in (True, False):
            words = sparse_messages.recheck_text(
                RecheckProblem(code, {**facts, "deficient": deficient})
            )
            assert words, code
    raw = RecheckProblem(RecheckCode.RAW_EIGENVALUE, {**facts, "deficient": False})
    assert sparse_messages.recheck_text(raw).endswith("is borderline")
    for code in SparseCode:
        assert code.verdict.value in ("holds", "fails", "inconclusive")
