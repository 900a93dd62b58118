"""Cases that once gave wrong answers or crashes (from a review of the code)."""

from pathlib import Path

import numpy as np
import pytest

from ssecert import System, irrepresentable, load_spec, observability, sparse_observability
from ssecert.base.format import distance as readable_distance
from ssecert.cli import main
from ssecert.design.gains import GainError, deadbeat_gain
from ssecert.stability import observer_messages
from ssecert.structure.outcomes import IrrepresentableCode, SparseCode

DATA = Path(__file__).parent / "data"


@pytest.mark.parametrize("name", ["chain3", "close9"])
@pytest.mark.parametrize("method", ["auto", "enumeration", "eigenspace"])
def test_close_well_conditioned_eigenvalues_are_not_merged(name, method):
    """Distinct eigenvalues 1e-4 apart with condition number 1 are separate modes; one of
    them is seen by a single sensor, so one attacked sensor cannot be corrected."""
    spec = load_spec(DATA / f"{name}.toml")
    check = sparse_observability(spec.system, spec.max_attacked, method=method)
    assert check.verdict.value == "fails"
    assert check.fields["max_removable"] == 0


def test_enumeration_screening_accounts_for_basis_errors():
    """The 12 sensors that break this plant in floating point leave its exact data
    observable, 1.5e-15 away from unobservable: max_removable >= 11 is all the data
    support, and the verdict for s = 1 holds."""
    spec = load_spec(DATA / "t3_71.npz", max_attacked=1)
    enum = sparse_observability(spec.system, 1, method="enumeration")
    eig = sparse_observability(spec.system, 1, method="eigenspace")
    auto = sparse_observability(spec.system, 1)
    assert eig.fields["max_removable"] in (11, None)
    assert enum.fields["max_removable"] in (11, None)
    assert auto.verdict.value == "holds"
    assert auto.fields["max_removable"] == 11 and auto.fields["max_removable_is_lower_bound"]
    # a lower bound because the 12-sensor set is within precision of breaking the plant
    assert auto.code is SparseCode.LOWER_BOUND
    assert auto.evidence["within_precision_of_breaking"] == [
        [1, 3, 4, 5, 7, 8, 9, 10, 11, 12, 13, 15]
    ]
    assert auto.evidence["distance_to_breaking"] < 10 * 2.0**-52


def test_nilpotency_index_is_invariant_under_scaling():
    spec = load_spec(DATA / "small.toml")
    gain = deadbeat_gain(spec.system)
    assert gain.verified and gain.details["nilpotency_index"] == 6
    rng = np.random.default_rng(0)
    A, C = rng.standard_normal((6, 6)), rng.standard_normal((1, 6))
    for alpha in (1e-3, 1.0, 1e3):
        assert deadbeat_gain(System(alpha * A, C)).details["nilpotency_index"] == 6


@pytest.mark.slow
def test_rounding_does_not_make_a_stable_gain_fail(capsys):
    code = main(["analyze", str(DATA / "jordan12.toml")])
    out = capsys.readouterr().out
    assert "observer_gain         FAILS" not in out
    assert code != 1


def test_irrepresentable_without_attack_on_a_rank_deficient_horizon():
    check = irrepresentable(System(np.eye(2), [[1.0, 0.0]]), 0, horizon=1)
    assert check.verdict.value == "fails" and np.isinf(check.value)


