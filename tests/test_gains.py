"""Observer gains: deadbeat (float and exact), placement with re-check, OGD, pinv."""

import types
import warnings
from fractions import Fraction

import control
import numpy as np
import pytest
import scipy.signal
import sympy as sp
from planted import planted

from ssecert import System
from ssecert.design.gains import (
    GainError,
    deadbeat_gain,
    exact_deadbeat_gain,
    nilpotency,
    ogd_gain,
    pinv_gain,
    place_gain,
)
from ssecert.structure.observability import observability_index


@pytest.mark.parametrize("seed", range(60))
def test_deadbeat_is_nilpotent_with_minimal_index(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 13))
    p = int(rng.integers(1, n))  # p < n: control.place cannot do this
    system = System(rng.standard_normal((n, n)), rng.standard_normal((p, n)))
    gain = deadbeat_gain(system)
    index = observability_index(system)
    F = system.A - gain.L @ system.C
    power = np.linalg.matrix_power(F, index)
    scale = max(1.0, np.linalg.norm(system.A, 2))
    assert np.linalg.norm(power, 2) <= 1e-8 * scale**index
    assert np.linalg.norm(np.linalg.matrix_power(F, index - 1), 2) > 1e-6 * scale ** (index - 1)
    assert gain.verified and gain.details["nilpotency_index"] == index
    assert gain.details["minimal"]


def test_control_place_refuses_what_deadbeat_does():
    rng = np.random.default_rng(4)
    A, C = rng.standard_normal((6, 6)), rng.standard_normal((2, 6))
    with pytest.raises(Exception, match="repeated"):
        control.place(A.T, C.T, np.zeros(6))
    assert deadbeat_gain(System(A, C)).details["nilpotency_index"] == 3


def test_eigenvalues_cannot_prove_nilpotency():
    rng = np.random.default_rng(2)
    system = System(rng.standard_normal((15, 15)), rng.standard_normal((1, 15)))
    gain = deadbeat_gain(system)
    assert gain.verified and gain.details["nilpotency_index"] == 15
    assert np.abs(np.linalg.eigvals(gain.error_matrix)).max() > 1e-3  # far from 0


def _observable_planted(seed):
    for attempt in range(100):
        pl = planted(np.random.default_rng(1000 * seed + attempt), "jordan", integer=True)
        if pl.max_removable >= 0:
            return pl
    raise AssertionError("no observable plant generated")


@pytest.mark.parametrize("seed", range(10))
def test_exact_deadbeat_on_integer_plants(seed):
    pl = _observable_planted(seed)
    A = np.round(pl.A).astype(int).tolist()
    C = np.round(pl.C).astype(int).tolist()
    gain = exact_deadbeat_gain(A, C)
    assert gain.verified
    # independent exact re-check with sympy
    Le = sp.Matrix([[sp.Rational(x) for x in row] for row in gain.details["L_exact"]])
    F = sp.Matrix(A) - Le * sp.Matrix(C)
    k = gain.details["exact_index"]
    assert (F**k).is_zero_matrix
    assert k == 1 or not (F ** (k - 1)).is_zero_matrix
    assert k == observability_index(System(pl.A, pl.C))


def test_exact_deadbeat_single_output_chain():
    gain = exact_deadbeat_gain([[0, 1, 0], [0, 0, 1], [1, 2, 3]], [[1, 0, 0]])
    assert gain.details["exact_index"] == 3


def test_deadbeat_refuses_unobservable_plant():
    with pytest.raises(GainError, match="not observable"):
        deadbeat_gain(System(np.diag([0.5, 0.9]), [[1.0, 0.0]]))


def test_nilpotency_test_follows_design_rule():
    assert nilpotency(np.diag([1.0, 1.0, 1.0], 1)).index == 4
    assert nilpotency(np.array([[0.5]])).index is None
    # ||F|| = 1e-7 is above its threshold 1e-8 but not clearly (100 times): inconclusive
    result = nilpotency(np.array([[0.0, 1e-7], [0.0, 0.0]]), scale=1.0)
    assert result.index == 2 and not result.conclusive
    assert nilpotency(np.array([[0.0, 1e-3], [0.0, 0.0]]), scale=1.0).conclusive


def test_place_gain_is_rechecked():
    system = System([[1.0, 0.1], [0.0, 1.0]], [[1.0, 0.0]])
    gain = place_gain(system, [0.2, 0.3])
    assert np.allclose(sorted(np.linalg.eigvals(gain.error_matrix).real), [0.2, 0.3])


def test_place_miss_is_an_error(monkeypatch):
    system = System([[1.0, 0.1], [0.0, 1.0]], [[1.0, 0.0]])

    def bad_place(A, B, poles, method):
        warnings.warn("convergence not reached", stacklevel=2)
        return types.SimpleNamespace(gain_matrix=np.array([[0.0, 0.0]]))

    monkeypatch.setattr(scipy.signal, "place_poles", bad_place)
    with pytest.raises(GainError, match="miss"):
        place_gain(system, [0.2, 0.3])


