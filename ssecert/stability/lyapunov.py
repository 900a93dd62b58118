"""Discrete Lyapunov certificates for linear error dynamics e(k+1) = F e(k).

``control.dlyap(A, Q)`` solves A X A^T - X + Q = 0, so F^T is passed to get
F^T P F - P + Q = 0.  It returns an indefinite X for an unstable F without
complaint, so nothing is taken on trust: the certificate holds only when
the recomputed P - F^T P F and P itself are positive definite by Cholesky
with a margin above a floating-point error bound.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validation import as_real_matrix
from ..tolerances import EPS

__all__ = ["LyapunovCertificate", "lyapunov_certificate", "instability_witness"]


@dataclass(frozen=True)
class LyapunovCertificate:
    """Outcome of ``lyapunov_certificate``.

    Attributes
    ----------
    verdict : str
        ``"holds"`` (F is Schur, proven by P), ``"fails"`` (an eigenvalue of
        modulus >= 1, with a growing trajectory as witness) or
        ``"inconclusive"``.
    P : ndarray or None
        Symmetric solution of F^T P F - P + Q = 0.
    decrease : ndarray or None
        The recomputed P - F^T P F.
    margin : float or None
        Smallest eigenvalue of the recomputed decrease, relative to
        ``||P||``; the certificate holds when it beats ``error_bound``.
    error_bound : float
        Floating-point error bound on that eigenvalue, also relative.
    contraction : float or None
        Factor c < 1 with V(e+) <= c^2 V(e), V = e^T P e: the error decays at
        least like c^k in the P-norm.
    condition : float or None
        Condition number of P.
    residual : float or None
        ||F^T P F - P + Q|| / ||Q||.
    spectral_radius : float
        Of F (reported, not used to decide).
    reason : str
    witness : dict or None
    """

    verdict: str
    P: np.ndarray | None
    decrease: np.ndarray | None
    margin: float | None
    error_bound: float
    contraction: float | None
    condition: float | None
    residual: float | None
    spectral_radius: float
    reason: str = ""
    witness: dict[str, Any] | None = field(default=None)


def instability_witness(F: np.ndarray, *, steps: int = 2000) -> dict[str, Any] | None:
    """A real initial error that does not decay under F, when the computed spectral
    radius is at least 1 - 1e-12, with how far that is verified.

    The trajectory is simulated with renormalisation (log-norms, so nothing
    overflows).  ``verified`` is True when the error grows by a factor 2
    within ``steps``, or when the dominant eigenvalue exceeds 1 by more than
    its first-order error bound n eps ||F|| kappa; rounding alone can put a
    stable eigenvalue above 1 (a defective one especially), so nothing less
    counts as proof.
    """
    import scipy.linalg

    n = F.shape[0]
    lam, vl, vr = scipy.linalg.eig(F, left=True, right=True)
    j = int(np.argmax(np.abs(lam)))
    if abs(lam[j]) < 1 - 1e-12:
        return None
    v = vr[:, j]
    z = v.real if np.linalg.norm(v.real) >= np.linalg.norm(v.imag) else v.imag
    z = np.real(z) / np.linalg.norm(z)
    y = vl[:, j] / np.linalg.norm(vl[:, j])
    dot = abs(np.vdot(y, vr[:, j] / np.linalg.norm(vr[:, j])))
    kappa = 1.0 / dot if dot > 0 else np.inf
    bound = n * EPS * float(np.linalg.norm(F, 2)) * kappa
    log_norms = [0.0]
    w = z.copy()
    total = 0.0
    for _ in range(steps):
        w = F @ w
        size = float(np.linalg.norm(w))
        if size == 0.0 or not np.isfinite(size):
            break
        total += np.log(size)
        w /= size
        log_norms.append(total)
        if total >= np.log(2.0):
            break
    grows = max(log_norms) >= np.log(2.0)
    clear = abs(lam[j]) - bound > 1 + 1e-9
    return {
        "eigenvalue": complex(lam[j]),
        "eigenvalue_error_bound": float(bound),
        "initial_error": z,
        "log_norms": log_norms[:: max(1, len(log_norms) // 200)],
        "grows_by_factor_2": bool(grows),
        "verified": bool(grows or clear),
    }


def lyapunov_certificate(
    F: np.ndarray, Q: np.ndarray | None = None, *, clear: float = 100.0
) -> LyapunovCertificate:
    """Certify that e(k+1) = F e(k) is asymptotically stable, or show it is not.

    Parameters
    ----------
    F : ndarray, shape (n, n)
    Q : ndarray, shape (n, n), optional
        Positive definite right-hand side (default identity); symmetrised.
    clear : float, default 100
        The decrease must exceed ``clear`` times the error bound.

    Returns
    -------
    LyapunovCertificate

    Examples
    --------
    >>> import numpy as np
    >>> cert = lyapunov_certificate(np.array([[0.5, 1.0], [0.0, 0.2]]))
    >>> cert.verdict, cert.contraction < 1
    ('holds', True)
    >>> lyapunov_certificate(np.array([[1.1]])).verdict
    'fails'
    """
    import control

    F = np.asarray(as_real_matrix(F, "F"), dtype=float)
    n = F.shape[0]
    Q = np.eye(n) if Q is None else np.asarray(as_real_matrix(Q, "Q", shape=(n, n)))
    Q = 0.5 * (Q + Q.T)
    rho = float(np.abs(np.linalg.eigvals(F)).max()) if n else 0.0
    normF = float(np.linalg.norm(F, 2))
    witness = None
    try:
        P = np.asarray(control.dlyap(F.T, Q), dtype=float)
    except Exception as exc:  # singular Lyapunov operator (lambda_i lambda_j = 1)
        witness = instability_witness(F)
        verdict = "fails" if witness is not None and witness["verified"] else "inconclusive"
        return LyapunovCertificate(verdict, None, None, None, 0.0, None, None, None, rho,
                                   f"the Lyapunov equation has no unique solution ({exc})",
                                   witness)
    P = 0.5 * (P + P.T)
    normP = max(float(np.linalg.norm(P, 2)), np.finfo(float).tiny)
    residual = float(np.linalg.norm(F.T @ P @ F - P + Q, 2)) / max(float(np.linalg.norm(Q, 2)),
                                                                      np.finfo(float).tiny)
    decrease = P - F.T @ P @ F
    decrease = 0.5 * (decrease + decrease.T)
    # rounding in forming F^T P F and in eigvalsh, relative to ||P||
    bound = 10 * n * EPS * (normF**2 + 1.0)
    dec_min = float(np.linalg.eigvalsh(decrease)[0]) / normP if n else 1.0
    p_eigs = np.linalg.eigvalsh(P)
    p_min = float(p_eigs[0]) / normP
    condition = float(p_eigs[-1] / p_eigs[0]) if p_eigs[0] > 0 else np.inf
    if dec_min > clear * bound and p_min > clear * bound:
        try:
            np.linalg.cholesky(P - 0.5 * p_min * normP * np.eye(n))
            np.linalg.cholesky(decrease - 0.5 * dec_min * normP * np.eye(n))
        except np.linalg.LinAlgError:
            pass
        else:
            contraction = float(np.sqrt(max(0.0, 1.0 - dec_min * normP / p_eigs[-1])))
            return LyapunovCertificate("holds", P, decrease, dec_min, bound, contraction,
                                       condition, residual, rho)
    witness = instability_witness(F)
    margin = min(dec_min, p_min)  # negative when P or the decrease is indefinite
    if witness is not None and witness["verified"]:
        how = ("an initial error along its eigenvector grows by a factor 2 in simulation"
               if witness["grows_by_factor_2"] else
               f"the eigenvalue exceeds 1 by more than its error bound "
               f"{witness['eigenvalue_error_bound']:.1e}")
        return LyapunovCertificate("fails", P, decrease, margin, bound, None, condition,
                                   residual, rho,
                                   f"F has an eigenvalue of modulus {rho:.6g} >= 1 ({how})",
                                   witness)
    if witness is not None:
        return LyapunovCertificate(
            "inconclusive", P, decrease, margin, bound, None, condition, residual, rho,
            f"the computed spectral radius of F is {rho:.12g}, but neither growth nor an "
            f"eigenvalue clear of its error bound {witness['eigenvalue_error_bound']:.1e} "
            f"confirms instability", witness)
    return LyapunovCertificate(
        "inconclusive", P, decrease, margin, bound, None, condition, residual, rho,
        f"the Lyapunov solution cannot be verified with a margin (smallest decrease "
        f"{dec_min:.2e}, smallest eigenvalue of P {p_min:.2e}, error bound {bound:.2e})")
