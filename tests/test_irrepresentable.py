"""Irrepresentable constant: batched values against the definition with pinv."""

import itertools
import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ssecert import System, Tolerances, irrepresentable, irrepresentable_constant
from ssecert.examples import load_example
from ssecert.structure import irrepresentable_messages
from ssecert.structure.outcomes import IrrepresentableCode as Code


@pytest.mark.parametrize("alpha", [1e-3, -0.7, 1.0, 2.0, 350.0])
def test_lasso_example_1_gives_one_half_for_any_alpha(alpha):
    check = irrepresentable(System([[1.0]], alpha * np.ones((3, 1))), 1, horizon=1)
    assert check.verdict.value == "holds"
    assert check.value == pytest.approx(0.5, rel=1e-12)
    assert check.margin == pytest.approx(0.5, rel=1e-12)
    assert check.fields["worst_support"] == [0]


def test_packaged_lasso_example():
    spec = load_example("lasso-example-1")
    check = irrepresentable(spec.system, spec.max_attacked, horizon=spec.horizon)
    assert check.value == pytest.approx(0.5)
    assert not check.required


@pytest.mark.parametrize("seed", range(8))
def test_block_mode_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    n, p, tau, s = 3, 6, 2, 2
    system = System(rng.standard_normal((n, n)) / 2, rng.standard_normal((p, n)))
    O = system.observability_matrix(tau)
    values = {
        S: irrepresentable_constant(O, [t * p + i for i in S for t in range(tau)])
        for S in itertools.combinations(range(p), s)
    }
    worst = max(values.values())
    first = min(S for S, v in values.items() if v >= worst * (1 - 1e-12))
    check = irrepresentable(system, s, horizon=tau)
    assert check.value == pytest.approx(worst, rel=1e-9)
    assert tuple(check.fields["worst_support"]) == first
    assert check.verdict.value == ("holds" if worst < 1 else "fails")


def test_entrywise_mode_matches_brute_force():
    rng = np.random.default_rng(3)
    system = System(rng.standard_normal((2, 2)), rng.standard_normal((4, 2)))
    O = system.observability_matrix(2)
    worst = max(irrepresentable_constant(O, list(S)) for S in itertools.combinations(range(8), 2))
    check = irrepresentable(system, 2, horizon=2, mode="entrywise")
    assert check.value == pytest.approx(worst, rel=1e-9)
    assert check.fields["mode"] == "entrywise"
    assert all("@" in name for name in check.fields["worst_support_names"])


def test_rank_deficient_complement_gives_infinity_and_witness():
    # sensor 0 alone sees state 0: removing it leaves O_Sbar without full column rank
    system = System(np.eye(2), [[1.0, 0.0], [0.0, 1.0], [0.0, 2.0]])
    check = irrepresentable(system, 1, horizon=1)
    assert check.verdict.value == "fails"
    assert math.isinf(check.value)
    assert check.witness["support"] == [0]


def test_short_horizon_is_infinite():
    # n = 2 with one usable sensor needs two steps
    system = System([[1.0, 1.0], [0.0, 1.0]], [[1.0, 0.0], [1.0, 0.0]])
    check = irrepresentable(system, 1, horizon=1)
    assert math.isinf(check.value) and check.verdict.value == "fails"


def test_no_attack_is_trivially_fine():
    check = irrepresentable(System([[1.0]], [[1.0], [1.0]]), 0)
    assert check.value == 0.0 and check.verdict.value == "holds"


def test_budget():
    check = irrepresentable(System(np.eye(2), np.eye(6, 2) + 1), 3, horizon=1, max_sets=5)
    assert check.verdict.value == "inconclusive" and check.code is Code.TOO_MANY_SUPPORTS


def test_bad_mode():
    with pytest.raises(ValueError, match="mode"):
        irrepresentable(System([[1.0]], [[1.0]]), 1, mode="rows")


# ---------------------------------------------------------------------------
# units: a change of state units changes nothing; a sensor's units change rho, never a rank

ZF_PLANT = ([[-0.4, -0.9], [1.1, -0.4]], [[0.9, -0.2], [0.7, 0.5], [0.8, 0.7]])  # README
DAMPED_PLANT = (  # README, "damped"
    [[0.98, 0.17, 0.0, 0.0], [-0.17, 0.98, 0.0, 0.0], [0.0, 0.0, 0.9, 0.4], [0.0, 0.0, -0.4, 0.9]],
    [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1], [1, 0, 1, 0], [0, 1, 0, 1]],
)
PACKAGED = ["lasso-example-1", "notes-example-0", "notes-example-1", "notes-example-2",
            "notes-example-3", "ugv"]  # fmt: skip
# a claim that the plant is within the precision of its data of a rank-deficient one
DOUBTS = (Code.O_TAU_DOUBT, Code.SUPPORT_DOUBT)


