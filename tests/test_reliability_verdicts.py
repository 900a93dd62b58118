"""Verdicts that once were wrong, each as an instance of its class.

* a certificate certifies the very numbers it prints (the float gain, not an exact one);
* no two checks of one certificate contradict each other;
* sensor units do not change verdicts;
* a decision that hinges on digits below the data's precision is inconclusive;
* every reported breaking set and max_removable is re-verified (hidden Jordan structure);
* the answer does not depend on the horizon once it exceeds n;
* transient growth is not taken for instability.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from planted import hidden_jordan, planted

from ssecert import System, analyze, observability, sparse_observability, spec_from_dict
from ssecert.base.format import distance as readable_distance
from ssecert.design.gains import deadbeat_gain, verify_deadbeat
from ssecert.results import Verdict
from ssecert.stability import observer_messages
from ssecert.stability.lyapunov import instability_witness, lyapunov_certificate
from ssecert.stability.outcomes import SchurCode
from ssecert.stability.spectral import schur_decision
from ssecert.structure.outcomes import SparseCode

CYCLIC = 1e6 * np.roll(np.eye(3), 1, axis=0)


def _exact_power_inf_norm(A, L, C, m):
    """log2 ||(A - L C)^m||_inf with the floats taken as exact dyadic rationals, by
    repeated squaring in Python integers (independent of ssecert)."""
    A, L, C = (np.asarray(X, dtype=float) for X in (A, L, C))
    n = A.shape[0]

    def exponent(M):  # smallest e with M * 2^e integral
        return max(Fraction(float(x)).denominator.bit_length() - 1 for x in M.ravel())

    def ints(M, e):
        return [[int(Fraction(float(x)) * 2**e) for x in row] for row in M]

    eL, eC = exponent(L), exponent(C)
    shift = max(exponent(A), eL + eC)
    Ai, Li, Ci = ints(A, shift), ints(L, eL), ints(C, eC)
    Li = [[x * 2 ** (shift - eL - eC) for x in row] for row in Li]
    F = [
        [Ai[i][j] - sum(Li[i][k] * Ci[k][j] for k in range(C.shape[0])) for j in range(n)]
        for i in range(n)
    ]  # F * 2^shift

    def mul(X, Y):
        return [[sum(X[i][k] * Y[k][j] for k in range(n)) for j in range(n)] for i in range(n)]

    result, base, e, k = None, F, 0, m
    power_shift = 0
    while k:
        if k & 1:
            result = base if result is None else mul(result, base)
            power_shift += shift * (1 << e)
        k >>= 1
        if k:
            base = mul(base, base)
            e += 1
    top = max(sum(abs(x) for x in row) for row in result)
    return (math.log2(top) if top else -math.inf) - power_shift


def _design(A, C, observer, s=0):
    return spec_from_dict(
        {
            "name": "t",
            "system": {"A": np.asarray(A).tolist(), "C": np.asarray(C).tolist()},
            "attack": {"max_attacked": s},
            "observer": observer,
        }
    )


# ---------------------------------------------------------------------------
# a certificate certifies what it prints


def test_deadbeat_gain_is_judged_as_printed_not_as_its_exact_value():
    """The exact rational deadbeat gain of this plant is nilpotent, but the float L that
    the certificate prints makes A - L C unstable (spectral radius 4.67, proved exactly)."""
    cert = analyze(_design(CYCLIC, [[1, 2, 3]], {"kind": "luenberger", "gain": "deadbeat"}))
    gain, stab = cert["observer_gain"], cert["observer_stability"]
    assert gain.verdict.value == "fails" and stab.verdict.value == "fails"
    assert gain.fields["spectral_radius_lower_bound"] > 4.6
    assert gain.evidence["exact"]["verified"]  # the exact object is nilpotent, and says so
    # the printed gain fails with a verified witness; the exact gain's index is said beside it
    assert gain.witness is not None and gain.witness["verified"]
    exact_index = gain.evidence["exact"]["exact_index"]
    assert gain.summary.endswith(observer_messages.exact_deadbeat_note(exact_index))
    L = np.array(gain.fields["L"])
    # the printed L really is unstable: |tr F^3| / 3 > 1 exactly, so rho(F) > 1
    check = verify_deadbeat(CYCLIC, L, [[1, 2, 3]])
    assert not check.verified and check.radius_lower > 1


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(12))
def test_deadbeat_holds_only_with_a_certified_printed_gain(seed):
    """Random single-sensor plants, n = 11..14, scaled up: the deadbeat loop is very
    sensitive to rounding.  Whatever the verdict, a holds re-verifies independently."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(11, 15))
    A = rng.standard_normal((n, n)) * (1.0 + 3.0 * rng.random())
    C = rng.standard_normal((1, n))
    cert = analyze(_design(A, C, {"kind": "luenberger", "gain": "deadbeat"}))
    gain, stab = cert["observer_gain"], cert["observer_stability"]
    if gain.verdict.value == "holds":
        L = np.array(gain.fields["L"])
        assert gain.fields["spectral_radius"] < 1
        m = gain.evidence["details"]["upper_bound_power"]
        assert _exact_power_inf_norm(A, L, C, m) / m < 0  # rho <= ||F^m||^(1/m) < 1
        assert stab.verdict.value != "fails"
    if stab.verdict.value == "fails":
        assert gain.verdict.value != "holds"


