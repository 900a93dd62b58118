"""ssecert.testing: strategies deliver what they promise, assertions explain, the plugin works."""

import inspect
import os
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import find, given, settings
from hypothesis import strategies as st

import ssecert.testing
from ssecert import Spec, SpecError, System, observability, sparse_observability, spec_from_dict
from ssecert.design.gains import deadbeat_gain
from ssecert.examples import list_examples, load_example
from ssecert.observers import build_observer
from ssecert.stability.outcomes import SchurCode
from ssecert.testing import (
    assert_certified,
    assert_deadbeat,
    assert_observable,
    assert_recovers,
    assert_schur,
    assert_sparse_observable,
    strategies,
)
from ssecert.testing.plugin import PROFILES, QUICK_EXAMPLES, THOROUGH_EXAMPLES
from ssecert.testing.strategies import (
    marginally_stable_systems,
    observable_systems,
    observer_designs,
    sparse_attacks,
    sparse_observable_systems,
)

UGV = load_example("ugv")
SIZES = st.integers(1, 6)


# ---------------------------------------------------------------------------
# strategies


@given(observable_systems(SIZES, SIZES))
def test_observable_systems_are_observable_with_a_margin(system):
    check = observability(system)
    assert check.verdict.value == "holds", check.summary
    assert check.margin > 1e-4
    assert np.all(np.abs(system.C).max(axis=1) > 1e-3)  # every sensor sees something


@given(observable_systems(4, 3))
def test_integer_sizes_are_the_sizes(system):
    assert system.A.shape == (4, 4) and system.C.shape == (3, 4)
    assert system.sensors == ("y1", "y2", "y3")


@given(st.data())
def test_sparse_observable_systems_have_the_planted_max_removable(data):
    p = data.draw(st.integers(1, 7), label="p")
    max_removable = data.draw(st.integers(0, p - 1), label="max_removable")
    system = data.draw(sparse_observable_systems(SIZES, p, max_removable))
    assert system.p == p
    if np.count_nonzero(np.linalg.eigvals(system.A).imag >= -1e-9) > 1:
        # with two eigenvalues (or pairs) or more, every sensor sees one of them
        assert np.all(np.abs(system.C).max(axis=1) > 1e-3)
    for method in ("enumeration", "eigenspace"):
        check = sparse_observability(system, 0, method=method)
        assert check.fields["max_removable"] == max_removable, (method, check.summary)
        assert check.fields["max_removable_is_lower_bound"] is False
        assert len(check.fields["breaking_set"]) == max_removable + 1


@given(sparse_observable_systems(3, st.integers(1, 6), 3))
def test_drawn_sensor_counts_too_small_for_max_removable_are_rejected(system):
    assert system.p >= 4


@pytest.mark.parametrize(
    "args, error, words",
    [
        ((3, 4, 4), ValueError, ["max_removable", "p - 1 = 3", "got 4"]),
        ((3, 4, -1), ValueError, ["max_removable", ">= 0", "got -1"]),
        ((0, 4, 1), ValueError, ["n must be >= 1", "got 0"]),
        ((3, 4, 1.5), TypeError, ["max_removable", "integer or a hypothesis strategy", "1.5"]),
        ((3, True, 1), TypeError, ["p must be", "boolean True"]),
    ],
)
def test_sparse_observable_systems_refuse_bad_arguments(args, error, words):
    with pytest.raises(error) as info:
        sparse_observable_systems(*args)
    for word in words:
        assert word in str(info.value)


@given(marginally_stable_systems(SIZES, SIZES))
def test_marginally_stable_systems_have_an_exact_eigenvalue_at_one(system):
    n = system.n
    diagonal = np.diag(system.A)
    at_one = np.flatnonzero(diagonal == 1.0)
    assert at_one.size == 1
    j = int(at_one[0])
    e = np.eye(n)[j]
    assert np.array_equal((system.A - np.eye(n)) @ e, np.zeros(n))  # exact, not approximate
    others = np.delete(diagonal, j)
    assert np.all(np.abs(others) <= 0.9)
    moduli = np.sort(np.abs(np.linalg.eigvals(system.A)))[::-1]
    assert moduli[0] == pytest.approx(1.0, abs=1e-9)
    assert np.all(moduli[1:] < 1 - 0.05)
    assert observability(system).verdict.value == "holds"
    assert np.all(np.abs(system.C).max(axis=1) > 1e-3)