def test_place_refusal_is_an_error():
    with pytest.raises(GainError, match="refused"):
        place_gain(System(np.eye(2), [[1.0, 0.0]]), [0.1, 0.1])


def test_ogd_and_pinv_gains():
    system = System([[0.5, 1.0], [0.0, 0.5]], [[1, 0], [0, 1], [1, 1]])
    g = ogd_gain(system, 0.1)
    np.testing.assert_allclose(g.L, 0.1 * system.A @ system.C.T)
    p = pinv_gain(system)
    np.testing.assert_allclose(p.error_matrix, 0.0, atol=1e-12)
    with pytest.raises(GainError, match="full column rank"):
        pinv_gain(System(np.eye(2), [[1.0, 0.0]]))


def test_place_with_dependent_sensor_rows():
    """Two sensors read the same combination: place on one, zero gain on the other."""
    system = System([[0.5, 1.0], [0.0, 0.9]], [[1.0, 0.5], [2.0, 1.0]])
    gain = place_gain(system, [0.1, 0.2])
    assert gain.verified and len(gain.details["sensors_used"]) == 1
    np.testing.assert_allclose(
        sorted(np.linalg.eigvals(gain.error_matrix).real), [0.1, 0.2], atol=1e-10
    )


@pytest.mark.parametrize("seed", range(8))
def test_place_gain_is_control_place_on_the_dual_pair(seed):
    """place_gain calls SciPy's Tits-Yang placement directly (python-control is not imported
    for it): on the independent sensors it uses, it returns control.place's gain, bit for bit."""
    rng = np.random.default_rng(seed)
    n, p = int(rng.integers(2, 6)), int(rng.integers(1, 4))
    system = System(rng.standard_normal((n, n)), rng.standard_normal((p, n)))
    poles = np.linspace(-0.5, 0.5, n).astype(complex)
    gain = place_gain(system, poles)
    rows = gain.details["sensors_used"]
    expected = np.zeros((n, p))
    expected[:, rows] = np.asarray(control.place(system.A.T, system.C[rows].T, poles)).T
    assert np.array_equal(gain.L, expected)


@pytest.mark.parametrize("seed", range(8))
def test_lyapunov_solution_is_control_dlyap(seed):
    """The Lyapunov certificate's P is what control.dlyap returns without Slycot."""
    from ssecert.stability.lyapunov import _lyapunov_solution
    from ssecert.stability.outcomes import LyapunovCode

    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 7))
    F = rng.standard_normal((n, n))
    F *= 0.9 / max(np.abs(np.linalg.eigvals(F)).max(), 1e-12)
    P, code, _ = _lyapunov_solution(F, np.eye(n))
    assert code is LyapunovCode.VERIFIED
    assert np.allclose(P, control.dlyap(F.T, np.eye(n)), rtol=1e-12, atol=1e-12)
    assert np.allclose(F.T @ P @ F - P + np.eye(n), 0, atol=1e-9 * np.abs(P).max())


def test_the_deadbeat_tests_say_why_from_their_numbers():
    from ssecert.design import deadbeat_messages
    from ssecert.design.deadbeat import verify_deadbeat

    # a nilpotent shift is verified and says nothing; F = 2 is proved unstable
    shift = verify_deadbeat(np.array([[0.0, 1.0], [0.0, 0.0]]), np.zeros((2, 1)), np.ones((1, 2)))
    assert shift.verified and shift.reason == ""
    unstable = verify_deadbeat(np.array([[2.0]]), np.zeros((1, 1)), np.ones((1, 1)))
    assert not unstable.verified and unstable.index is None
    assert unstable.radius_lower > 1 or unstable.radius_excess > 0
    unstable_words = deadbeat_messages.deadbeat_reason(
        index=None, conclusive=False, relative=(1.0,), rtol=1e-8, complete=True,
        radius_upper=2.0, radius_lower=2.0, radius_excess=0.5,
    )  # fmt: skip
    assert "the printed gain is unstable" in unstable_words
    words = deadbeat_messages.deadbeat_reason(
        index=None, conclusive=False, relative=(0.5, 0.25), rtol=1e-8, complete=False,
        radius_upper=1.0, radius_lower=0.5, radius_excess=0.0,
    )  # fmt: skip
    assert "up to k = 2 (smallest 2.50e-01); the exact powers stopped" in words
    assert "not certified below 1" in words
    unclear = deadbeat_messages.deadbeat_reason(
        index=2, conclusive=False, relative=(3e-8, 1e-9), rtol=1e-8, complete=True,
        radius_upper=0.5, radius_lower=0.0, radius_excess=0.0,
    )  # fmt: skip
    assert unclear == "||F^1|| / ||A||^1 = 3.00e-08 is not clearly above 1e-08"
    assert deadbeat_messages.nilpotency_reason(2, (1e-6, 1e-9), 1e-8, 1.0, True) == ""
    assert "exceeds 1e-08" in deadbeat_messages.nilpotency_reason(None, (1.0,), 1e-8, 1.0, True)
    assert "1.00e-06 is not clearly" in deadbeat_messages.nilpotency_reason(
        2, (1e-6, 1e-9), 1e-8, 1.0, False
    )


