"""The error dynamics of an observer written as a Lur'e system.

With xi the error state (the estimation error e, followed for sparse
observers by the attack estimate), every observer of ssecert reads

    xi+ = A xi + B phi(w) + E a,   w = Cw xi + Dw a,   e = Ce xi,

with phi = q * soft_threshold, componentwise, in the sector [0, q].  Linear
observers have no nonlinearity (B and Cw empty).  The LMI certificates of
``ssecert.stability.lmi`` are written for this form; each observer kind
(``ssecert.observers``) builds it for its designs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .base import ObserverDesign

__all__ = ["LureModel", "scaling_text"]


def scaling_text(s: np.ndarray) -> str:
    """``diag(2^a, 2^b, ...)`` for the powers of two of a balancing (``LureModel.balancing``)."""
    return "diag(" + ", ".join(f"2^{int(e)}" for e in np.log2(np.asarray(s, dtype=float))) + ")"


@dataclass(frozen=True)
class LureModel:
    """xi+ = A xi + B phi(w) + E a, w = Cw xi + Dw a, e = Ce xi; phi in sector [0, q].

    ``n_e`` is the size of the first state block (the estimation error); the
    remaining ``m`` states are the attack estimate, equal to the previous
    nonlinearity output.
    """

    A: np.ndarray
    B: np.ndarray
    Cw: np.ndarray
    E: np.ndarray
    Dw: np.ndarray
    Ce: np.ndarray
    q: float
    n_e: int
    threshold: float = 0.0

    @property
    def N(self) -> int:
        return self.A.shape[0]

    @property
    def m(self) -> int:
        return self.B.shape[1]

    @property
    def r(self) -> int:
        return self.E.shape[1]

    def vertex(self, k: float) -> np.ndarray:
        """Closed loop with phi(w) = k w."""
        return self.A + k * self.B @ self.Cw

    @classmethod
    def from_design(cls, design: ObserverDesign) -> LureModel:
        """The Lur'e form of an observer's error dynamics, as its kind writes it.

        Raises NotImplementedError for a design that has none (an SSO with
        several inner steps per sample).
        """
        return design.observer_kind.lure_model(design)

    def scaled(self, s: np.ndarray) -> LureModel:
        """The same dynamics in the coordinates xi = diag(s) xi_b.

        A_b = S^-1 A S, B_b = S^-1 B, Cw_b = Cw S, E_b = S^-1 E, Ce_b = Ce S;
        the channels and the attack keep their units.  With powers of two
        (``balancing``) every entry is scaled exactly.
        """
        s = np.asarray(s, dtype=float)
        return LureModel(
            self.A * (s[None, :] / s[:, None]),
            self.B / s[:, None],
            self.Cw * s[None, :],
            self.E / s[:, None],
            self.Dw,
            self.Ce * s[None, :],
            self.q,
            self.n_e,
            self.threshold,
        )

    def balancing(self, spread: float = 16.0) -> np.ndarray | None:
        """Powers of two s that balance the large-signal loop A + q B Cw (LAPACK's gebal
        through ``scipy.linalg.matrix_balance``), or None when they spread less than
        ``spread`` or the scaled model would not be exact (an entry under- or overflowing).

        An LMI solver fails on a Lur'e model whose states are in very different units; the
        model in the coordinates xi = diag(s) xi_b (``scaled``) is the same system, written
        exactly.
        """
        from scipy.linalg import matrix_balance

        if self.N == 0:
            return None
        with np.errstate(all="ignore"):  # a model at the ends of the float range: no scaling
            loop = self.vertex(self.q)
            if not np.all(np.isfinite(loop)):
                return None
            _, (s, _) = matrix_balance(loop, permute=False, separate=True)
            s = np.asarray(s, dtype=float)
            if not np.all(np.isfinite(s) & (s > 0)) or s.max() < spread * s.min():
                return None
            exponents = np.log2(s)
            if not np.array_equal(exponents, np.round(exponents)):
                return None
            balanced = self.scaled(s)
            back = balanced.scaled(1.0 / s)
        for name in ("A", "B", "Cw", "E", "Ce"):
            if not np.array_equal(getattr(back, name), getattr(self, name)):
                return None
        return s

    def phi(self, w: np.ndarray) -> np.ndarray:
        """The nonlinearity q * soft_threshold(w), componentwise."""
        return self.q * np.sign(w) * np.maximum(np.abs(w) - self.threshold, 0.0)

    def simulate(self, xi0: np.ndarray, steps: int, attack: np.ndarray | None = None) -> np.ndarray:
        """Trajectories of the error state, shape (steps + 1, ..., N).

        ``xi0`` may hold many initial states (..., N); ``attack`` has shape
        (steps, ..., r) or is None (no attack).
        """
        xi = np.asarray(xi0, dtype=float)
        out = np.empty((steps + 1,) + xi.shape)
        out[0] = xi
        for k in range(steps):
            a = 0.0 if attack is None else attack[k]
            w = xi @ self.Cw.T + (0.0 if attack is None else a @ self.Dw.T)
            xi = xi @ self.A.T + (self.phi(w) @ self.B.T if self.m else 0.0)
            if attack is not None:
                xi = xi + a @ self.E.T
            out[k + 1] = xi
        return out

    @classmethod
    def linear(cls, F: np.ndarray, L: np.ndarray) -> LureModel:
        """e+ = F e + L a with no nonlinearity (a Luenberger-type observer)."""
        n, r = L.shape
        return cls(F, np.zeros((n, 0)), np.zeros((0, n)), L, np.zeros((0, r)), np.eye(n), 0.0, n)