@pytest.mark.parametrize("kind", strategies.ATTACK_SHAPES)
def test_sparse_attacks_are_sparse_finite_and_bounded(kind):
    @given(st.data())
    def check(data):
        p = data.draw(st.integers(1, 6), label="p")
        s = data.draw(st.integers(0, p), label="s")
        a = data.draw(sparse_attacks(p, s, st.integers(1, 40), kinds=[kind], magnitude=(0.5, 2.0)))
        assert a.ndim == 2 and a.shape[1] == p and a.dtype == np.float64
        assert np.all(np.isfinite(a)) and np.abs(a).max(initial=0.0) <= 2.0
        assert np.all(np.count_nonzero(a, axis=1) <= s)
        if s == 0:
            assert not a.any()
        if kind == "constant":
            assert np.array_equal(a, np.broadcast_to(a[0], a.shape))
            assert (np.count_nonzero(a[0]) >= 1) == (s >= 1)
        if kind == "sinusoidal":
            assert np.count_nonzero(np.abs(a).sum(axis=0)) <= s  # one fixed support

    check()


def _attacked(a):
    """The sensors attacked at some step of the window."""
    return set(np.flatnonzero(np.abs(a).sum(axis=0)).tolist())


@given(st.data())
def test_sparse_attacks_default_to_one_attacked_set_over_the_window(data):
    # the certificates' threat model: one set of at most s sensors for the whole window
    p = data.draw(st.integers(1, 6), label="p")
    s = data.draw(st.integers(0, p), label="s")
    a = data.draw(sparse_attacks(p, s, st.integers(1, 40)), label="attack")
    assert len(_attacked(a)) <= s
    assert (len(_attacked(a)) >= 1) == (s >= 1)


def test_the_default_kinds_are_the_fixed_support_shapes():
    default = inspect.signature(sparse_attacks).parameters["kinds"].default
    assert default == strategies.FIXED_SUPPORT_SHAPES == ("constant", "sinusoidal")
    assert set(strategies.FIXED_SUPPORT_SHAPES) == set(strategies.ATTACK_SHAPES) - {"switching"}


def test_switching_attacks_change_their_support():
    def supports(a):
        return {tuple(np.flatnonzero(row)) for row in a}

    a = find(sparse_attacks(5, 2, 20, kinds=["switching"]), lambda a: len(supports(a)) >= 3)
    assert all(len(support) <= 2 for support in supports(a))
    # at most s = 2 per step, but more than s over the window: outside the certificates
    a = find(sparse_attacks(5, 2, 20, kinds=["switching"]), lambda a: len(_attacked(a)) > 2)
    assert len(_attacked(a)) > 2 and (np.count_nonzero(a, axis=1) <= 2).all()


def test_sparse_attacks_refuse_bad_arguments():
    with pytest.raises(ValueError, match=r"s must be between 0 and p = 3.*got 4"):
        sparse_attacks(3, 4, 10)
    with pytest.raises(
        ValueError,
        match=r"kinds must contain only constant, switching, "
        r"sinusoidal; got 'random'",
    ):
        sparse_attacks(3, 1, 10, kinds=["random"])
    with pytest.raises(ValueError, match="low <= high"):
        sparse_attacks(3, 1, 10, magnitude=(2.0, 1.0))


@given(
    observer_designs(
        observable_systems(st.integers(1, 4), st.integers(1, 4)), max_attacked=st.integers(0, 2)
    )
)
def test_observer_designs_are_valid_and_buildable(design):
    assert isinstance(design, Spec) and design.max_attacked in (0, 1, 2)
    observer = design.observer
    design_obj = build_observer(design.system, observer)  # no GainError
    n, p = design.system.n, design.system.p
    assert design_obj.L.shape[0] == n
    kind = observer["kind"]
    if kind != "luenberger":
        assert observer["step"] > 0
    if kind in ("sso", "dsso", "elastic_net"):
        assert 0.01 <= observer["threshold"] <= 0.5
    if kind == "elastic_net":
        assert 0.1 <= observer["shrink"] <= 0.95
    if kind == "sso":
        assert 1 <= observer["window"] <= n and 1 <= observer["inner_steps"] <= 3
    if not isinstance(observer.get("gain", "ogd"), str):
        assert np.asarray(observer["gain"]).shape == (n, p)
    assert [sc["name"] for sc in design.scenarios] == ["nominal"]