def test_verify_deadbeat_on_an_exact_integer_gain():
    check = verify_deadbeat([[1.0, 1.0], [0.0, 1.0]], [[2.0], [1.0]], [[1.0, 0.0]])
    assert check.verified and check.exactly_nilpotent and check.index == 2
    assert check.radius_upper == 0.0


@pytest.mark.slow
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(2, 7),
    p=st.integers(1, 3),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
)
def test_observer_checks_never_contradict(seed, n, p, scale):
    """observer_gain and observer_stability of a linear observer decide the same matrix."""
    rng = np.random.default_rng(seed)
    A = scale * rng.standard_normal((n, n))
    C = rng.standard_normal((p, n))
    for gain in ("deadbeat", [[float(x) for x in row] for row in rng.standard_normal((n, p))]):
        try:
            cert = analyze(_design(A, C, {"kind": "luenberger", "gain": gain}))
        except Exception as exc:  # pragma: no cover - reported with the case
            raise AssertionError((seed, n, p, scale, gain)) from exc
        verdicts = {cert["observer_gain"].verdict.value, cert["observer_stability"].verdict.value}
        assert verdicts != {"holds", "fails"}, (seed, n, p, scale, gain)


# ---------------------------------------------------------------------------
# units


def test_sensor_units_do_not_change_verdicts():
    """Sensors in nanometres and in megametres: an observable plant stays observable."""
    A = np.diag([1.0, 2.0])
    C = np.array([[1e-8, 0.0], [0.0, 1e8], [1e-8, 1e-8]])
    check = observability(System(A, C))
    assert check.verdict.value == "holds"
    sparse = sparse_observability(System(A, C), 0)
    assert sparse.verdict.value == "holds" and sparse.fields["max_removable"] == 1


@pytest.mark.slow
@given(
    seed=st.integers(0, 2**32 - 1),
    kind=st.sampled_from(["distinct", "jordan", "mixed"]),
    powers=st.lists(st.integers(-60, 60), min_size=1, max_size=8),
    factors=st.lists(st.floats(1e-9, 1e9), min_size=1, max_size=8),
)
def test_row_scaling_is_invisible(seed, kind, powers, factors):
    """Power-of-two units change nothing at all.  Other factors round each entry on its own,
    which can break structure that rests on cancellation (C v = 0 with nonzero entries) by
    eps: the verdict may then become inconclusive (within precision), never the opposite."""
    pl = planted(np.random.default_rng(seed), kind, integer=True)
    p = pl.C.shape[0]
    d2, d = np.ones(p), np.ones(p)
    for i, k in enumerate(powers[:p]):
        d2[i] = 2.0**k
    for i, f in enumerate(factors[:p]):
        d[i] = f
    base = System(pl.A, pl.C)
    exact_units, other_units = System(pl.A, d2[:, None] * pl.C), System(pl.A, d[:, None] * pl.C)
    for s in (0, 1):
        a = sparse_observability(base, s)
        b = sparse_observability(exact_units, s)
        c = sparse_observability(other_units, s)
        assert (a.verdict, a.fields["max_removable"], a.fields["breaking_set"]) == (
            b.verdict,
            b.fields["max_removable"],
            b.fields["breaking_set"],
        ), (seed, d2)
        assert {a.verdict.value, c.verdict.value} != {"holds", "fails"}, (seed, d)
    assert observability(base).verdict == observability(exact_units).verdict
    assert {observability(base).verdict.value, observability(other_units).verdict.value} != {
        "holds",
        "fails",
    }


