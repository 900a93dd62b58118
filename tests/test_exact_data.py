"""Every exact claim is made on the spec's exact data, and every size a spec names is budgeted.

A float product such as A - L C rounds: with L C below half an ulp of A's entries the product is
A itself, and an "exact" decision on it would be a decision about another observer.  These tests
build designs whose answer is known in exact arithmetic and check that no verdict contradicts it.
"""

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ssecert.analyze import analyze
from ssecert.cli import main
from ssecert.observers import build_observer
from ssecert.spec import spec_from_dict
from ssecert.stability import observer_messages, spectral_messages
from ssecert.stability.checks import observer_gain_check, observer_stability_check
from ssecert.stability.outcomes import LMICause, LyapunovCode, SchurCode, WitnessKind


def _spec(A, C, observer, s=0, **extra):
    data = {
        "name": "exact",
        "system": {"A": A, "C": C},
        "attack": {"max_attacked": s},
        "observer": observer,
        **extra,
    }
    return spec_from_dict(data)


def _verdicts(cert):
    return {c.id: c.verdict.value for c in cert.checks}


# ---------------------------------------------------------------------------
# L C below half an ulp of A


@pytest.mark.slow
def test_an_elastic_net_gain_below_rounding_gets_no_fails():
    # F = 1 - 1e-17 exactly: the float product A - L C rounds to 1.0
    cert = analyze(
        _spec(
            [[1.0]],
            [[1.0], [1.0]],
            {
                "kind": "elastic_net",
                "gain": [[1e-17, 0.0]],
                "step": 0.5,
                "threshold": 0.1,
                "shrink": 0.5,
            },
        )
    )
    verdicts = _verdicts(cert)
    assert "fails" not in verdicts.values(), verdicts
    gain = cert["observer_gain"]
    # held by the exact powers of F = 1 - 1e-17, shown as such (not as the float 1)
    assert gain.verdict.value == "holds" and gain.code is SchurCode.POWERS_STABLE
    assert gain.value_text == "1 - 1e-17" and gain.margin == pytest.approx(1e-17, rel=1e-3)
    assert spectral_messages.below_one(gain.value, gain.margin) == "1 - 1e-17 < 1"
    stability = cert["observer_stability"]
    assert stability.verdict.value == "inconclusive"
    assert stability.code is LMICause.VERTEX_WITHIN_ROUNDING


def test_a_luenberger_gain_below_rounding_is_certified_by_its_exact_powers():
    cert = analyze(_spec([[1.0]], [[1.0], [1.0]], {"kind": "luenberger", "gain": [[1e-17, 0.0]]}))
    verdicts = _verdicts(cert)
    assert "fails" not in verdicts.values(), verdicts
    stability = cert["observer_stability"]
    assert stability.verdict.value == "holds" and stability.method == "exact powers of A - L C"
    assert 0 < stability.margin < 1e-16


def test_a_product_that_rounds_to_a_above_one_entry_is_decided_exactly():
    # A = 1 + 2^-52 and L C = 2^-52 + 2^-60: F = 1 - 2^-60 exactly, fl(A - L C) = 1
    A = 1.0 + 2.0**-52
    lc = 2.0**-52 + 2.0**-60
    cert = analyze(_spec([[A]], [[1.0], [1.0]], {"kind": "luenberger", "gain": [[lc, 0.0]]}))
    assert cert["observer_gain"].verdict.value == "holds"
    assert cert["observer_stability"].verdict.value == "holds"
    assert "fails" not in _verdicts(cert).values()


def _exactly_schur(F: list[list[Fraction]]) -> bool:
    """Every eigenvalue of the exact 1 x 1 or 2 x 2 matrix strictly inside the unit circle
    (Jury's test on the characteristic polynomial z^2 - t z + d)."""
    if len(F) == 1:
        return abs(F[0][0]) < 1
    t = F[0][0] + F[1][1]
    d = F[0][0] * F[1][1] - F[0][1] * F[1][0]
    return abs(d) < 1 and abs(t) < 1 + d


def _exact_F(A, L, C) -> list[list[Fraction]]:
    n, p = len(A), len(C)
    return [
        [
            Fraction(A[i][j]) - sum((Fraction(L[i][k]) * Fraction(C[k][j]) for k in range(p)), 0)
            for j in range(n)
        ]
        for i in range(n)
    ]