def _plant(name):
    """(A, C, s, horizon) of a README plant or a packaged example."""
    if name in ("zf-plant", "damped"):
        A, C = ZF_PLANT if name == "zf-plant" else DAMPED_PLANT
        return np.asarray(A, dtype=float), np.asarray(C, dtype=float), 1, None
    spec = load_example(name)
    return spec.system.A, spec.system.C, spec.max_attacked, spec.horizon


def _state_units(A, C, j, k):
    """x' = T x with T = diag(1, .., 2^k, ..) (state j): A' = T A T^-1, C' = C T^-1, exactly."""
    t = np.ones(A.shape[0])
    t[j] = 2.0**k
    return A * t[:, None] / t[None, :], C / t[None, :]


def _sensor_units(C, i, k):
    """Sensor i's row of C times 2^k, exactly."""
    d = np.ones(C.shape[0])
    d[i] = 2.0**k
    return C * d[:, None]


def _exact_rows(A, C, tau):
    """Rows of O_tau as Fractions (row t p + i is C_i A^t)."""
    A = [[Fraction(float(x)) for x in row] for row in np.asarray(A)]
    block = [[Fraction(float(x)) for x in row] for row in np.asarray(C)]
    n, rows = len(A), []
    for _ in range(tau):
        rows.extend(block)
        block = [[sum(b[k] * A[k][j] for k in range(n)) for j in range(n)] for b in block]
    return rows


def _exact_rho(O, inside):
    """rho(S) in rational arithmetic; None where O_Sbar lacks full column rank."""
    n = len(O[0])
    bar = [row for r, row in enumerate(O) if r not in set(inside)]
    M = [[sum(b[i] * b[j] for b in bar) for j in range(n)] + [O[r][i] for r in inside]
         for i in range(n)]  # fmt: skip
    for c in range(n):  # Gauss-Jordan on [O_Sbar^T O_Sbar | O_S^T]
        pivot = next((r for r in range(c, n) if M[r][c] != 0), None)
        if pivot is None:
            return None
        M[c], M[pivot] = M[pivot], M[c]
        M[c] = [x / M[c][c] for x in M[c]]
        for r in range(n):
            if r != c and M[r][c] != 0:
                M[r] = [a - M[r][c] * b for a, b in zip(M[r], M[c])]
    X = [row[n:] for row in M]
    return max(sum(abs(sum(b[i] * X[i][j] for i in range(n))) for j in range(len(inside)))
               for b in bar)  # fmt: skip


def _exact_worst(A, C, s, horizon):
    """The worst rho over block supports of s sensors, exactly (inf when some O_Sbar is
    rank deficient)."""
    p, tau = len(C), horizon or len(A)
    O = _exact_rows(A, C, tau)
    worst = Fraction(0)
    for S in itertools.combinations(range(p), s):
        value = _exact_rho(O, [t * p + i for i in S for t in range(tau)])
        if value is None:
            return math.inf
        worst = max(worst, value)
    return worst


def _same(a, b, rel):
    return a == b or (math.isfinite(a) and math.isfinite(b) and abs(a - b) <= rel * abs(b))


@pytest.mark.parametrize("name", ["zf-plant", "damped", *PACKAGED])
def test_a_change_of_state_units_changes_neither_verdict_nor_value(name):
    A, C, s, horizon = _plant(name)
    base = irrepresentable(System(A, C), s, horizon=horizon)
    for j in range(A.shape[0]):
        for k in (30, 50, -60, 200):
            check = irrepresentable(System(*_state_units(A, C, j, k)), s, horizon=horizon)
            assert check.verdict == base.verdict, (j, k, check.summary)
            assert _same(check.value, base.value, 1e-9), (j, k, check.value, base.value)
            assert check.code not in DOUBTS


@pytest.mark.slow
@pytest.mark.parametrize("name", ["zf-plant", "damped", *PACKAGED])
def test_a_sensors_units_change_rho_but_never_make_a_false_rank_claim(name):
    """rho in a sensor's new units against rational arithmetic: the verdict is the exact
    one (or inconclusive, saying why), the value within its stated error estimate."""
    A, C, s, horizon = _plant(name)
    for i in range(C.shape[0]):
        for k in (30, 50, -60, 200):
            C2 = _sensor_units(C, i, k)
            check = irrepresentable(System(A, C2), s, horizon=horizon)
            exact = _exact_worst(A, C2, s, horizon)
            assert check.code not in DOUBTS, (i, k, check.summary)
            if check.verdict.value == "inconclusive":
                assert abs(exact - 1) <= 1e-9 or check.code is Code.NOT_TOLD_FROM_ONE
                continue
            assert check.verdict.value == ("holds" if exact < 1 else "fails"), (i, k)
            if math.isfinite(exact):
                error = abs(check.value - float(exact)) / float(exact)
                assert error <= max(check.evidence["value_relative_error_estimate"], 4e-16)


