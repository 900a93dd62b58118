"""Lyapunov certificates of linear error dynamics."""

import numpy as np
import pytest

from ssecert.stability.lyapunov import lyapunov_certificate


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("radius", [0.3, 0.9, 0.999])
def test_stable_matrices_are_certified_with_a_residual_identity(seed, radius):
    rng = np.random.default_rng(seed)
    F = rng.standard_normal((6, 6))
    F *= radius / np.abs(np.linalg.eigvals(F)).max()
    cert = lyapunov_certificate(F)
    assert cert.verdict == "holds"
    P = cert.P
    np.testing.assert_allclose(P, P.T)
    assert np.linalg.norm(F.T @ P @ F - P + np.eye(6)) <= 1e-8 * np.linalg.norm(P)
    # the contraction bounds every trajectory in the P-norm
    e = rng.standard_normal((6, 20))
    for _ in range(30):
        e_next = F @ e
        v, v_next = np.sum(e * (P @ e), 0), np.sum(e_next * (P @ e_next), 0)
        assert np.all(v_next <= cert.contraction**2 * v * (1 + 1e-9))
        e = e_next


def test_unstable_matrix_fails_with_a_growing_witness():
    F = np.array([[1.2, 1.0], [0.0, 0.5]])
    cert = lyapunov_certificate(F)
    assert cert.verdict == "fails"
    assert cert.witness["grows_by_factor_2"] and cert.witness["log_norms"][-1] >= np.log(2)


def test_marginal_matrix_is_not_certified():
    cert = lyapunov_certificate(np.array([[1.0, 0.0], [0.0, 0.5]]))
    assert cert.verdict in ("fails", "inconclusive")
    assert cert.verdict != "holds"


def test_nilpotent_matrix_is_certified():
    cert = lyapunov_certificate(np.diag(np.ones(9), 1))
    assert cert.verdict == "holds" and cert.spectral_radius < 1e-12


def test_custom_q_is_symmetrised():
    F = np.array([[0.5, 0.1], [0.0, 0.4]])
    cert = lyapunov_certificate(F, Q=np.array([[2.0, 1.0], [0.0, 2.0]]))
    Qs = np.array([[2.0, 0.5], [0.5, 2.0]])
    assert np.allclose(F.T @ cert.P @ F - cert.P + Qs, 0, atol=1e-10)


@pytest.mark.slow
def test_rounding_above_one_is_not_called_unstable():
    """A 12 x 12 Jordan block at 0.95 in a rotated basis: computed eigenvalues reach 1.0019,
    the exact ones stay below 0.999; the witness decays, so the verdict is not 'fails'."""
    rng = np.random.default_rng(0)
    J = 0.95 * np.eye(12) + np.diag(np.ones(11), 1)
    Q, _ = np.linalg.qr(rng.standard_normal((12, 12)))
    cert = lyapunov_certificate(Q @ J @ Q.T)
    assert cert.verdict != "fails"


@pytest.mark.parametrize("k", [700, 900])
def test_a_lyapunov_matrix_for_states_2_to_the_900_apart_is_written_in_the_users_units(k):
    # F = [[0.5, 2^k], [0, 0.7]] (a triangular matrix in units 2^k apart, radius 0.7): P was
    # solved in balanced coordinates, but S^-1 P_b S^-1 has entries 2^-1202 there (underflow)
    # and the certificate was dropped; a positive multiple of it centres its entries
    from fractions import Fraction

    F = np.array([[0.5, 2.0**k], [0.0, 0.7]])
    cert = lyapunov_certificate(F)
    assert cert.verdict.value == "holds"
    P = cert.P
    assert np.all(np.isfinite(P)) and P[0, 0] > 0
    # P > 0 and P - F'PF > 0, in exact arithmetic on the printed floats
    Pq = [[Fraction(x) for x in row] for row in P.tolist()]
    Fq = [[Fraction(x) for x in row] for row in F.tolist()]
    FtPF = [[sum(Fq[a][i] * Pq[a][b] * Fq[b][j] for a in range(2) for b in range(2))
             for j in range(2)] for i in range(2)]  # fmt: skip
    D = [[Pq[i][j] - FtPF[i][j] for j in range(2)] for i in range(2)]
    for M in (Pq, D):
        assert M[0][0] > 0 and M[0][0] * M[1][1] - M[0][1] * M[1][0] > 0
