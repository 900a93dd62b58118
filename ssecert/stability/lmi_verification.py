"""The LMIs of the Lur'e certificates recomputed in numpy, and a certificate re-verified.

Nothing is taken from the solver's status: the LMI is recomputed from the
returned P and T, symmetrised, and its largest eigenvalue must beat a
floating-point error bound by a factor ``clear``; P must pass a Cholesky
test with a margin and T must be nonnegative.  ``ssecert.stability.lmi``
uses these on every certificate it returns.
"""

from __future__ import annotations

import numpy as np

from ..observers.lure import LureModel
from ..tolerances import EPS
from .outcomes import VerifyCode, VerifyProblem

__all__ = ["circle_matrix", "iss_matrix", "verify_certificate", "definite_problem", "decide"]


def circle_matrix(model: LureModel, P: np.ndarray, t: np.ndarray, alpha: float = 0.0) -> np.ndarray:
    """The circle-criterion LMI in (xi, phi), recomputed in numpy and symmetrised.

    [A B]' P [A B] - diag((1 - alpha) P, 0) + sym([[0, q Cw' T], [q T Cw, -2 T]])
    """
    G = np.hstack([model.A, model.B])
    N = model.N
    M = G.T @ P @ G
    M[:N, :N] -= (1.0 - alpha) * P
    T = np.diag(t)
    M[:N, N:] += model.q * model.Cw.T @ T
    M[N:, :N] += model.q * T @ model.Cw
    M[N:, N:] -= 2.0 * T
    return 0.5 * (M + M.T)


def iss_matrix(
    model: LureModel, P: np.ndarray, t: np.ndarray, alpha: float, g: float
) -> np.ndarray:
    """The dissipation LMI in (xi, phi, a), recomputed in numpy and symmetrised.

    V(xi+) - (1 - alpha) V(xi) + |e|^2 - g |a|^2 plus the sector terms with
    w = Cw xi + Dw a.
    """
    H = np.hstack([model.A, model.B, model.E])
    N, m, r = model.N, model.m, model.r
    M = H.T @ P @ H
    M[:N, :N] += model.Ce.T @ model.Ce - (1.0 - alpha) * P
    M[N + m :, N + m :] -= g * np.eye(r)
    if m:
        T = np.diag(t)
        qTC = model.q * T @ model.Cw
        qTD = model.q * T @ model.Dw
        M[N : N + m, :N] += qTC
        M[:N, N : N + m] += qTC.T
        M[N : N + m, N + m :] += qTD
        M[N + m :, N : N + m] += qTD.T
        M[N : N + m, N : N + m] -= 2.0 * T
    return 0.5 * (M + M.T)


def _error_bound(
    model: LureModel,
    P: np.ndarray,
    t: np.ndarray,
    size: int,
    output: bool = True,
    g: float = 0.0,
) -> float:
    """Rounding error bound on the eigenvalues of the recomputed LMI, relative to ||P||;
    ``output`` when the LMI has the |e|^2 term and the attack, ``g`` times the identity
    subtracted on the attack's block (the dissipation LMI, not the circle one: its matrix
    has no E or Dw, which may be in units of their own)."""
    normP = max(float(np.linalg.norm(P, 2)), np.finfo(float).tiny)
    G = np.hstack([model.A, model.B, model.E] if output else [model.A, model.B])
    normG = float(np.linalg.norm(G, 2))
    tmax = float(np.abs(t).max(initial=0.0))
    Cw = np.hstack([model.Cw, model.Dw]) if output else model.Cw
    normC = float(np.linalg.norm(Cw, 2)) if model.m else 0.0
    normCe = float(np.linalg.norm(model.Ce, 2)) if output else 0.0
    raw = (normG**2 + 2.0) * normP + (2 * model.q * normC + 2) * tmax + normCe**2 + abs(g)
    # the model's floats are within d of the exact matrices of the spec's data: G'PG moves by
    # at most (2 ||G|| + d) d ||P||, the sector terms by 2 q max(T) d
    d = model.rounding
    data = (2.0 * normG + d) * d * normP + 2.0 * model.q * tmax * d
    return 10.0 * size * EPS * raw / normP + data * (1 + 1e-12) / normP


def definite_problem(P: np.ndarray, clear: float) -> VerifyProblem | None:
    """None when the symmetric P is clearly positive definite: its smallest eigenvalue beats
    ``clear`` times a rounding bound and P minus half of it passes a Cholesky test."""
    normP = max(float(np.linalg.norm(P, 2)), np.finfo(float).tiny)
    p_eigs = np.linalg.eigvalsh(P)
    if p_eigs[0] <= clear * 10 * P.shape[0] * EPS * normP:
        return VerifyProblem(VerifyCode.NOT_CLEARLY_DEFINITE, {"smallest": float(p_eigs[0])})
    try:
        np.linalg.cholesky(P - 0.5 * p_eigs[0] * np.eye(P.shape[0]))
    except np.linalg.LinAlgError:
        return VerifyProblem(VerifyCode.CHOLESKY_FAILED)
    return None


def verify_certificate(
    model: LureModel,
    P: np.ndarray,
    t: np.ndarray,
    *,
    kind: str = "circle",
    alpha: float = 0.0,
    g: float = 0.0,
    clear: float = 100.0,
) -> tuple[bool, float, float, VerifyProblem | None]:
    """Re-verify a certificate without the solver.

    Returns
    -------
    ok : bool
    margin : float
        ``-lambda_max(LMI) / ||P||``.
    bound : float
        Error bound on that quantity.
    problem : VerifyProblem or None
        Why it is not verified (None when ok); its words: ``lmi_messages.verify_text``.
    """
    P = 0.5 * (np.asarray(P, dtype=float) + np.asarray(P, dtype=float).T)
    t = np.asarray(t, dtype=float)
    if not (np.all(np.isfinite(P)) and np.all(np.isfinite(t))):
        return False, float("nan"), 0.0, VerifyProblem(VerifyCode.NON_FINITE)
    if model.m and t.min(initial=0.0) < 0:
        negative = VerifyProblem(VerifyCode.NEGATIVE_MULTIPLIER, {"value": float(t.min())})
        return False, float("nan"), 0.0, negative
    M = circle_matrix(model, P, t, alpha) if kind == "circle" else iss_matrix(model, P, t, alpha, g)
    normP = max(float(np.linalg.norm(P, 2)), np.finfo(float).tiny)
    lam = float(np.linalg.eigvalsh(M)[-1])
    margin = -lam / normP
    bound = _error_bound(model, P, t, M.shape[0], output=kind != "circle", g=g)
    return decide(P, margin, bound, clear)


def decide(
    P: np.ndarray, margin: float, bound: float, clear: float
) -> tuple[bool, float, float, VerifyProblem | None]:
    """A recomputed LMI's verdict: P clearly positive definite and the margin (``-lambda_max /
    ||P||``) above ``clear`` times its rounding bound; (ok, margin, bound, problem or None)."""
    problem = definite_problem(P, clear)
    if problem is not None:
        return False, margin, bound, problem
    if margin <= clear * bound:
        facts = {"margin": margin, "clear": clear, "bound": bound}
        return False, margin, bound, VerifyProblem(VerifyCode.MARGIN_NOT_CLEAR, facts)
    return True, margin, bound, None