def test_observer_designs_draw_every_kind_and_gain():
    seen = set()

    @settings(max_examples=120)
    @given(observer_designs(UGV.system))
    def collect(design):
        gain = design.observer.get("gain", "")
        seen.add((design.observer["kind"], gain if isinstance(gain, str) else "matrix"))

    collect()
    kinds = {kind for kind, _ in seen}
    gains = {gain for _, gain in seen}
    assert kinds == {"luenberger", "ogd", "sso", "dsso", "elastic_net"}
    assert {"deadbeat", "place", "pinv", "matrix", "ogd"} <= gains


@given(observer_designs(System(np.eye(2), [[1.0, 0.0]]), kinds=["luenberger", "dsso"]))
def test_unobservable_plants_get_explicit_gains(design):
    # deadbeat, place and pinv need an observable plant; an explicit matrix is always valid
    assert not isinstance(design.observer["gain"], str)
    build_observer(design.system, design.observer)


def test_observer_designs_refuse_bad_arguments():
    with pytest.raises(TypeError, match="system must be a System or a hypothesis strategy"):
        observer_designs(np.eye(2))
    with pytest.raises(ValueError, match="kinds must contain only .*; got 'kalman'"):
        observer_designs(UGV.system, kinds=["kalman"])
    with pytest.raises(ValueError, match="max_attacked must be >= 0, got -1"):
        observer_designs(UGV.system, max_attacked=-1)


# ---------------------------------------------------------------------------
# assertions


def test_assert_observable():
    assert assert_observable(UGV.system).verdict.value == "holds"
    with pytest.raises(AssertionError) as info:
        assert_observable(System(np.eye(3), [[1.0, 0.0, 0.0]], name="blind"))
    message = str(info.value)
    assert "system 'blind' (n = 3, p = 1) is not observable" in message
    assert "2-dimensional unobservable subspace" in message
    assert "direction z = [0, 1, 0]" in message and "at eigenvalue 1" in message


def test_assert_observable_inconclusive_says_why():
    with pytest.raises(AssertionError) as info:
        assert_observable(System(np.diag([1.0, 1.0 + 1e-13]), [[1.0, 1.0]]))
    message = str(info.value)
    assert "could not be decided (inconclusive)" in message and "borderline" in message


def test_assert_sparse_observable_names_the_single_point_of_failure():
    assert assert_sparse_observable(UGV.system, 0).fields["max_removable"] == 0
    with pytest.raises(AssertionError) as info:
        assert_sparse_observable(UGV.system, 1)
    message = str(info.value)
    assert "system 'ugv' (n = 2, p = 3) is not 1-sparse observable" in message
    assert "max_removable = 0 < 2s = 2" in message
    assert "Breaking sensor set: position (index 0);" in message
    assert "Stealthy attack over 2 steps (verified by simulation)" in message
    assert "an attacker on position (index 0) makes x0 look exactly like x0 + z" in message
    assert "With z = [1, 0] (||z|| = 1) the largest |attack| entry is 1;" in message


def test_assert_sparse_observable_splits_a_larger_breaking_set():
    with pytest.raises(AssertionError) as info:
        assert_sparse_observable(load_example("notes-example-2").system, 1, horizon=4)
    message = str(info.value)
    assert "max_removable = 1 < 2s = 2" in message
    assert "Breaking sensor set: y1 (index 0), y3 (index 2)" in message
    assert "attack_a on y1 (index 0)" in message and "attack_b on y3 (index 2)" in message
    assert "the largest |entry| is 0.7071 in attack_a and 0.7071 in attack_b" in message
    assert "over 4 steps" in message


