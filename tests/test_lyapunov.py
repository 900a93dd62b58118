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


def test_rounding_above_one_is_not_called_unstable():
    """A 12 x 12 Jordan block at 0.95 in a rotated basis: computed eigenvalues reach 1.0019,
    the exact ones stay below 0.999; the witness decays, so the verdict is not 'fails'."""
    rng = np.random.default_rng(0)
    J = 0.95 * np.eye(12) + np.diag(np.ones(11), 1)
    Q, _ = np.linalg.qr(rng.standard_normal((12, 12)))
    cert = lyapunov_certificate(Q @ J @ Q.T)
    assert cert.verdict != "fails"