def test_a_constant_that_grows_with_a_sensors_units_is_accurate():
    # notes-example-2 with y1 in units 2^-29: rho = 2^29 exactly on the support y3; whitening
    # by the whole of O_tau printed 536870921.19 (relative error 1.7e-8)
    A, C, s, horizon = _plant("notes-example-2")
    C2 = _sensor_units(C, 0, -29)
    assert _exact_worst(A, C2, s, horizon) == 2**29
    check = irrepresentable(System(A, C2), s, horizon=horizon)
    assert check.verdict.value == "fails" and check.fields["worst_support"] == [2]
    error = abs(check.value - 2.0**29) / 2.0**29
    assert error < 1e-12
    assert error <= check.evidence["value_relative_error_estimate"]
    # lasso-example-1 with y1 in units 2^30: rho = 2^29 on y1
    check = irrepresentable(System([[1.0]], _sensor_units(np.ones((3, 1)), 0, 30)), 1, horizon=1)
    assert check.value == pytest.approx(2.0**29, rel=1e-15) and check.fields["worst_support"] == [0]


def test_a_constant_that_rests_on_a_cancellation_is_inconclusive_with_its_error():
    # y1 in units 2^-60 alone tells state 1 from state 3 once y3 is attacked: rho = 2^60
    # exactly, but an error of one ulp in the other rows (whose difference cancels) moves it
    # by 100%; the condition number of O_Sbar in the sensors' units says so
    A, C, s, horizon = _plant("notes-example-2")
    check = irrepresentable(System(A, _sensor_units(C, 0, -60)), s, horizon=horizon)
    assert check.verdict.value == "inconclusive" and check.code is Code.NOT_TOLD_FROM_ONE
    assert check.evidence["value_relative_error_estimate"] > 1


def test_a_claim_of_rank_deficiency_within_precision_states_its_singular_value():
    # exactly, O_tau has rank 2; in floating point it looks like rank 1
    check = irrepresentable(System(np.diag([1.0, 1.0 + 2.0**-52]), np.ones((3, 2))), 1, horizon=2)
    assert check.verdict.value == "inconclusive"
    assert check.code is Code.O_TAU_DOUBT
    smallest = check.evidence["exact_rank_check"]["scaled_smallest_singular_value"]
    assert smallest < 2.0**-52
    # the summary states it: the words of the doubt with these numbers (3 x 2 rows of O_tau)
    tol = Tolerances()
    rtol = tol.rtol(6, 2)
    doubt = {"n": 2, "smallest": smallest, "rtol": rtol, "band": tol.borderline_factor * rtol}
    facts = {"tau": 2, "doubt": irrepresentable_messages.doubt(doubt)}
    assert check.summary == irrepresentable_messages.summary(Code.O_TAU_DOUBT, facts)


@pytest.mark.parametrize("seed", range(4))
def test_rho_from_the_rows_matches_the_definition(seed):
    """support_rho (QR of O_Sbar, rows sorted) against pinv on well-scaled rows, and against
    rational arithmetic on rows 2^40 apart."""
    from ssecert.structure._irrepresentable_scan import StackedRows, support_rho

    rng = np.random.default_rng(seed)
    O = rng.integers(-3, 4, size=(8, 3)).astype(float)
    supports = np.array(list(itertools.combinations(range(8), 2)))
    rho, codes, _, _ = support_rho(StackedRows.of(O), supports, Tolerances())
    direct = [irrepresentable_constant(O, S) for S in supports]
    assert np.allclose(rho, direct, rtol=1e-12)
    assert np.array_equal(np.isinf(rho), codes == 0)
    O[0] *= 2.0**40
    rho, _, _, _ = support_rho(StackedRows.of(O), supports, Tolerances())
    exact = _exact_rows(np.eye(3), O, 1)
    for value, S in zip(rho, supports):
        truth = _exact_rho(exact, list(S))
        assert (
            (value == math.inf)
            if truth is None
            else value == pytest.approx(float(truth), rel=1e-12)
        )


@st.composite
def _integer_plants(draw):
    n = draw(st.integers(2, 4))
    p = draw(st.integers(3, 6))
    entries = st.integers(-3, 3)
    A = draw(st.lists(st.lists(entries, min_size=n, max_size=n), min_size=n, max_size=n))
    C = draw(st.lists(st.lists(entries, min_size=n, max_size=n), min_size=p, max_size=p))
    j = draw(st.integers(0, n - 1))
    return np.array(A, dtype=float), np.array(C, dtype=float), j