def test_assert_sparse_observable_on_an_unobservable_plant():
    with pytest.raises(AssertionError) as info:
        assert_sparse_observable(System(np.eye(2), [[1.0, 0.0], [1.0, 0.0]]), 0)
    message = str(info.value)
    assert "(A, C) itself is not observable" in message
    assert "no attack is needed: x0 and x0 + z give identical outputs for z = [0, 1]" in message


def test_assert_sparse_observable_inconclusive_gives_the_budget():
    # every sensor sees 4 of the 6 modes, so the enumeration cannot prune its search
    C = [[1.0 + i + j if (i + 2 * j) % 3 else 0.0 for j in range(6)] for i in range(12)]
    plant = System(np.diag(np.linspace(0.1, 0.9, 6)), C)
    assert assert_sparse_observable(plant, 2).fields["max_removable"] == 7
    with pytest.raises(AssertionError) as info:
        assert_sparse_observable(plant, 2, method="enumeration", max_sets=5)
    message = str(info.value)
    assert "2-sparse observability of system 'system' (n = 6, p = 12) could not be decided" in (
        message
    )
    assert "enumeration budget of 5 sets reached" in message and "max_sets=..." in message


def test_assert_deadbeat():
    plant = UGV.system
    L = deadbeat_gain(plant).L
    assert assert_deadbeat(plant.A, L, plant.C, rtol=1e-8) == 1
    with pytest.raises(AssertionError) as info:
        assert_deadbeat(plant.A, np.zeros((2, 3)), plant.C, rtol=1e-8)
    message = str(info.value)
    assert "A - L C is not nilpotent: ||F^2|| / ||A||^2 >= 0.7" in message
    assert "at the power k = n = 2" in message
    assert "needs <= 1e-08" in message
    with pytest.raises(AssertionError, match="L has the opposite sign convention"):
        assert_deadbeat(plant.A, -L, plant.C, rtol=1e-8)
    with pytest.raises(ValueError, match="L has the wrong number of rows: expected 2"):
        assert_deadbeat(plant.A, np.zeros((3, 3)), plant.C)
    with pytest.raises(ValueError, match="rtol must be a number in"):
        assert_deadbeat(plant.A, L, plant.C, rtol=0.0)
    # any real number type in (0, 1), not a bool
    assert assert_deadbeat(plant.A, L, plant.C, rtol=np.float32(1e-8)) == 1
    with pytest.raises(ValueError, match="rtol must be a number in"):
        assert_deadbeat(plant.A, L, plant.C, rtol=True)


def test_assert_deadbeat_is_exact_by_default():
    # F^2 = 1e-9 I exactly: never zero; nor small against F's own scale (in balanced units F
    # is 3.2e-5 times a rotation), so no tolerance accepts it either
    F = np.array([[0.0, 1.0], [1e-9, 0.0]])
    with pytest.raises(AssertionError) as info:
        assert_deadbeat(F, np.zeros((2, 1)), [[0.0, 0.0]])
    assert "no power of A - L C is exactly zero, nor zero to 1e-08" in str(info.value)
    with pytest.raises(AssertionError, match="A - L C is not nilpotent"):
        assert_deadbeat(F, np.zeros((2, 1)), [[0.0, 0.0]], rtol=1e-8)
    # F^2 = 2^-60 I against ||A|| = 1: nilpotent to the tolerance, and the message says so
    G = np.array([[0.0, 1.0], [2.0**-60, 0.0]])
    with pytest.raises(AssertionError) as info:
        assert_deadbeat(np.eye(2), np.eye(2) - G, np.eye(2))
    message = str(info.value)
    assert "no power F^k, k = 1..2, is exactly zero" in message
    assert "pass rtol=1e-08 to accept that" in message
    assert assert_deadbeat(np.eye(2), np.eye(2) - G, np.eye(2), rtol=1e-8) == 2
    # the printed float deadbeat gain of the UGV is deadbeat to rounding only
    with pytest.raises(AssertionError, match="nilpotent to the tolerance 1e-08"):
        assert_deadbeat(UGV.system.A, deadbeat_gain(UGV.system).L, UGV.system.C)
    # an exactly nilpotent error matrix passes with its exact index
    shift = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]])
    assert assert_deadbeat(shift, np.zeros((3, 1)), np.zeros((1, 3))) == 3
    A = np.array([[1.0, 1.0], [0.0, 1.0]])
    assert assert_deadbeat(A, [[2.0], [1.0]], [[1.0, 0.0]]) == 2
    # not nilpotent at all, exactly or to a tolerance
    with pytest.raises(AssertionError, match="nor zero to 1e-08"):
        assert_deadbeat(np.eye(2), np.zeros((2, 1)), np.zeros((1, 2)))


