"""The Schur-Cohn test on the exact characteristic polynomial (``ssecert.numerics.schur_cohn``),
against numpy's eigenvalues where the spectral radius is far from 1, and on matrices whose
exact eigenvalues are known by construction where it is within a hair of 1."""

import numpy as np
import pytest

from ssecert.numerics.exact_powers import ExactMatrix, dyadic
from ssecert.numerics.schur_cohn import characteristic_polynomial, radius_below, schur_stable
from ssecert.stability.outcomes import SchurCode, SchurState
from ssecert.stability.spectral import schur_decision


def _hidden_triangular(diagonal, seed):
    """An upper-triangular matrix with the given diagonal (its exact eigenvalues) and random
    entries above it, its rows and columns permuted alike (exactly)."""
    rng = np.random.default_rng(seed)
    n = len(diagonal)
    T = np.triu(rng.standard_normal((n, n)), 1) + np.diag(diagonal)
    order = rng.permutation(n)
    return T[np.ix_(order, order)]


@pytest.mark.parametrize("seed", range(40))
def test_it_agrees_with_numpy_where_the_radius_is_far_from_one(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 13))
    F = rng.standard_normal((n, n)) / np.sqrt(n) * rng.uniform(0.5, 1.5)
    rho = float(np.max(np.abs(np.linalg.eigvals(F))))
    if abs(rho - 1.0) < 1e-6:
        pytest.skip("too close to 1 for numpy to be the reference")
    assert schur_stable(characteristic_polynomial(dyadic(F))) is (rho < 1.0)


@pytest.mark.parametrize(
    ("largest", "stable"),
    [
        (1.0 - 2.0**-52, True),
        (-(1.0 - 2.0**-53), True),
        (1.0, False),
        (-1.0, False),
        (1.0 + 2.0**-52, False),
    ],
)
def test_eigenvalues_within_an_ulp_of_one_are_told_apart(largest, stable):
    F = _hidden_triangular([largest, 0.5, -0.75, 0.0, 0.25], seed=3)
    assert schur_stable(characteristic_polynomial(dyadic(F))) is stable


def test_the_radius_test_is_strict_at_the_exact_radius():
    # rho = 1 - 2^-40 exactly: below 1 - 2^-41, not below 1 - 2^-40 nor 1 - 2^-39
    coefficients = characteristic_polynomial(dyadic(_hidden_triangular([1 - 2.0**-40, 0.5], 1)))
    assert radius_below(coefficients, 41) is True
    assert radius_below(coefficients, 40) is False
    assert radius_below(coefficients, 39) is False
    with pytest.raises(ValueError, match="j >= 1"):
        radius_below(coefficients, 0)


def test_the_exact_error_matrix_decides_a_knife_edge():
    # A = diag(1.1, 0.5), L = 0.1 I, C = I: the floats of 1.1 and 0.1 leave the exact
    # eigenvalue 1 + 8.3e-17 > 1, which neither powers nor traces nor the first-order bound
    # resolve
    A, L, C = np.diag([1.1, 0.5]), 0.1 * np.eye(2), np.eye(2)
    exact = ExactMatrix.error_matrix(A, L, C).value
    assert schur_stable(characteristic_polynomial(exact)) is False
    decision = schur_decision(A - L @ C, parts=(A, L, C))
    assert decision.code is SchurCode.SCHUR_COHN_FAILS and decision.rigorous
    assert decision.state is SchurState.UNSTABLE and decision.radius_lower == 1.0
    # and 1 - 2^-52 on the diagonal instead of 1.1: stable, with a radius bound below 1
    A = np.diag([1.0 - 2.0**-52, 0.5]) + np.triu(np.full((2, 2), 2.0**30), 1)
    decision = schur_decision(A - L @ C, parts=(A, L, C))
    assert decision.state is SchurState.STABLE and decision.radius_upper < 1.0


def test_small_and_invalid_polynomials():
    assert schur_stable([5]) is True  # no roots
    assert schur_stable([1, 2]) is True and schur_stable([2, 1]) is False  # roots -1/2, -2
    with pytest.raises(ValueError, match="nonzero leading"):
        schur_stable([1, 0])
    big = characteristic_polynomial(dyadic(_hidden_triangular([0.5, 0.25, 0.125, -0.5], 2)))
    assert schur_stable(big, max_bits=8) is None  # beyond the budget: undecided
    assert schur_stable(big) is True


def test_the_characteristic_polynomial_is_checked_independently():
    from ssecert.numerics.schur_cohn import _cayley_hamilton

    F = dyadic(_hidden_triangular([1 - 2.0**-52, 0.5, -0.75], 4))
    c = [1, *[0] * 3]
    assert not _cayley_hamilton(F, c)  # z^3 does not annihilate it
    a = characteristic_polynomial(F)  # (checked inside: it would raise otherwise)
    assert schur_stable(a) is True