@st.composite
def _rounding_level_designs(draw):
    """A plant whose A has entries near 1 and a gain whose L C is at or below its rounding."""
    n = draw(st.integers(1, 2))
    p = draw(st.integers(1, 2))
    ulp = 2.0**-52
    diag = draw(st.sampled_from([1.0, 1.0 + ulp, 1.0 - ulp / 2, -1.0, 0.5]))
    A = [[diag if i == j else 0.0 for j in range(n)] for i in range(n)]
    if n == 2:
        A[0][1] = draw(st.sampled_from([0.0, 0.25, 1.0]))
    C = [[draw(st.sampled_from([1.0, -1.0, 0.5, 0.0])) for _ in range(n)] for _ in range(p)]
    for i in range(min(n, p)):
        C[i][i] = 1.0
    exponent = st.integers(50, 64)
    L = [
        [
            draw(st.sampled_from([-1.0, 1.0])) * 2.0 ** -draw(exponent)
            + draw(st.sampled_from([0.0, 2.0**-70]))
            for _ in range(p)
        ]
        for _ in range(n)
    ]
    return A, C, L


@pytest.mark.slow
@settings(max_examples=40, deadline=None)
@given(_rounding_level_designs())
def test_gain_verdicts_at_the_rounding_level_agree_with_exact_arithmetic(design):
    A, C, L = design
    spec = _spec(A, C, {"kind": "luenberger", "gain": L})
    observer = build_observer(spec.system, spec.observer)
    stable = _exactly_schur(_exact_F(A, L, C))
    gain = observer_gain_check(observer)
    stability, _ = observer_stability_check(observer)
    for check in (gain, stability):
        if check.verdict.value == "holds":
            assert stable, (check.id, check.summary)
        if check.verdict.value == "fails":
            assert not stable, (check.id, check.summary)


@pytest.mark.slow
@settings(max_examples=25, deadline=None)
@given(_rounding_level_designs(), st.sampled_from([0.5, 0.9]))
def test_sparse_observer_verdicts_at_the_rounding_level_agree_with_exact_arithmetic(design, shrink):
    A, C, L = design
    observer = {"kind": "elastic_net", "gain": L, "step": 0.5, "threshold": 0.1}
    observer["shrink"] = shrink
    spec = _spec(A, C, observer)
    design_ = build_observer(spec.system, spec.observer)
    stable = _exactly_schur(_exact_F(A, L, C))
    check, _ = observer_stability_check(design_)
    if check.verdict.value == "holds":
        assert stable, check.summary  # a stable F is necessary: near 0 the error follows F
    if check.verdict.value == "fails" and check.code is LMICause.ERROR_MATRIX_UNSTABLE:
        assert not stable, check.summary


# ---------------------------------------------------------------------------
# witnesses whose replay disagrees


def test_a_repelling_equilibrium_says_so_and_why_its_replay_drifts():
    # found by a search over small rational designs: the equilibrium exists exactly, but the
    # linear part of the error's map near it has an eigenvalue 1.76, so rounding moves off it
    spec = _spec(
        [[0.4]],
        [[-1.1], [-0.6], [1.3]],
        {"kind": "dsso", "gain": [[1.5, 0.7, 1.2]], "step": 0.9, "threshold": 0.1},
    )
    check, _ = observer_stability_check(build_observer(spec.system, spec.observer))
    witness = check.witness
    assert check.verdict.value == "fails" and witness["kind"] == "nonzero equilibrium"
    assert witness["repelling"] and witness["local_loop_moduli"][0] > 1.7
    replay = witness["observer_replay"]
    assert replay["replayed"] and not replay["agrees"]
    assert check.code is WitnessKind.NONZERO_EQUILIBRIUM and replay["steps"] == 50
    assert replay["largest_drift"] > 1e-9  # what the summary says it drifted by
    assert check.summary == observer_messages.failure_summary(witness)


# ---------------------------------------------------------------------------
# every size a spec names, at 10^9


UGV = {"A": [[1.0, 0.0099], [0.0, 0.9876]], "C": [[1, 0], [0, 1], [0, 1]]}
BIG = 10**9