def test_assert_deadbeat_inconclusive_names_both_powers():
    # F^2 = 0 exactly, F itself tiny: the power test cannot tell nilpotent from small
    A = np.eye(2)
    F = np.array([[0.0, 1e-7], [0.0, 0.0]])
    C = np.eye(2)
    with pytest.raises(AssertionError) as info:
        assert_deadbeat(A, A - F, C, rtol=1e-8)
    message = str(info.value)
    assert "cannot conclude: ||F^2|| / ||A||^2 <= 0 <= 1e-08" in message
    assert "but ||F^1|| / ||A||^1 >= 7.07e-08 only, not clearly above it" in message


def test_assert_schur():
    assert assert_schur([[0.5, 1.0], [0.0, 0.2]]).verdict == "holds"
    with pytest.raises(AssertionError) as info:
        assert_schur(np.diag([0.5, -1.25]))
    message = str(info.value)
    assert "M is not Schur stable: eigenvalue -1.25 has modulus 1.25 >= 1" in message
    assert "(confirmed: an initial state along its eigenvector grows by a factor 2" in message
    with pytest.raises(AssertionError) as info:  # rho = 1 exactly: not asymptotically stable
        assert_schur([[0.0, -1.0], [1.0, 0.0]])
    message = str(info.value)
    assert "eigenvalue 0+1j has modulus 1 >= 1 (confirmed: in exact arithmetic" in message
    assert "|trace F^2| = n = 2 exactly" in message
    # rho = 1 - 2^-54 in exact arithmetic: ||M^2||_inf < 1 is decided in integers
    close = assert_schur([[0.0, 2.0**60], [np.nextafter(2.0**-60, 0.0), 0.0]])
    assert close.method == "exact powers" and 0 < close.margin < 1e-15
    assert close.decided_by is SchurCode.POWERS_STABLE and close.decision.facts["power"] == 2
    assert close.decision.facts["gap"] == pytest.approx(5.55e-17, rel=1e-3)
    with pytest.raises(AssertionError, match=r"eigenvalue 1\.000000001 has modulus 1\.000000001"):
        assert_schur([[1.0 + 1e-9]])  # enough digits to see the eigenvalue is not 1


def _luenberger_design(C, s):
    return spec_from_dict(
        {
            "name": "three-sensors",
            "system": {"A": [[0.5]], "C": C},
            "attack": {"max_attacked": s},
            "observer": {"kind": "luenberger", "gain": "deadbeat"},
        }
    )


def test_assert_certified():
    cert = assert_certified(_luenberger_design([[1.0], [1.0], [1.0]], 1))
    assert [c.id for c in cert.checks if c.required] == [
        "observability",
        "sparse_observability",
        "observer_gain",
        "observer_stability",
    ]
    with pytest.raises(AssertionError) as info:
        assert_certified(UGV)
    message = str(info.value)
    assert "design 'ugv'" in message and "2 of 4 required checks do not hold" in message
    assert "- sparse_observability FAILS:" in message
    assert "Breaking sensor set: position (index 0)" in message
    assert "- observer_stability inconclusive: No stability certificate" in message
    assert "observability FAILS" not in message.replace("sparse_observability", "")


