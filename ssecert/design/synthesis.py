"""An observer gain L designed against the certificate: the dissipation LMI with L free.

For the soft-threshold observers (D-SSO, elastic net) the error state is the
Lur'e system of ``ssecert.observers.lure`` with

    A = [[A_p - L S, -L], [0, 0]],  B = [[0], [I]],  E = [[L], [0]],

and the dissipation inequality of ``ssecert.stability.lmi.iss_certificate``,
V(xi+) - (1 - alpha) V(xi) + |e|^2 - g |a|^2 <= 0 under the sector
constraints, is quadratic in L.  With P = diag(P1, D) block diagonal (the
structure the certificates use) and a Schur complement, the inequality reads

    [[ (1 - alpha) diag(P, 0, 0) - Ce'Ce - sector terms + g,  (P H)' ],
     [ P H,                                                    P      ]] >= 0,

H = [A B E], whose first block row P1 [A_p - L S, -L, 0, L] is linear in
Y = P1 L.  One Clarabel solve (cvxpy) minimises g = gamma^2 over (P1, D, T,
Y); the gain is L = P1^-1 Y.  Nothing of the solve is trusted: the design
with that gain is certified again by the ordinary certificates, from
scratch, and only their verified gamma is reported.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..observers.base import ObserverDesign
from ..observers.lure import LureModel

__all__ = ["GainSynthesis", "synthesize_gain", "with_gain"]


@dataclass(frozen=True)
class GainSynthesis:
    """A gain proposed by the synthesis LMI, and what the solver said (unverified)."""

    L: np.ndarray | None
    gamma_proposed: float | None
    status: str
    seconds: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "L": self.L,
            "gamma_proposed": self.gamma_proposed,
            "status": self.status,
            "seconds": self.seconds,
        }


def synthesize_gain(design: ObserverDesign, *, alpha: float = 1e-3) -> GainSynthesis:
    """The gain L minimising the l2 gain from attack to estimation error that the
    dissipation LMI certifies, for the design's step, threshold and shrink (its own gain is
    ignored); a candidate only: certify the design built with it.

    Parameters
    ----------
    design : ObserverDesign
        A D-SSO or elastic-net design (window 1, one step per sample) or a Luenberger design.
    alpha : float, default 1e-3
        Decay imposed with the gain (V(xi+) <= (1 - alpha) V(xi) without attack).
    """
    import cvxpy as cp

    start = time.perf_counter()
    model = LureModel.from_design(design)
    n, p = design.system.n, design.system.p
    S = design.sensing
    if S.shape[0] != p:
        raise NotImplementedError("gain synthesis needs one attack estimate per sensor")
    N, m, r = model.N, model.m, model.r
    A_p = design.system.A
    P1 = cp.Variable((n, n), symmetric=True)
    Y = cp.Variable((n, p))
    g = cp.Variable(nonneg=True)
    cons = [P1 >> np.eye(n)]
    Z = np.zeros
    if m:
        d = cp.Variable(m)
        t = cp.Variable(m)
        cons += [d >= 1, t >= 1e-6]
        D, T = cp.diag(d), cp.diag(t)
        P = cp.bmat([[P1, Z((n, m))], [Z((m, n)), D]])
        PH = cp.bmat(
            [
                [P1 @ A_p - Y @ S, -Y, Z((n, m)), Y],
                [Z((m, n)), Z((m, m)), D, Z((m, r))],
            ]
        )
    else:
        P = P1
        PH = cp.hstack([P1 @ A_p - Y @ S, Y])
    size = N + m + r
    Ce = model.Ce
    top = (1 - alpha) * P - Ce.T @ Ce
    if m:
        qTC = model.q * T @ model.Cw
        qTD = model.q * T @ model.Dw
        left = cp.bmat(
            [
                [top, -qTC.T, Z((N, r))],
                [-qTC, 2 * T, -qTD],
                [Z((r, N)), -qTD.T, g * np.eye(r)],
            ]
        )
    else:
        left = cp.bmat([[top, Z((N, r))], [Z((r, N)), g * np.eye(r)]])
    big = cp.bmat([[left, PH.T], [PH, P]])
    cons.append(0.5 * (big + big.T) >> 1e-7 * np.eye(size + N))
    problem = cp.Problem(cp.Minimize(g), cons)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a candidate: certified afterwards either way
            problem.solve(solver=cp.CLARABEL)
    except (cp.error.SolverError, ArithmeticError, ValueError) as exc:
        return GainSynthesis(None, None, f"solver failed ({type(exc).__name__})", _since(start))
    if Y.value is None or P1.value is None:
        return GainSynthesis(None, None, str(problem.status), _since(start))
    L = np.linalg.solve(0.5 * (P1.value + P1.value.T), Y.value)
    if not np.all(np.isfinite(L)):
        return GainSynthesis(None, None, "the solver's gain is not finite", _since(start))
    gamma = float(np.sqrt(max(float(np.asarray(g.value)), 0.0)))
    return GainSynthesis(L, gamma, str(problem.status), _since(start))


def with_gain(design: ObserverDesign, L: np.ndarray) -> ObserverDesign:
    """``design`` with the gain L (an explicit matrix, as a spec file would give it)."""
    from ..observers.base import gain_from_choice

    gain = gain_from_choice(design.system, {"gain": np.asarray(L, dtype=float)})
    return replace(design, gain=replace(gain, details={"synthesised": True}))


def _since(start: float) -> float:
    return round(time.perf_counter() - start, 3)