def _write(tmp_path, observer, attack=None, scenario=None):
    import json

    data = {
        "name": "big",
        "system": UGV,
        "attack": attack or {"max_attacked": 1},
        "observer": observer,
    }
    if scenario is not None:
        data["scenario"] = [scenario]
    path = tmp_path / "big.json"
    path.write_text(json.dumps(data))
    return str(path)


SSO = {"kind": "sso", "step": 0.3, "threshold": 0.1}
SCENARIO = {"name": "c", "attack": "constant", "sensors": [1], "magnitude": [4.0, 5.0]}


def test_a_horizon_of_a_billion_is_refused_naming_it(tmp_path, capsys):
    path = _write(tmp_path, SSO, attack={"max_attacked": 1, "horizon": BIG})
    assert main(["analyze", path]) == 2
    assert "attack.horizon" in capsys.readouterr().err


@pytest.mark.parametrize("key", ["window", "inner_steps"])
def test_an_sso_size_of_a_billion_is_answered_naming_it(tmp_path, capsys, key):
    path = _write(tmp_path, {**SSO, key: BIG})
    assert main(["analyze", path, "--json", "-"]) in (1, 3)
    out = capsys.readouterr().out
    assert f"{key} = 1,000,000,000" in out or f"{key} = {BIG:,}" in out


@pytest.mark.parametrize("key", ["steps", "runs"])
def test_a_scenario_size_of_a_billion_is_refused_naming_it(tmp_path, capsys, key):
    path = _write(tmp_path, SSO, scenario={**SCENARIO, "steps": 20, "runs": 2, key: BIG})
    assert main(["simulate", path]) == 2
    err = capsys.readouterr().err
    assert "1,000,000,000" in err and key in err and "--memory-budget" in err


def test_a_switching_period_of_a_billion_simulates(tmp_path, capsys):
    scenario = {"name": "c", "attack": "switching", "count": 1, "magnitude": [1.0, 2.0]}
    path = _write(tmp_path, SSO, scenario={**scenario, "steps": 20, "runs": 2, "period": BIG})
    assert main(["simulate", path]) == 0


@pytest.mark.parametrize("option", ["--runs", "--steps"])
def test_a_simulation_option_of_a_billion_is_refused(tmp_path, capsys, option):
    path = _write(tmp_path, SSO, scenario={**SCENARIO, "steps": 20, "runs": 2})
    assert main(["simulate", path, option, str(BIG)]) == 2
    assert "1,000,000,000" in capsys.readouterr().err


# ---------------------------------------------------------------------------
# found by an adversarial pass (CLI and documents only)


def test_an_sso_gain_derived_from_its_step_is_exact_from_the_step():
    # L = step A C^T rounds to a gain whose A - L C is stable; the spec's own observer,
    # A (1 - 5 step) = 1 + 1.09e-47, is not
    spec = _spec(
        [[1.0000000000000002]],
        [[1.0]] * 5,
        {"kind": "sso", "step": 4.440892098500625e-17, "threshold": 0.1},
    )
    design = build_observer(spec.system, spec.observer)
    gain = observer_gain_check(design)
    # decided on the exact F of L = step A C^T: 1 + 1.09e-47, where the floats' F is stable
    assert gain.verdict.value == "fails" and gain.code is SchurCode.TRACE_EXCESS
    excess = gain.evidence["exact_decision"]["spectral_radius_excess"]
    assert excess == pytest.approx(1.0947644252537622e-47, rel=1e-6)
    assert gain.value_text == "1 + 1.09e-47"
    assert observer_stability_check(design)[0].verdict.value == "fails"


@pytest.mark.slow
def test_an_sso_error_matrix_that_overflows_is_inconclusive_not_an_error(tmp_path, capsys):
    plant = {"A": [[1.0, 0.0099], [0.0, 0.9876]], "C": [[1, 0], [0, 1], [0, 1], [1, 1]]}
    data = {"name": "o", "system": plant, "attack": {"max_attacked": 1}}
    data["observer"] = {"kind": "sso", "step": 0.9, "threshold": 0.1, "inner_steps": 1000}
    path = tmp_path / "o.json"
    import json

    path.write_text(json.dumps(data))
    assert main(["analyze", str(path)]) == 1  # sparse observability fails; nothing crashes
    out = capsys.readouterr().out
    assert "A (I - step S' S)^1000 overflows in floating point" in out