def test_gain_that_cannot_be_computed_is_bad_input_for_simulate(tmp_path, capsys):
    spec = tmp_path / "s.toml"
    spec.write_text(
        'name = "s"\n[system]\nA = [[0.5, 0.0], [0.0, 0.9]]\nC = [[1.0, 0.0]]\n'
        '[attack]\nmax_attacked = 0\n[observer]\nkind = "dsso"\ngain = "deadbeat"\n'
        'step = 0.5\nthreshold = 0.1\n[[scenario]]\nname = "c"\nattack = "none"\n'
    )
    assert main(["simulate", str(spec), "--runs", "2", "--steps", "5"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ssecert: error:") and "Traceback" not in err
    # the file, the key and the cause
    assert "s.toml: observer.gain = 'deadbeat'" in err and "not observable" in err


def test_elastic_net_with_ogd_gain_runs(tmp_path):
    spec = tmp_path / "s.toml"
    spec.write_text(
        'name = "s"\n[system]\nA = [[0.5, 0.1], [0.0, 0.9]]\nC = [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]\n'
        '[attack]\nmax_attacked = 0\n[observer]\nkind = "elastic_net"\ngain = "ogd"\n'
        'step = 0.1\nthreshold = 0.1\nshrink = 0.5\n[[scenario]]\nname = "c"\nattack = "none"\n'
    )
    assert main(["simulate", str(spec), "--runs", "2", "--steps", "5"]) == 0


def test_unwritable_report_folder_is_bad_input(capsys):
    assert main(["certify", "notes-example-0", "--no-sim", "--out", "/proc/sys/ssecert"]) == 2
    assert "cannot write" in capsys.readouterr().err


@pytest.mark.parametrize("tiny", [5e-324, 1e-310])
@pytest.mark.parametrize("where", ["A", "C"])
def test_subnormal_largest_entries_are_analysed(tiny, where):
    """A plant whose largest entry (of A, or of a sensor's row) is subnormal: exact units
    cannot reach [1, 2) with one power of two, and once ended in an OverflowError."""
    from ssecert import analyze, spec_from_dict

    A = [[tiny]] if where == "A" else [[1.0]]
    C = [[1.0], [1.0]] if where == "A" else [[tiny], [1.0]]
    spec = spec_from_dict(
        {"name": "sub", "system": {"A": A, "C": C}, "attack": {"max_attacked": 0}}
    )
    cert = analyze(spec)
    assert cert["observability"].verdict.value == "holds"  # every entry is exactly nonzero
    assert cert["sparse_observability"].verdict.value == "holds"


@pytest.mark.parametrize("A, index", [([[0.0, 1.0], [0.0, 0.0]], 2), ([[0.0]], 1)])
def test_deadbeat_with_no_output_and_a_nilpotent_plant(A, index):
    """C = 0: no gain changes A - L C, and L = 0 is deadbeat exactly when A is nilpotent."""
    n = len(A)
    gain = deadbeat_gain(System(A, np.zeros((1, n))))
    assert gain.verified and gain.details["nilpotency_index"] == index
    assert not np.any(gain.L)
    with pytest.raises(GainError, match="A is not nilpotent"):
        deadbeat_gain(System([[0.5]], [[0.0]]))


def test_sparse_observability_with_no_attack_on_an_ill_conditioned_plant():
    """s = 0 on a plant whose observability is confirmed only in exact arithmetic (a
    20-state Vandermonde-like pair): the kept set is the whole plant, observable exactly,
    so the floating-point re-check's doubt does not make the answer inconclusive."""
    system = System(np.diag(np.linspace(0.1, 0.95, 20)), np.ones((1, 20)))
    check = sparse_observability(system, 0)
    assert check.verdict.value == "holds", check.summary


@pytest.mark.parametrize("support_size", [0, 1])
def test_irrepresentable_does_not_fail_on_a_rank_deficiency_below_precision(support_size):
    # exactly, O_tau has rank 2; in floating point it looks like rank 1
    system = System(np.diag([1.0, 1.0 + 2.0**-52]), np.ones((3, 2)))
    check = irrepresentable(system, support_size, horizon=2)
    assert check.verdict.value == "inconclusive"
    assert check.code is IrrepresentableCode.O_TAU_DOUBT
    assert check.evidence["exact_rank_check"]["state"] == "observable"


def test_irrepresentable_rank_deficiency_is_confirmed_exactly():
    check = irrepresentable(System(np.eye(2), np.ones((3, 2))), 1, horizon=2)
    assert check.verdict.value == "fails"
    assert check.evidence["exact_rank_check"]["state"] == "unobservable"


@pytest.mark.parametrize(("top", "verdict"), [(1.0 + 2.0**-52, "inconclusive"), (1.0, "fails")])
def test_irrepresentable_support_rank_is_decided_exactly(top, verdict):
    # without sensor y3, the rows left are rank deficient exactly only when top == 1
    system = System(np.diag([1.0, top]), [[1.0, 1.0], [1.0, 1.0], [1.0, 0.0]])
    check = irrepresentable(system, 1, horizon=2)
    assert check.verdict.value == verdict
    assert check.evidence["exact_rank_check"]["state"] == (
        "observable" if verdict == "inconclusive" else "unobservable"
    )


def test_stealthy_witness_beyond_the_float_range_is_shown_in_scaled_units():
    # C A^3 z ~ 1e360: the plant's own attack overflows before n = 4 steps
    n = 4
    A = np.diag([1e120 * (1 - 0.1 * i) for i in range(n)])
    A[0, 1] = A[1, 2] = A[2, 3] = 1e118
    system = System(A, np.vstack([np.eye(n), np.eye(n)[-1:]]))
    check = sparse_observability(system, 1)
    assert check.verdict.value == "fails"
    w = check.witness
    assert w["verified"] and np.all(np.isfinite(np.asarray(w["attack_a"], dtype=float)))
    assert w["time_scale_log2"] < -300 and "gamma" in w["units"]


def test_ambiguous_eigenvalue_grouping_does_not_block_a_clear_observability_verdict():
    # eigenvalues 0.5 and 0.5 + 2^-45 with independent eigenvectors; C alone has rank 2 (four
    # rows [1, 1] hold the states' units together: with two, the balancing scales the 2^-45
    # coupling up to 2^-27 and the eigenvalues are no longer ambiguous)
    d = 2.0**-45
    C = [[-1.0, 0.0], [1.0, 1.0], [1.0, 1.0], [1.0, 1.0], [1.0, 1.0], [-1.0, 0.0]]
    system = System([[0.5 + d, 0.0], [-d, 0.5]], C)
    check = observability(system)
    assert check.verdict.value == "holds"
    assert "eigenvalue_grouping_ambiguous" in check.evidence
    # eigenvalues in messages are the plant's, not those of its power-of-two rescaling
    assert "eigenvalue 0.5" in check.evidence["eigenvalue_grouping_ambiguous"]
    sparse = sparse_observability(system, 1)
    assert sparse.verdict.value == "fails" and sparse.fields["max_removable"] == 1


def test_sparse_observability_of_an_exactly_unobservable_plant_is_minus_one():
    # float analysis of the eigenspaces is borderline; the exact data are unobservable
    A = np.array(
        [
            [1.5000000000009095, 1.0, -1.0, 0.0],
            [
                9.094947017729282e-13,
                0.5000000000063665,
                -9.094947017729282e-13,
                -2.7284841053187847e-12,
            ],
            [1.0000000000009095, 1.000000000005457, -0.5, -2.7284841053187847e-12],
            [
                1.8189894035458565e-12,
                1.0913936421275139e-11,
                -1.8189894035458565e-12,
                0.4999999999954525,
            ],
        ]
    )
    system = System(A, [[1.0, 4.0, -1.0, -2.0]])
    assert observability(system).verdict.value == "fails"
    check = sparse_observability(system, 1)
    assert check.verdict.value == "fails" and check.fields["max_removable"] == -1


@pytest.mark.slow
def test_a_diverging_simulation_says_so(tmp_path, capsys):
    spec = tmp_path / "d.toml"
    spec.write_text(
        "[system]\nA = [[1.0, 0.0099], [0.0, 0.9876]]\nC = [[1, 0], [0, 1], [0, 1]]\n"
        '[attack]\nmax_attacked = 1\n[observer]\nkind = "luenberger"\n'
        "gain = [[3.0, 0.0, 0.0], [0.0, 0.0, 0.0]]\n"
        '[[scenario]]\nname = "c"\nattack = "constant"\nsensors = [1]\nsteps = 2000\nruns = 3\n'
    )
    assert main(["simulate", str(spec)]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("c "))
    assert row.split()[4:6] == ["inf", "inf"]  # unbounded, not NaN
    assert "overflows in floating point in 3 of 3 runs, the first at step" in out


def test_observer_checks_use_and_report_the_tolerances_given():
    from ssecert.stability.checks import observer_checks
    from ssecert.tolerances import Tolerances

    system = System([[0.5, 1.0], [0.0, 0.2]], [[1.0, 0.0]])
    observer = {"kind": "luenberger", "gain": [[0.1], [0.0]]}
    default = observer_checks(system, observer)
    assert default[0].verdict.value == "holds"
    assert default[0].tolerances["clear_factor"] == 100.0
    assert default[0].method == "discrete Lyapunov (dlyap)"
    # a Lyapunov decrease that must beat its error bound 1e30 times cannot: the gain falls
    # back to the exact powers, and the ISS gain (an LMI certificate) is not certified
    strict = observer_checks(system, observer, tolerances=Tolerances(certificate_clear=1e30))
    assert [c.tolerances["clear_factor"] for c in strict] == [1e30] * 3
    assert strict[0].method == "exact powers of A - L C"
    assert strict[2].verdict.value == "inconclusive"


def test_the_deadbeat_gain_is_built_with_the_run_tolerances():
    # the power test of a deadbeat gain runs when the gain is built: certify's tolerances
    # reach the builder, and the check reports the ones the verdict rested on
    from ssecert.certify import certify
    from ssecert.examples import load_example
    from ssecert.tolerances import Tolerances

    tol = Tolerances(deadbeat_rtol=1e-6, certificate_clear=1e3)
    result = certify(load_example("ugv"), simulate=False, region=False, tolerances=tol)
    gain = result.certificate["observer_gain"]
    assert gain.method.startswith("deadbeat")
    assert gain.tolerances["deadbeat_rtol"] == 1e-6
    assert gain.tolerances["clear_factor"] == 1e3
    default = certify(load_example("ugv"), simulate=False, region=False)
    assert default.certificate["observer_gain"].tolerances["deadbeat_rtol"] == 1e-8


@pytest.mark.parametrize(
    ("F", "code", "eigenvalue"),
    [
        # below the first-order bound
        (np.diag([1.0 + 2.0**-40, 0.5]), "EIGENVALUE_ON_CIRCLE", 1.0 + 2.0**-40),
        (np.diag([-(1.0 + 2.0**-40), 0.5]), "EIGENVALUE_ON_CIRCLE", -(1.0 + 2.0**-40)),
        # eigenvalues +-1
        (np.array([[0.0, 2.0**60], [2.0**-60, 0.0]]), "EIGENVALUE_ON_CIRCLE", 1.0),
        (np.array([[0.0, 1.0], [-1.0, 0.0]]), "TRACE_REACHES_N", None),  # a rotation: rho = 1
    ],
)
def test_a_spectral_radius_of_at_least_one_is_decided_exactly(F, code, eigenvalue):
    from ssecert.stability.outcomes import SchurCode, SchurState
    from ssecert.stability.spectral import schur_decision

    decision = schur_decision(F)
    assert decision.state is SchurState.UNSTABLE and decision.rigorous
    assert decision.code is SchurCode[code]
    assert decision.facts.get("eigenvalue") == eigenvalue


def test_deadbeat_summary_gives_the_exact_index_of_the_printed_gain():
    # A nilpotent of index 2 and C of rank 2: the printed L leaves F = 2^-52 A, which is not
    # zero (index 1 to rounding only) but squares to zero exactly
    from ssecert.stability.checks import observer_checks

    system = System([[-1.0, 1.0], [-1.0, 1.0]], [[-3.0, 1.0], [4.0, -2.0], [-2.0, 1.0], [0.0, 0.0]])
    gain = observer_checks(system, {"kind": "luenberger", "gain": "deadbeat"})[0]
    assert gain.verdict.value == "holds"
    assert gain.fields["nilpotency_index"] == 2 and gain.fields["nilpotency_index_to_rounding"] == 1
    details = gain.evidence["details"]
    assert details["exactly_nilpotent"] and details["exact_nilpotency_index"] == 2
    assert gain.value == 2 and gain.value_name == "nilpotency index"
    assert gain.summary.startswith(observer_messages.nilpotent_summary(details))


def test_near_zero_distances_are_not_printed_as_zero():
    # exactly observable (distinct eigenvalues), within rounding of unobservable
    system = System(np.diag([1.0, 1.0 + 2.0**-52, 1.0 - 2.0**-53]), np.ones((5, 3)))
    check = observability(system)
    assert check.verdict.value == "inconclusive"
    # computed as 0, the distance is written as below the rounding level, never as 0.0e+00
    distance = check.evidence["distance_to_unobservability"]
    assert distance == 0.0 and check.evidence["exact"]["state"] == "observable"
    assert readable_distance(distance) == "below the rounding level 2.2e-16"


def test_eigenvalue_grouping_tests_each_component_once(monkeypatch):
    # a dense plant: every pair of eigenvalues is a candidate edge, but a component is tested
    # only when it grows (at most n - 1 times), not once per edge inside it
    from ssecert.numerics import eigen

    calls = []
    original = eigen._compatible
    monkeypatch.setattr(eigen, "_compatible", lambda *args: calls.append(1) or original(*args))
    n = 60
    eigen.eigen_clusters(np.random.default_rng(0).standard_normal((n, n)))
    assert len(calls) <= n - 1


def test_a_certain_breaking_set_is_found_past_undecided_smaller_sets():
    # A = I: any 4 removed sensors leave one row, so s = 2 fails whatever the last digits; the
    # sets of 3 are within precision of breaking (rows [1, 1] and [1, 1 + 2^-52] are nearly
    # parallel; rows [1, 0] and [1, 2^-52] were, until the balancing scaled the states 2^17
    # apart)
    C = [[1.0, 1.0], [1.0, 1.0 + 2.0**-52], [0.0, 1.0], [1.0, 0.0], [1.0, -1.0]]
    check = sparse_observability(System(np.eye(2), C), 2, method="enumeration")
    assert check.verdict.value == "fails"
    assert check.fields["max_removable_is_upper_bound"]
    assert check.fields["max_removable"] == 3 and check.fields["max_removable_at_least"] == 2
    # the breaking set is confirmed on the exact data, whatever digits they lack
    assert check.code is SparseCode.BREAKING_SET and check.evidence["breaking_set_exact"]
    assert check.evidence["breaking_set_check"]["exact"]["state"] == "unobservable"
    assert check.witness["verified"] and len(check.fields["breaking_set"]) == 4


@pytest.mark.slow
@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("scale, gain_row", [(1e-308, "holds"), (1e-310, "inconclusive")])
def test_sensor_rows_near_the_bottom_of_the_float_range_end_in_verdicts(scale, gain_row):
    """C of order 1e-308 put exact powers of 1e308 past 2.0 ** 1024 in the spectral bound (an
    OverflowError); at 1e-310 the deadbeat gain itself overflows, which is said as such.  At
    1e-308 the dead zone |Cw_i xi| <= 0.1 holds errors up to about 1e307, where the deadbeat
    loop alone acts: the region is proved in balanced coordinates (states 2^1023 from the
    channels' units), within that dead zone.  No warning escapes (the piecewise search's
    samples and the LMIs' data overflowed with RuntimeWarnings, an error under -W error)."""
    from ssecert import analyze, spec_from_dict

    C = (np.array([[0.9, -0.2], [0.7, 0.5], [0.8, 0.7]]) * scale).tolist()
    observer = {"kind": "elastic_net", "gain": "deadbeat", "step": 1.0, "threshold": 0.1,
                "shrink": 0.8}  # fmt: skip
    spec = spec_from_dict(
        {"name": "tiny-c", "system": {"A": [[-0.4, -0.9], [1.1, -0.4]], "C": C},
         "attack": {"max_attacked": 1}, "observer": observer}
    )  # fmt: skip
    cert = analyze(spec)
    assert cert["observer_gain"].verdict.value == gain_row
    if gain_row == "inconclusive":
        # no gain: the deadbeat construction itself overflows (its words: test_observer_messages)
        assert cert["observer_gain"].fields["L"] is None
        with pytest.raises(GainError):
            deadbeat_gain(spec.system)
    else:
        region = cert["region_of_attraction"]
        assert region.verdict.value == "holds"
        rows = np.array([[0.9, -0.2], [0.7, 0.5], [0.8, 0.7]])  # C / scale (no underflow)
        dead_zone = 0.1 / (scale * np.max(np.linalg.norm(rows, axis=1)))
        assert 1e306 < region.value <= dead_zone


def test_a_power_bound_beyond_the_float_range_is_infinite():
    from ssecert.numerics.exact_powers import _pow2

    assert _pow2(1e4) == np.inf and _pow2(1023.5) < np.inf and _pow2(-1e5) == 0.0


_NEAR_THE_LIMITS = [  # (seed, p, scale of C, observer): each raised a RuntimeWarning
    (7, 3, 1e-300, {"kind": "luenberger", "gain": "deadbeat"}),
    (
        16,
        3,
        1e300,
        {"kind": "elastic_net", "gain": "deadbeat", "step": 1.0, "threshold": 0.1, "shrink": 0.8},
    ),
    (20, 3, 1e-150, {"kind": "dsso", "step": 0.5, "threshold": 0.1}),
    (27, 3, 1e150, {"kind": "sso", "step": 0.5, "threshold": 0.1}),
    (28, 3, 1e300, {"kind": "sso", "step": 0.5, "threshold": 0.1}),
    (70, 4, 1e300, {"kind": "sso", "step": 0.5, "threshold": 0.1, "window": 2}),
    (6, 3, 2.0**-1060, {"kind": "luenberger", "gain": "pinv"}),
    (
        82,
        4,
        1e300,
        {"kind": "elastic_net", "gain": "deadbeat", "step": 1.0, "threshold": 0.1, "shrink": 0.8},
    ),
]


@pytest.mark.slow
@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("seed, p, scale, observer", _NEAR_THE_LIMITS)
def test_sensors_near_the_floats_limits_raise_no_warning(seed, p, scale, observer):
    """Sensors of order 1e+-150 to 1e+-300 (and subnormal) overflowed in the iss LMI's data,
    the balanced certificate's way back, the output scaling, the instability witness, the
    OGD, SSO and pseudo-inverse gains, the periodic orbit search and a constant attack's bias
    norm, each a RuntimeWarning (an error under -W error); the checks end in verdicts, and
    every holding check's value is a number."""
    from ssecert import analyze, spec_from_dict

    rng = np.random.default_rng(seed)
    A = rng.standard_normal((2, 2)) * 0.5
    C = rng.standard_normal((p, 2)) * scale
    if seed % 2:
        A = A * (1 + 2.0**-50)
    spec = spec_from_dict({"name": "near-limits", "system": {"A": A.tolist(), "C": C.tolist()},
                           "attack": {"max_attacked": 1}, "observer": observer})  # fmt: skip
    cert = analyze(spec)
    for check in cert.checks:
        if check.verdict.value == "holds" and isinstance(check.value, float):
            assert not np.isnan(check.value), check.id


def test_an_sso_with_a_step_near_the_floats_bottom_is_answered(tmp_path, capsys):
    # its dead zone's balancing reaches the floats' ends: the scaled model's rounding bound
    # divided by zero (an internal error) where it should grow to inf
    spec = tmp_path / "tiny-step.toml"
    spec.write_text(
        'name = "x"\n[system]\nA = [[1.01, 0.1], [0, 0.9]]\nC = [[1, 0], [0, 1], [1, 1], [1, -1]]\n'
        "[attack]\nmax_attacked = 1\n"
        '[observer]\nkind = "sso"\nstep = 1e-300\nthreshold = 1e-300\nwindow = 2\n'
        "inner_steps = 3\n"
    )
    assert main(["analyze", str(spec), "--quiet"]) in (0, 1, 3)
    assert "internal error" not in capsys.readouterr().err