@pytest.mark.slow
@given(_integer_plants())
@settings(deadline=None)
def test_state_units_property(plant):
    """Random small integer plants, s = 1: the verdict (and rho, to 1e-9) is the same after a
    power-of-two change of one state's units, and no rescaling (of a state or of a sensor)
    claims a rank deficiency within precision: these plants' ranks are far from any."""
    A, C, j = plant
    exact = _exact_worst(A, C, 1, None)
    base = irrepresentable(System(A, C), 1)
    assert base.code not in DOUBTS
    if base.verdict.value != "inconclusive":
        assert base.verdict.value == ("holds" if exact < 1 else "fails")
    for k in (30, -30, 50, 200, -200):
        check = irrepresentable(System(*_state_units(A, C, j, k)), 1)
        assert check.verdict == base.verdict, (k, check.summary, base.summary)
        assert _same(check.value, base.value, 1e-9), (k, check.value, base.value)
        assert check.code not in DOUBTS
        sensor = irrepresentable(System(A, _sensor_units(C, j % C.shape[0], k)), 1)
        assert sensor.code not in DOUBTS


def test_an_exact_constant_of_one_fails_by_rational_arithmetic():
    # A = I, C = [e1; e2; e1 + e2], tau = 2: rho on sensor y1 is exactly 1 (holds needs < 1);
    # the floats give 1 + 4.4e-16, within the tolerance band, and the check said inconclusive
    check = irrepresentable(System(np.eye(2), [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]), 1)
    assert check.verdict.value == "fails" and check.code is Code.EXACTLY_AT_LEAST_ONE
    assert check.evidence["worst_support_exact_value"] == "1"
    assert check.witness["exact_value"] == "1"


def test_supports_too_ill_conditioned_to_rank_make_the_worst_a_lower_bound():
    # C's second column holds 2^-57 in two rows: for supports {y1, y3} and {y3, y5} O_Sbar
    # has a condition number near 2^57 and the QR's rho is off by 20x (exactly 5.0e17 and
    # 1.3e18, computed 2.2e16); the worst computed precisely, 4.3e17 on {y1, y5}, is then a
    # lower bound, not the constant
    from ssecert.structure.irrepresentable import _exact_rho

    e = 2.0**-57
    C = [[-1, 2, -1], [-2, e, 0], [0, e, 2], [-2, 0, 0], [-1, -1, -2]]
    plant = System(np.eye(3), C)
    check = irrepresentable(plant, 2, horizon=1)
    assert check.verdict.value == "fails" and check.fields["value_is_lower_bound"]
    assert check.fields["worst_support"] == [0, 4]
    assert check.evidence["imprecise_supports"] == 2
    named = check.evidence["imprecise_support"]["support"]
    assert _exact_rho(plant, 1, np.array(named)) > check.value


def test_an_imprecise_support_beside_an_imprecise_worst_is_still_seen():
    # the worst support itself may have the largest upper bound: the next one, above the
    # worst, must still make the worst a lower bound; ranges merged keep the same two
    from ssecert.structure._irrepresentable_scan import SupportScan
    from ssecert.structure.irrepresentable import _imprecise, _Verdicts

    def scan_of(parts):
        scan = SupportScan()
        for rho, error, support in parts:
            part = SupportScan()
            part.add_finite(np.array([rho]), np.array([support]))
            part.add_imprecise(np.array([rho]), np.array([error]), np.array([support]))
            scan.merge(part)
        return scan

    parts = [(40.0, 0.3, (2,)), (39.96, 1.3e-3, (1,)), (10.0, 1e-3, (0,))]
    scan = scan_of(parts)
    assert scan.worst_support == (2,) and scan.imprecise == 3
    assert [e[1] for e in scan.imprecise_top] == [(2,), (1,)]
    plant = System(np.eye(1), [[1.0], [2.0], [3.0]])
    out = _Verdicts(plant, plant, "block", 1, 1, {}, {})
    facts = _imprecise(out, scan)
    assert facts is not None and facts["imprecise_label"] == "y2"
    assert out.evidence["imprecise_support"]["support"] == [1]
    # below the worst, however imprecise, none is named
    assert _imprecise(out, scan_of([(40.0, 0.3, (2,)), (10.0, 1e-3, (0,))])) is None


def test_sensors_in_far_units_are_not_taken_for_imprecise_supports():
    # rows 1e12 and 4e13 beside rows near 1: the QR's rho is exact to 2e-16 on every support,
    # and its error estimate must say so (it read 0.3 with the columns scaled for other rows)
    C = [[1e12, 0], [40.004e12, 0], [0, 1], [1, 0.01], [0.2, 0.02]]
    check = irrepresentable(System(np.eye(2), C), 1, horizon=1)
    assert check.verdict.value == "fails" and "value_is_lower_bound" not in check.fields
    assert check.evidence.get("imprecise_supports", 0) == 0