def test_assert_certified_gives_the_growing_error_of_an_unstable_gain():
    design = spec_from_dict(
        {
            "name": "bad-gain",
            "system": {"A": [[0.5]], "C": [[1.0], [1.0]]},
            "attack": {"max_attacked": 0},
            "observer": {"kind": "luenberger", "gain": [[-1.0, 0.0]]},
        }
    )
    with pytest.raises(AssertionError) as info:
        assert_certified(design)
    message = str(info.value)
    assert "- observer_gain FAILS:" in message
    assert "eigenvalue 1.5 of modulus 1.5; initial error [1]; grows by a factor 2" in message


def test_assert_recovers():
    design = _luenberger_design([[1.0], [1.0], [1.0]], 0)
    result = assert_recovers(design, {"attack": "none", "steps": 5, "runs": 3}, 1e-12)
    assert result.runs == 3 and result.relative_error[-1].max() <= 1e-12
    with pytest.raises(AssertionError) as info:
        assert_recovers(UGV, "stealthy", 0.01, runs=8, steps=100)
    message = str(info.value)
    assert "the dsso observer of design 'ugv' does not recover under scenario 'stealthy'" in (
        message
    )
    assert "8 of 8 runs end with a relative state error above tol = 0.01 after 100 steps" in (
        message
    )
    worst = int(message.split("worst run: index ")[1].split(",")[0])
    final = float(message.split("final relative error ")[1].split(";")[0])
    mean = float(message.split("; mean ")[1].split(".\n")[0])
    assert 0 <= worst < 8 and final > 0.01 and 0.01 < mean <= final
    assert "attack 'stealthy'" in message and "seed 0, runs 8, steps 100" in message
    assert "numpy.random.default_rng([0, r])" in message


def test_assert_recovers_validates_the_scenario_as_the_loader_does():
    with pytest.raises(
        SpecError,
        match=r"scenario\[0\]\.sensorz': unknown key \(did you mean "
        r"'sensors'\?\)",
    ):
        assert_recovers(UGV, {"attack": "constant", "sensorz": [1]}, 0.1)
    with pytest.raises(
        SpecError,
        match=r"scenario\[0\]\.sensors': sensors\[0\] = 7 is out "
        r"of range: sensor indices are 0-based and must be < 3",
    ):
        assert_recovers(UGV, {"attack": "constant", "sensors": [7]}, 0.1)
    with pytest.raises(
        ValueError,
        match="'nope' is not a \\[\\[scenario\\]\\] of design 'ugv'; "
        "its scenarios: 'constant-velocity-a', 'stealthy'",
    ):
        assert_recovers(UGV, "nope", 0.1)
    with pytest.raises(TypeError, match="design must be a ssecert.Spec"):
        assert_recovers(UGV.system, "stealthy", 0.1)


def test_assertions_refuse_the_wrong_kind_of_input():
    with pytest.raises(TypeError, match=r"a design's plant is design.system"):
        assert_sparse_observable(UGV, 1)
    with pytest.raises(ValueError, match="s must be >= 0, got -1"):
        assert_sparse_observable(UGV.system, -1)


@pytest.mark.parametrize("name", ssecert.testing.__all__ + strategies.__all__)
def test_public_functions_are_documented_with_examples(name):
    module = ssecert.testing if name in ssecert.testing.__all__ else strategies
    obj = getattr(module, name)
    if not callable(obj):
        return
    doc = inspect.getdoc(obj) or ""
    assert ">>>" in doc, name
    for param in inspect.signature(obj).parameters:
        assert f"{param} :" in doc or f", {param}" in doc or f"{param}," in doc, (name, param)
    options = [p for p in inspect.signature(obj).parameters.values() if p.default is not p.empty]
    assert all(p.kind is p.KEYWORD_ONLY for p in options), name


# ---------------------------------------------------------------------------
# plugin


def test_example_fixture(ssecert_example):
    ugv = ssecert_example("ugv")
    assert isinstance(ugv, Spec) and ugv.observer["kind"] == "dsso"
    plant = ssecert_example("notes-example-0")
    assert isinstance(plant, System) and plant.name == "notes-example-0"
    assert ssecert_example("ugv") is ugv
    with pytest.raises(ValueError) as info:
        ssecert_example("ugv2")
    assert str(info.value) == (
        "no packaged ssecert example named 'ugv2'; available: " + ", ".join(list_examples())
    )