@pytest.mark.parametrize("factor", [1e-12, 1e-8, 0.3, 7.0, 1e8, 1e12])
def test_units_of_a_zero_pattern_plant_never_matter(factor):
    """Structure carried by zeros survives any scaling exactly."""
    A = np.diag([1.0, 2.0, 0.5])
    C = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [1.0, 1.0, 0], [0, 2.0, 3.0]])
    for i in range(C.shape[0]):
        scaled = C.copy()
        scaled[i] *= factor
        for s in (0, 1, 2):
            a = sparse_observability(System(A, C), s)
            b = sparse_observability(System(A, scaled), s)
            assert (a.verdict, a.fields["max_removable"], a.fields["breaking_set"]) == (
                b.verdict,
                b.fields["max_removable"],
                b.fields["breaking_set"],
            ), (i, s)


def test_entries_near_the_float_range_give_answers_not_crashes():
    A = np.array([[1e308, 0.0], [0.0, 5e307]])
    C = np.array([[1.0, 1.0], [1e308, 0.0]])
    sparse = sparse_observability(System(A, C), 0)
    assert observability(System(A, C)).verdict.value == "holds"
    assert sparse.verdict.value == "holds" and sparse.fields["breaking_set"] == [0]
    tiny = System(np.array([[1e300, 1e300], [0.0, 1e300]]), np.array([[1e-300, 0.0]]))
    assert observability(tiny).verdict.value == "holds"


# ---------------------------------------------------------------------------
# precision


@pytest.mark.parametrize("where", ["C", "A"])
@pytest.mark.parametrize("exponent", [-50, -52])
def test_sub_precision_perturbations_are_not_degeneracies(where, exponent):
    """Sensor 3 alone sees x3; nudging the data by 2^-50 makes another sensor see it
    too (in exact arithmetic).  A FAILS would rest on digits the data do not have."""
    A = np.eye(3)
    C = np.array([[1.0, 0, 0], [0, 1.0, 0], [1.0, 1.0, 0], [0, 0, 1.0]])
    if where == "C":
        C[2, 2] = 2.0**exponent  # sensor 2 sees x3 directly
    else:
        A[0, 2] = 2.0**exponent  # x3 feeds x1, which sensor 0 sees
    check = sparse_observability(System(A, C), 1)
    assert check.verdict.value != "fails" or check.witness.get("z_exact_integers"), check.summary
    if check.verdict.value == "inconclusive":
        assert check.code is SparseCode.EXACT_DATA_OBSERVABLE
    exact_degenerate = sparse_observability(
        System(np.eye(3), np.array([[1.0, 0, 0], [0, 1.0, 0], [1.0, 1.0, 0], [0, 0, 1.0]])), 1
    )
    assert exact_degenerate.verdict.value == "fails"
    assert exact_degenerate.witness["z_exact_integers"]


def test_unobservable_within_rounding_is_inconclusive_with_the_distance():
    # eigenvalues one ulp apart, one sensor: a double eigenvalue within rounding, in any units
    A = np.diag([1.0, 1.0 + 2.0**-52])
    C = np.array([[1.0, 1.0]])
    check = observability(System(A, C))
    assert check.verdict.value == "inconclusive"
    assert check.evidence["exact"]["state"] == "observable"
    # within the rounding level of an unobservable plant, and said so with the distance
    distance = check.evidence["distance_to_unobservability"]
    assert 0 < distance < 2.0**-52 and check.margin == distance
    assert readable_distance(distance) == "below the rounding level 2.2e-16"


def test_a_mode_seen_by_two_to_the_minus_fifty_is_a_change_of_units_away_from_clear():
    # the sensor sees the second mode by 2^-50 (exactly): in units 2^50 times smaller for
    # that state the plant is diag(1, 2) with C = [1, 1]; a change of units changes no verdict
    A = np.diag([1.0, 2.0])
    C = np.array([[1.0, 2.0**-50]])
    check = observability(System(A, C))
    plain = observability(System(A, np.array([[1.0, 1.0]])))
    assert check.verdict.value == plain.verdict.value == "holds"
    assert check.margin == pytest.approx(plain.margin, rel=1e-12)


# ---------------------------------------------------------------------------
# hidden structure, horizon


@pytest.mark.slow
@pytest.mark.parametrize("seed", [3, 159, 188, 194, 247, 496, 524, 526] + list(range(20)))
def test_hidden_jordan_structure_is_never_answered_wrongly(seed):
    """Exact integer plants whose Jordan blocks an integer similarity hides; once gave
    wrong max_removable and breaking sets (enumeration) and missed supports (eigenspace)."""
    pl = hidden_jordan(np.random.default_rng(50_000 + seed))
    if pl is None:
        pytest.skip("entries beyond 2^50 for this seed")
    system = System(pl.A, pl.C)
    for method in ("enumeration", "eigenspace", "auto"):
        for s in (0, 1, 2):
            check = sparse_observability(system, s, method=method)
            context = (seed, method, s, pl.description, check.summary)
            if check.verdict.value == "inconclusive":
                continue
            assert check.verdict.value == ("holds" if 2 * s <= pl.max_removable else "fails"), (
                context
            )
            mr = check.fields["max_removable"]
            if check.fields["max_removable_is_lower_bound"]:
                assert mr <= pl.max_removable, context
            else:
                assert mr == pl.max_removable, context
            if check.fields["breaking_set"] is not None:
                assert tuple(check.fields["breaking_set"]) == pl.breaking_set, context