def _random_rational_matrix(rng, rows, cols):
    """Small integers and halves, often rank-deficient (a repeated or zero row)."""
    M = rng.integers(-3, 4, (rows, cols)) / rng.choice([1, 2], (rows, cols))
    if rows > 1 and rng.random() < 0.5:
        M[-1] = M[0] if rng.random() < 0.5 else 0.0
    return M


@pytest.mark.parametrize("seed", range(6))
def test_exact_linear_algebra_matches_sympy(seed):
    # the exact deadbeat construction reads its bases off reduced row echelon forms (unique):
    # each helper gives sympy's answer, so the construction gives sympy's gain
    from fractions import Fraction

    from ssecert.numerics import rational as rq

    rng = np.random.default_rng(seed)
    for _ in range(8):
        rows, cols = (int(v) for v in rng.integers(1, 6, 2))
        M = _random_rational_matrix(rng, rows, cols)
        Mq = rq.fractions(M)
        S = sp.Matrix([[sp.Rational(Fraction(float(v))) for v in row] for row in M])
        R, pivots = rq.rref(Mq)
        SR, Spivots = S.rref()
        assert pivots == list(Spivots)
        assert [[sp.Rational(x) for x in row] for row in R] == SR.tolist()
        assert rq.rank(Mq) == S.rank()
        expected = [[sp.Rational(x) for x in v] for v in rq.nullspace(Mq, columns=cols)]
        assert expected == [list(v) for v in S.nullspace()]
        b = list(S * sp.Matrix(rng.integers(-2, 3, cols)))
        x = rq.particular_solution(Mq, [Fraction(int(v.p), int(v.q)) for v in b])
        sol, params = S.gauss_jordan_solve(sp.Matrix(b))
        assert [sp.Rational(v) for v in x] == list(sol.subs(dict.fromkeys(params, 0)))
        Y = sp.Matrix(rng.integers(-2, 3, (rows, 2)))
        mn = rq.minimum_norm_solution(
            Mq, [[Fraction(int(v)) for v in row] for row in Y.tolist()], cols
        )
        assert [[sp.Rational(v) for v in row] for row in mn] == (
            (S.T * S).pinv() * S.T * Y
        ).tolist()
        if rows == cols:
            inv = rq.inverse(Mq)
            assert (inv is None) == (S.det() == 0)
            if inv is not None:
                assert [[sp.Rational(v) for v in row] for row in inv] == S.inv().tolist()


@pytest.mark.parametrize(
    ("A", "C", "field"),
    [
        ([[1, 1], [0, 1]], [[1, 0, 5]], "C must have rows of 2"),
        ([[1, 1, 0], [0, 1, 1]], [[1, 0, 0]], "A must be square"),
        ([[1, 0], [0, 1]], [[1, 0], [1]], "C must have rows of 2"),
        ([[float("nan")]], [[1]], "A must be finite"),
        ([[1]], [["x"]], "C must hold rational numbers"),
    ],
)
def test_exact_deadbeat_refuses_bad_shapes_and_entries_by_name(A, C, field):
    with pytest.raises(ValueError, match=field):
        exact_deadbeat_gain(A, C)


def test_exact_deadbeat_gain_beyond_the_floats_is_infinite_not_an_error():
    # the exact gain 1e400 exists; its float is inf, the exact index still 1
    gain = exact_deadbeat_gain([[1e200]], [[1e-200]])
    assert gain.L[0, 0] == np.inf and gain.details["exact_index"] == 1
    assert gain.details["L_exact"] == [[str(Fraction(1e200) / Fraction(1e-200))]]


@pytest.mark.parametrize("gain", ["pinv", "place"])
def test_gains_of_states_in_units_far_apart(gain):
    # the same plant with its states in units 2^30 and 2^-30: C's singular values mix the
    # units (the pseudo-inverse read rank(C) = 1 < 2, the placement refused); computed in the
    # balanced units, the gain is the plant's own, S L (A - L C similar to the plant's)
    A = np.array([[0.98, 0.1], [-0.2, 0.9]])
    C = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    t = np.array([2.0**30, 2.0**-30])
    far = System(A * t[:, None] / t[None, :], C / t[None, :])
    if gain == "pinv":
        base, got = pinv_gain(System(A, C)), pinv_gain(far)
    else:
        base, got = place_gain(System(A, C), [0.5, 0.4]), place_gain(far, [0.5, 0.4])
        assert np.sort(np.abs(np.linalg.eigvals(got.error_matrix))) == pytest.approx([0.4, 0.5])
    assert np.allclose(got.L / t[:, None], base.L, rtol=1e-9, atol=1e-12)
    assert np.ptp(np.log2(got.details["state_scaling"])) >= 16
    assert "state_scaling" not in base.details