def test_a_deadbeat_gain_of_a_badly_scaled_plant_is_deadbeat():
    # the plant's states in units 2^40 apart: the gain was index 2 "to rounding" with
    # rho(A - L C) = 0.54; built and tested in balanced state units it has index 3
    A = [
        [0.3, 1099511627776.0, 0.0],
        [0.0, 0.5, 9.094947017729282e-13],
        [9.313225746154785e-10, 0.0, 0.7],
    ]
    cert = analyze(_spec(A, [[1.0, 1.0, 1.0]], {"kind": "luenberger", "gain": "deadbeat"}))
    gain = cert["observer_gain"]
    assert gain.verdict.value == "holds"
    assert gain.fields["nilpotency_index"] == cert["observability"].value == 3
    assert gain.evidence["details"]["spectral_radius_upper_bound"] < 1e-3


def test_assert_deadbeat_with_a_tolerance_does_not_depend_on_units():
    from ssecert.testing import assert_deadbeat

    for F in ([[0.0, 2.0**33], [2.0**-36, 0.0]], [[0.0, 0.5], [0.25, 0.0]]):  # rho 0.354
        with pytest.raises(AssertionError, match="not nilpotent"):
            assert_deadbeat(F, np.zeros((2, 1)), np.zeros((1, 2)), rtol=1e-8)


@pytest.mark.parametrize("k", [(47, -23), (200, -200)])
def test_a_lyapunov_certificate_survives_state_units(k):
    # (1 - 1e-9) times a rotation, its states in units 2^47 and 2^-23: P verified in balanced
    # coordinates and written back exactly
    c, s = np.cos(1.0), np.sin(1.0)
    F = (1 - 1e-9) * np.array([[c, -s], [s, c]])
    t = np.array([2.0 ** k[0], 2.0 ** k[1]])
    Ft = F * t[:, None] / t[None, :]
    cert = analyze(
        _spec(
            Ft.tolist(),
            np.diag(1.0 / t).tolist(),
            {"kind": "luenberger", "gain": [[0.0, 0.0], [0.0, 0.0]]},
        )
    )
    for check in ("observer_gain", "observer_stability"):
        assert cert[check].verdict.value == "holds", cert[check].summary
    # a verified P, found in balanced state coordinates (its scaling in the proof)
    gain = cert["observer_gain"]
    assert gain.code is LyapunovCode.VERIFIED
    scaling = gain.evidence["exact_decision"]["state_scaling"]
    assert np.ptp(np.log2(scaling)) > 16


def test_the_dead_zone_region_fails_with_its_error_matrix():
    # F = 1 + 1e-17 exactly: observer_stability fails, and the region check agrees
    spec = _spec(
        [[1.0]],
        [[1.0], [1.0]],
        {"kind": "dsso", "gain": [[-1e-17, 0.0]], "step": 0.5, "threshold": 0.1},
    )
    from ssecert.stability.checks import region_of_attraction_check

    design = build_observer(spec.system, spec.observer)
    assert observer_stability_check(design)[0].verdict.value == "fails"
    assert region_of_attraction_check(design).verdict.value == "fails"


def test_a_large_sso_window_decides_its_error_block_alone():
    # window 100: the Lur'e model (302 states) is beyond its exact budget, but F (2 x 2) is not,
    # so observer_stability agrees with observer_gain instead of being undecided
    spec = _spec(
        [[0.9, 0.2], [0.0, 0.8]],
        [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]],
        {"kind": "sso", "step": 0.1, "threshold": 0.1, "window": 100},
        s=1,
    )
    design = build_observer(spec.system, spec.observer)
    gain = observer_gain_check(design)
    # the exact traces of F = A - L O_tau (window 100) bound its spectral radius below by 1.0058
    assert gain.verdict.value == "fails" and gain.code is SchurCode.TRACES_BELOW
    assert (
        gain.value == pytest.approx(1.0058, abs=1e-4)
        and gain.evidence["exact_decision"]["rigorous"]
    )
    assert gain.method == "exact powers of A - L C"
    assert observer_stability_check(design)[0].verdict.value == "fails"