def test_the_answer_does_not_depend_on_the_horizon():
    A = np.diag([2.0, 0.5, 3.0])
    C = np.array([[1.0, 0, 0], [1, 0, 0], [0, 1, 1], [0, 1, 0]])
    answers = set()
    for horizon in (3, 4, 10, 200, 2000):
        check = sparse_observability(System(A, C), 1, horizon=horizon)
        answers.add(
            (
                check.verdict.value,
                check.fields["max_removable"],
                tuple(check.fields["breaking_set"]),
            )
        )
        assert check.witness["verified"]
        # cut at the first overflow of the eigenvalue-3 mode, never below n steps
        assert 3 <= len(check.witness["attack_a"]) <= horizon
    assert answers == {("fails", 0, (2,))}


# ---------------------------------------------------------------------------
# instability needs a proof


def test_transient_growth_is_not_instability():
    F = np.array([[0.5, 1e6], [0.0, 0.5]])  # Schur, grows by 5e5 in one step
    assert lyapunov_certificate(F).verdict != "fails"
    assert instability_witness(F) is None
    assert schur_decision(F).state == "stable"


def test_nearly_nilpotent_large_matrix_is_decided_exactly():
    gain = deadbeat_gain(
        System(np.diag(np.ones(5), 1) * 1e3 + np.diag(np.ones(5), -1) * 1e-3, np.eye(6)[:1])
    )
    decision = schur_decision(
        gain.error_matrix,
        parts=(
            np.diag(np.ones(5), 1) * 1e3 + np.diag(np.ones(5), -1) * 1e-3,
            gain.L,
            np.eye(6)[:1],
        ),
    )
    # whatever floats say about its eigenvalues, the decision is exact or honestly open
    assert decision.state in ("stable", "unstable", "unknown")
    if decision.state == "stable":
        assert decision.rigorous and decision.radius_upper < 1
    if decision.state == "unstable":
        assert decision.radius_lower is None or decision.radius_lower >= 1 or not decision.rigorous


def test_eigenvalue_exactly_on_the_unit_circle_is_not_asymptotically_stable():
    d = schur_decision(np.array([[1.0, 0.5], [0.0, 0.3]]))
    assert d.state == "unstable" and d.rigorous and d.code is SchurCode.EIGENVALUE_ON_CIRCLE
    assert d.facts["eigenvalue"] == 1.0
    assert math.isfinite(d.radius_upper)


def test_analyze_agrees_with_the_checks_run_alone_in_any_units():
    """analyze shares one eigenvalue analysis between checks: it must be of the same units."""
    A = 1e6 * np.diag([1.0, 2.0, 3.0])
    C = np.array([[1e-8, 0, 0], [0, 1e8, 0], [0, 0, 3.0], [1.0, 1.0, 1.0]])
    spec = spec_from_dict(
        {"name": "u", "system": {"A": A.tolist(), "C": C.tolist()}, "attack": {"max_attacked": 1}}
    )
    cert = analyze(spec)
    alone = (observability(System(A, C)), sparse_observability(System(A, C), 1))
    for check in alone:
        together = cert[check.id]
        assert (together.verdict, together.value, together.fields.get("breaking_set")) == (
            check.verdict,
            check.value,
            check.fields.get("breaking_set"),
        )
    assert cert["observability"].verdict.value == "holds"
    np.testing.assert_allclose(
        sorted(np.real(cert["observability"].evidence["eigenvalues"])), [1e6, 2e6, 3e6]
    )