COUNTING = """
from hypothesis import given, strategies as st

@given(st.integers(0, 10**9))
def test_count(x):
    with open("drawn.txt", "a") as out:
        out.write(f"{x}\\n")
"""

# the same test marked as using ssecert; it also writes the settings it runs under
MARKED_COUNTING = """
import pytest
from hypothesis import given, settings, strategies as st

@pytest.mark.ssecert
@given(st.integers(0, 10**9))
def test_count(x):
    current = settings.default
    with open("drawn.txt", "a") as out:
        out.write(f"{x}\\n")
    with open("settings.txt", "w") as out:
        out.write(f"{current.verbosity.name} {current.deadline} {current.derandomize}")
"""


def _run(pytester, *args):
    """Run the counting file in-process as from a fresh process: its draws, result, and the
    hypothesis profile active after the run."""
    from hypothesis import settings as hypothesis_settings

    drawn = pytester.path / "drawn.txt"
    if drawn.exists():
        drawn.unlink()
    outer = hypothesis_settings.get_current_profile_name()
    hypothesis_settings.load_profile("default")  # what a fresh process starts from
    try:
        result = pytester.runpytest("-p", "no:cacheprovider", *args)
        after = hypothesis_settings.get_current_profile_name()
    finally:
        hypothesis_settings.load_profile(outer)
    values = drawn.read_text().split() if drawn.exists() else []
    return values, result, after


@pytest.mark.slow
def test_profiles_quick_for_ssecert_tests_and_thorough_on_demand(pytester):
    pytester.makepyfile(test_counting=MARKED_COUNTING)
    quick, result, after = _run(pytester)
    result.assert_outcomes(passed=1)
    result.stdout.fnmatch_lines(
        [
            "ssecert: hypothesis profile 'ssecert-quick' (for tests that use ssecert; "
            "hypothesis's own for the others)"
        ]
    )
    assert len(quick) == QUICK_EXAMPLES
    assert after == "default"  # restored: nothing leaks out of an in-process run
    again, _, _ = _run(pytester)
    assert again == quick  # derandomized: the same examples every run
    pytester.makepyfile(test_counting=COUNTING)  # not marked: --ssecert-profile reaches it too
    thorough, result, after = _run(pytester, "--ssecert-profile", "thorough")
    result.assert_outcomes(passed=1)
    result.stdout.fnmatch_lines(
        ["ssecert: hypothesis profile 'ssecert-thorough' (--ssecert-profile)"]
    )
    assert len(thorough) == THOROUGH_EXAMPLES
    assert after == "default"


def test_an_explicit_hypothesis_profile_is_respected(pytester):
    pytester.makepyfile(test_counting=MARKED_COUNTING)
    drawn, result, _ = _run(pytester, "--hypothesis-profile", "ci")
    result.assert_outcomes(passed=1)
    assert len(drawn) == 100  # hypothesis's own ci profile: 100 derandomized examples
    result.stdout.fnmatch_lines(["ssecert: hypothesis profile 'ci' (--hypothesis-profile ci)"])
    _, result, _ = _run(pytester, "--hypothesis-profile", "ci", "--ssecert-profile", "quick")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines(
        [
            "*--ssecert-profile quick and --hypothesis-profile ci both "
            "choose the hypothesis profile; give only one"
        ]
    )


def test_hypothesis_verbosity_keeps_the_ssecert_profile(pytester):
    pytester.makepyfile(test_counting=MARKED_COUNTING)
    drawn, result, after = _run(pytester, "--hypothesis-verbosity", "verbose")
    result.assert_outcomes(passed=1)
    assert len(drawn) == QUICK_EXAMPLES
    result.stdout.fnmatch_lines(
        ["ssecert: hypothesis profile 'ssecert-quick-with-verbose-verbosity' (for tests*"]
    )
    # the verbosity was kept, and so were the quick profile's settings
    assert (pytester.path / "settings.txt").read_text() == "verbose None True"
    assert after == "default-with-verbose-verbosity"  # what hypothesis's plugin had loaded
    drawn, result, after = _run(
        pytester, "--hypothesis-verbosity", "verbose", "--ssecert-profile", "quick"
    )
    assert len(drawn) == QUICK_EXAMPLES
    assert (pytester.path / "settings.txt").read_text() == "verbose None True"
    assert after == "default-with-verbose-verbosity"