@pytest.mark.slow
@pytest.mark.parametrize(
    "A, C",
    [
        ([[1.0, 0.0], [0.0, 1.0]], [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
        ([[0.5, 0.0], [0.0, 0.5]], [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, -1.0], [2.0, 1.0]]),
    ],
)
def test_a_step_of_1e308_is_inconclusive_not_an_internal_error(tmp_path, capsys, A, C):
    # the error dynamics overflow: normF**2 raised OverflowError in the dead zone's Lyapunov
    # check, and eigvals / distance bounds met infinite matrices (exit 4)
    import json

    from ssecert.cli import main

    spec = {"name": "huge-step", "system": {"A": A, "C": C}, "attack": {"max_attacked": 1},
            "observer": {"kind": "dsso", "gain": "deadbeat", "step": 1e308, "threshold": 0.1}}  # fmt: skip
    path = tmp_path / "huge-step.json"
    path.write_text(json.dumps(spec))
    assert main(["analyze", str(path), "--seed", "0", "--time-budget", "2"]) in (1, 3)
    out = capsys.readouterr().out
    assert "observer_stability: inconclusive" in out
    # the certified region's map runs the cells around that step: undecided, not an error
    folder = tmp_path / "out"
    assert main(["certify", str(path), "--out", str(folder), "--seed", "0", "--runs", "2"]) in (
        1,
        3,
    )
    assert (folder / "huge-step.json").exists()


def test_an_elastic_net_with_a_step_of_1e308_in_far_units_ends_in_verdicts():
    # the canonical balancing put the dead zone's loop in coordinates where its Lyapunov
    # solution is not finite: the residual's 2-norm (an SVD of NaNs) ended in LinAlgError
    from ssecert import analyze, spec_from_dict

    spec = spec_from_dict(
        {"name": "huge-step", "system": {"A": [[1.0, 0.0099], [0.0, 0.9876]],
         "C": [[1, 0], [0, 1], [0, 1], [1, 1]]}, "attack": {"max_attacked": 1},
         "observer": {"kind": "elastic_net", "gain": "pinv", "step": 1e308, "threshold": 0.1,
                      "shrink": 0.5}}
    )  # fmt: skip
    cert = analyze(spec)
    assert cert["observer_stability"].verdict.value != "holds"
    assert cert["region_of_attraction"].verdict.value == "inconclusive"


def test_an_exact_observability_matrix_is_formed_within_its_total_bits():
    # the entries of C A^k grow by A's 53 bits per power: a window of 3,000 formed an exact
    # O_tau of about 10^9 bits and its exact gain's products ran for minutes; beyond the total
    # budget the design's floats are used (their rounding bounded a priori)
    from ssecert.numerics.exact_powers import exact_observability_matrix

    A, C = np.array([[0.9, 0.2], [0.0, 0.8]]), np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    assert exact_observability_matrix(A, C, 3000) is None
    exact = exact_observability_matrix(A, C, 50)
    assert exact is not None and exact.shape == (150, 2)
    assert exact.to_fractions()[3 * 49][0] == (Fraction(0.9) ** 49)


def test_a_step_of_1e200_fails_by_a_divergent_trajectory_replayed_within_the_float_range():
    # the large-signal loop has the eigenvalue -1e200: a replay of two steps overflowed and the
    # observer was left inconclusive ("which does not mean the observer is unstable")
    from ssecert.stability.checks import observer_stability_check

    spec = spec_from_dict(
        {"name": "step-1e200", "system": {"A": np.eye(2).tolist(),
         "C": [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]}, "attack": {"max_attacked": 1},
         "observer": {"kind": "dsso", "gain": "deadbeat", "step": 1e200, "threshold": 0.1}}
    )  # fmt: skip
    check, _ = observer_stability_check(build_observer(spec.system, spec.observer))
    assert check.verdict.value == "fails"
    witness = check.witness
    assert witness["kind"] == "divergent trajectory" and witness["steps"] == 1
    assert np.isfinite(witness["norms"][1]) and witness["norms"][1] > 1e100 * witness["norms"][0]


def test_an_error_weight_of_2_to_the_1000_is_not_an_internal_error(tmp_path, capsys):
    # A = [[0.5, 2^1000], [0, 0.5]] (a nonnormal plant with its second state in units 2^1000
    # smaller), zero gain: the l2 gain's output scaling squared a power of two past the floats
    import json

    spec = {"name": "far", "system": {"A": [[0.5, 2.0**1000], [0.0, 0.5]], "C": [[1.0, 0.0]]},
            "attack": {"max_attacked": 0},
            "observer": {"kind": "luenberger", "gain": [[0.0], [0.0]]}}  # fmt: skip
    path = tmp_path / "far.json"
    path.write_text(json.dumps(spec))
    assert main(["analyze", str(path), "--seed", "0", "--time-budget", "2"]) in (0, 1, 3)
    assert "internal error" not in capsys.readouterr().err


@pytest.mark.slow
def test_messages_name_what_was_shown():  # a whole analyze of an SSO: about 10 s
    # an SSO with inner steps: the matrix checked is A (I - step S'S)^m, not A - L C with the
    # one-step L printed beside it
    from ssecert import analyze, spec_from_dict
    from ssecert.budget import Budget
    from ssecert.report.cells import margin_text
    from ssecert.testing import assert_schur

    spec = spec_from_dict(
        {"name": "sso", "system": {"A": [[1.0, 0.0099], [0.0, 0.9876]],
         "C": [[1, 0], [0, 1], [0, 1], [1, 1]]}, "attack": {"max_attacked": 1},
         "observer": {"kind": "sso", "step": 0.1, "threshold": 0.1, "window": 2,
                      "inner_steps": 100}}
    )  # fmt: skip
    gain = analyze(spec)["observer_gain"]
    assert gain.value_name == "spectral radius of A (I - step S' S)^100"
    assert gain.code is LyapunovCode.VERIFIED
    assert "100 inner steps" in gain.evidence["error_matrix"]
    # an eigenvalue 1 - 2^-53 is not written "1" (a Jordan block at it, with 19 stable
    # states: beyond the Schur-Cohn test's 20, which proves the block alone stable)
    jordan = np.array([[1 - 2.0**-53, 1.0], [0.0, 1 - 2.0**-53]])
    assert assert_schur(jordan).method.value == "exact Schur-Cohn test"
    with pytest.raises(AssertionError, match=r"modulus 1 - 1\.1e-16"):
        assert_schur(np.block([[jordan, np.zeros((2, 19))], [np.zeros((19, 2)), np.eye(19) / 8]]))
    # an estimate just over its budget is not "1e+12 over 1e+12"
    assert "1.0000001e+12 floating-point operations, over the work budget of 1e+12" in (
        Budget(work=1e12).refusal("x", flops=1.0000001e12)
    )
    # a deadbeat margin 1 - 2.2e-16 is not "1"
    ugv = analyze(spec_from_dict({"name": "u", "system": {"A": [[1.0, 0.0099], [0.0, 0.9876]],
                  "C": [[1, 0], [0, 1], [0, 1]]}, "attack": {"max_attacked": 1},
                  "observer": {"kind": "dsso", "gain": "deadbeat", "step": 0.7,
                               "threshold": 0.1}}))["observer_gain"]  # fmt: skip
    assert ugv.margin != 1.0 and margin_text(ugv).startswith("1 - ")


@pytest.mark.parametrize(
    ("A", "code"),
    [
        ([[2.0, 0.0], [0.0, 0.5]], SchurCode.TRACES_BELOW),
        # eigenvalues +-i and 1/2: the Schur-Cohn test of the exact characteristic polynomial
        ([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.5]], SchurCode.SCHUR_COHN_FAILS),
    ],
)
def test_an_exact_instability_shows_no_margin(A, code):
    # the margin of the Lyapunov solution that did not verify is not "1 - spectral radius
    # bound" (it read -1 beside a lower bound of 1)
    n = len(A)
    cert = analyze(
        _spec(A, np.eye(n).tolist(), {"kind": "luenberger", "gain": np.zeros((n, n)).tolist()})
    )
    for check in ("observer_gain", "observer_stability"):
        assert cert[check].verdict.value == "fails" and cert[check].code is code
        assert cert[check].margin is None