def test_a_check_that_contradicts_an_earlier_one_reports_it(monkeypatch):
    """A contradiction is reported by the check that sees it, where it is built: the later
    check of the pair is withdrawn (inconclusive, naming the other), the earlier one and every
    other check are left as built, and the certificate notes the defect."""
    import importlib
    from dataclasses import replace

    from ssecert.examples import load_example
    from ssecert.results import Withdrawn

    analyze_module = importlib.import_module("ssecert.analyze")
    spec = load_example("notes-example-3")
    cert = analyze(spec)
    assert cert["observability"].verdict is Verdict.HOLDS
    assert cert["sparse_observability"].code is not None
    assert "contradicts" not in cert["sparse_observability"].evidence

    found = analyze_module.sparse_observability

    def wrong(*args, **kwargs):  # a defect: max_removable = -1 on an observable plant
        check = found(*args, **kwargs)
        fields = {**check.fields, "max_removable": -1, "max_removable_is_lower_bound": False}
        return replace(check, fields=fields)

    monkeypatch.setattr(analyze_module, "sparse_observability", wrong)
    defect = analyze(spec)
    sparse = defect["sparse_observability"]
    assert sparse.verdict is Verdict.INCONCLUSIVE and sparse.code is Withdrawn.CONTRADICTS
    assert sparse.evidence["contradicts"] == "observability"
    assert sparse.evidence["withdrawn_verdict"] == cert["sparse_observability"].verdict.value
    assert defect["observability"].to_dict() == cert["observability"].to_dict()
    assert defect["irrepresentable"].verdict is cert["irrepresentable"].verdict
    assert len(defect.meta["notes"]) == len(cert.meta["notes"]) + 1


def test_a_stability_check_that_contradicts_the_gain_reports_it(monkeypatch):
    """observer_stability is decided after observer_gain: a stability verdict that
    contradicts the gain's (the same A - L C for a Luenberger observer) is withdrawn by the
    stability check itself; the gain check stays as built."""
    from dataclasses import replace

    from ssecert.results import Withdrawn
    from ssecert.stability import checks as checks_module

    spec = spec_from_dict(
        {
            "name": "two-states",
            "system": {"A": [[0.5, 1.0], [0.0, 0.8]], "C": [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]},
            "attack": {"max_attacked": 1},
            "observer": {"kind": "luenberger", "gain": "deadbeat"},
        }
    )
    cert = analyze(spec)
    assert cert["observer_gain"].verdict is Verdict.HOLDS
    assert cert["observer_stability"].verdict is Verdict.HOLDS

    built = checks_module.observer_stability_check

    def wrong(*args, **kwargs):  # a defect: the stable error matrix said unstable
        check, certificate = built(*args, **kwargs)
        return replace(check, verdict=Verdict.FAILS), certificate

    monkeypatch.setattr(checks_module, "observer_stability_check", wrong)
    defect = analyze(spec)
    stability = defect["observer_stability"]
    assert stability.verdict is Verdict.INCONCLUSIVE and stability.code is Withdrawn.CONTRADICTS
    assert stability.evidence["contradicts"] == "observer_gain"
    assert stability.evidence["withdrawn_verdict"] == "fails"
    assert defect["observer_gain"].to_dict() == cert["observer_gain"].to_dict()
    # the linear observer's ISS gain rests on its own certificate, not on the withdrawn one
    assert defect["iss_gain"].verdict is cert["iss_gain"].verdict
    assert defect["iss_gain"].value == cert["iss_gain"].value


@pytest.mark.slow
def test_nothing_rests_on_a_withdrawn_stability_certificate(monkeypatch):
    """A sparse observer whose stability is certified while the gain check (planted defect)
    proves A - L C unstable: observer_stability is withdrawn, and the ISS gain, which would
    rest on its certificate, has none."""
    from dataclasses import replace

    from ssecert.results import Withdrawn
    from ssecert.stability import checks as checks_module
    from ssecert.stability.outcomes import LMICause

    spec = spec_from_dict(
        {
            "name": "sso-plant",
            "system": {"A": [[0.9, 0.2], [0.0, 0.7]], "C": [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]},
            "attack": {"max_attacked": 0},
            "observer": {"kind": "sso", "step": 0.2, "threshold": 0.1},
        }
    )
    cert = analyze(spec)
    assert cert["observer_stability"].verdict is Verdict.HOLDS
    assert cert["iss_gain"].verdict is Verdict.HOLDS

    built = checks_module.observer_gain_check

    def wrong(design, **kwargs):  # a defect: a witness of an unstable A - L C
        return replace(built(design, **kwargs), verdict=Verdict.FAILS, witness={"planted": 1})

    monkeypatch.setattr(checks_module, "observer_gain_check", wrong)
    defect = analyze(spec)
    assert defect["observer_stability"].code is Withdrawn.CONTRADICTS
    assert defect["iss_gain"].verdict is Verdict.INCONCLUSIVE
    assert defect["iss_gain"].code is LMICause.NO_BASE
    assert len(defect.meta["notes"]) == len(cert.meta["notes"]) + 1