@pytest.mark.slow
def test_ini_option_and_project_profiles(pytester):
    pytester.makepyfile(test_counting=COUNTING)
    pytester.makeini("[pytest]\nssecert_profile = thorough\n")
    drawn, _, _ = _run(pytester)
    assert len(drawn) == THOROUGH_EXAMPLES
    pytester.makeini("[pytest]\nssecert_profile = slow\n")
    _, result, _ = _run(pytester)
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines(["*ssecert_profile must be one of quick, thorough; got 'slow'"])
    pytester.makeini("[pytest]\n")
    pytester.makeconftest("""
        from hypothesis import settings
        settings.register_profile("ours", max_examples=7, deadline=None)
        settings.load_profile("ours")
    """)
    drawn, result, _ = _run(pytester)
    assert len(drawn) == 7  # a profile the project loaded itself is left alone
    result.stdout.fnmatch_lines(["*profile 'ours' (profile 'ours' loaded by the project)"])


def test_example_fixture_in_property_tests(pytester):
    pytester.makepyfile(
        test_fixture="""
        from hypothesis import given, strategies as st
        from ssecert import Spec

        @given(st.integers(0, 2))
        def test_fixture_is_session_scoped(ssecert_example, s):
            assert isinstance(ssecert_example("ugv"), Spec)

        def test_unknown(ssecert_example):
            ssecert_example("no-such-example")
    """
    )
    result = pytester.runpytest("-p", "no:cacheprovider")
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines(
        [
            "*ValueError: no packaged ssecert example named "
            "'no-such-example'; available: *lasso-example-1, *ugv"
        ]
    )


@pytest.mark.slow
def test_plugin_works_without_hypothesis(pytester):
    # packages that shadow hypothesis and fail to import, as an absent package does
    shadow = pytester.mkdir("no_hypothesis")
    for name in ("hypothesis", "_hypothesis_pytestplugin", "_hypothesis_globals"):
        (shadow / f"{name}.py").write_text(
            f'raise ModuleNotFoundError("No module named {name!r}", name={name!r})\n'
        )
    pytester.makepyfile(
        test_plain="""
        import sys
        from ssecert import Spec
        from ssecert.testing import assert_observable

        def test_fixture_and_assertions(ssecert_example):
            assert isinstance(ssecert_example("ugv"), Spec)
            assert_observable(ssecert_example("ugv").system)
            assert "hypothesis" not in sys.modules
    """
    )
    env = {k: v for k, v in os.environ.items() if k not in ("PYTEST_ADDOPTS",)}
    env["PYTHONPATH"] = str(shadow)
    command = [
        sys.executable,
        "-m",
        "pytest",
        "-p",
        "no:cacheprovider",
        "-p",
        "no:hypothesispytest",
    ]
    run = subprocess.run(
        [*command, "test_plain.py"],
        cwd=pytester.path,
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert "1 passed" in run.stdout and "ssecert: hypothesis profile" not in run.stdout
    run = subprocess.run(
        [*command, "--ssecert-profile", "thorough", "test_plain.py"],
        cwd=pytester.path,
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert run.returncode == pytest.ExitCode.USAGE_ERROR
    assert '--ssecert-profile needs hypothesis: pip install "ssecert[testing]"' in run.stderr


def test_profile_names_do_not_collide_with_common_ones():
    assert set(PROFILES.values()) == {"ssecert-quick", "ssecert-thorough"}


def test_assert_deadbeat_judges_the_gain_as_given():
    """The exact deadbeat gain of this plant is nilpotent; its float rounding is unstable."""
    A = 1e6 * np.roll(np.eye(3), 1, axis=0)
    L = [[388888.88888888893], [-277777.77777777775], [55555.555555555555]]
    with pytest.raises(AssertionError, match="not certified stable|not nilpotent") as info:
        assert_deadbeat(A, L, [[1.0, 2.0, 3.0]])
    assert "certified between" in str(info.value)
