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

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from fractions import Fraction
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from ..numerics.exact_powers import Dyadic, ExactMatrix, dyadic
from ..numerics.linalg import anchored_units

if TYPE_CHECKING:
    from .base import ObserverDesign

__all__ = ["LureModel", "ExactLure", "scaling_text"]

# Largest model (entries of [A B E; Cw Dw]) whose exact matrices are formed on demand; beyond
# it nothing is decided in exact arithmetic and only the a-priori rounding bound is used.
EXACT_ENTRIES = 250_000


@dataclass(frozen=True)
class ExactLure:
    """The exact matrices of a Lur'e model, formed from the spec's data (the floats of A, L,
    C, the step and L2 as given), not from their floating-point products."""

    A: Dyadic
    B: Dyadic
    Cw: Dyadic
    E: Dyadic
    Dw: Dyadic

    def fractions(self, name: str) -> list[list[Fraction]]:
        """One matrix (``"A"``, ``"B"``, ``"Cw"``, ``"E"``, ``"Dw"``) as rows of Fractions."""
        return getattr(self, name).to_fractions()

    def scaled(
        self, s: np.ndarray, sensors: int = 0, channels: np.ndarray | None = None
    ) -> ExactLure:
        """The same dynamics in the coordinates xi = diag(s) xi_b, s powers of two, with the
        channels and the attack in units 2^-sensors, or each channel in its own
        (``LureModel.scaled``)."""
        k = np.round(np.log2(np.asarray(s, dtype=float))).astype(np.int64)
        m, r = self.B.shape[1], self.E.shape[1]
        jr = np.full(r, sensors, np.int64)
        if channels is None:
            jm, Dw = np.full(m, sensors, np.int64), self.Dw
        else:
            jm = np.asarray(channels, dtype=np.int64)
            Dw = self.Dw.scaled(jm, -jr)
        return ExactLure(
            self.A.scaled(-k, k),
            self.B.scaled(-k, -jm),
            self.Cw.scaled(jm, k),
            self.E.scaled(-k, -jr),
            Dw,
        )

    def distance_bound(self, model: LureModel) -> float:
        """An upper bound on the 2-norm of [A B E; Cw Dw] of ``model`` minus these."""
        parts = [
            getattr(self, name).distance_bound(getattr(model, name))
            for name in ("A", "B", "Cw", "E", "Dw")
        ]
        return math.sqrt(sum(v * v for v in parts)) * (1 + 1e-12)


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
    # NaN where the channels are in units of their own (``scaled`` with ``channels``): one
    # threshold per channel there, no single value (the sector LMIs do not read it)
    threshold: float = 0.0
    # the exact matrices from the spec's data (None: beyond their budget); without it the
    # model's own floats are its data
    exact_build: Callable[[], ExactLure | None] | None = field(
        default=None, compare=False, repr=False
    )
    # a-priori bound on the 2-norm of the floats of [A B E; Cw Dw] minus the exact matrices
    formation_error: float = 0.0
    # the exact error block F alone (n_e x n_e), when it can be formed without the whole model
    exact_error: ExactMatrix | None = field(default=None, compare=False, repr=False)
    # the spread of the state scaling the model is written in (``scaled``): its a-priori
    # bound grew by it, so the rounding is measured on the exact matrices where they are known
    spread: float = 1.0

    def exact(self) -> ExactLure | None:
        """The exact matrices of the model (formed once), or None beyond their budget."""
        return self._exact

    @cached_property
    def _exact(self) -> ExactLure | None:
        if self.exact_build is None:
            return ExactLure(*(dyadic(getattr(self, k)) for k in ("A", "B", "Cw", "E", "Dw")))
        return self.exact_build()

    def exact_A(self, *, error_block: bool = False) -> ExactMatrix | None:
        """The exact A (or its estimation-error block F with ``error_block``), formed on
        demand, when the model's floats are a rounding of the spec's data; None when the
        floats are themselves the data (a model built from given matrices)."""
        if self.exact_build is None:
            return None
        k = self.n_e if error_block else self.N
        model = self

        def build() -> Dyadic | None:
            if error_block and model.exact_error is not None and model.exact() is None:
                return model.exact_error.value  # F alone, where the whole model is too large
            exact = model.exact()
            return None if exact is None else exact.A[:k, :k]

        finite = math.isfinite(self.formation_error)
        if self.spread > 1.0 and self.exact() is not None:
            finite = False  # measured on the exact matrices: spread times the bound is loose
        return ExactMatrix(
            build,
            self.formation_error if finite else None,
            "F = A - L C formed exactly from the spec's data"
            if error_block
            else "the model's A formed exactly from the spec's data",
        )

    @cached_property
    def rounding(self) -> float:
        """An upper bound on the 2-norm of the model's floats [A B E; Cw Dw] minus its exact
        matrices: the perturbation every certificate verified on the floats must absorb."""
        if self.exact_build is None:
            return 0.0
        exact = self.exact()
        if exact is None:
            return self.formation_error
        return exact.distance_bound(self)

    @property
    def N(self) -> int:
        return self.A.shape[0]

    @property
    def m(self) -> int:
        return self.B.shape[1]

    @property
    def r(self) -> int:
        return self.E.shape[1]

    def with_input(self, extra: np.ndarray) -> LureModel:
        """The model with a further input w entering the state alone, xi+ = A xi + B phi(w_)
        + E a + ``extra`` w (w not in the nonlinearity's argument): its attack input is then
        [a; w].  ``extra`` is exact (the spec's data, as its exact matrices take it).

        Examples
        --------
        >>> model = LureModel.linear(np.array([[0.5]]), np.array([[1.0]]))
        >>> model.with_input(np.array([[-1.0]])).E.tolist()
        [[1.0, -1.0]]
        """
        extra = np.asarray(extra, dtype=float)
        zeros = np.zeros((self.Dw.shape[0], extra.shape[1]))
        build = self._exact_derived(
            lambda exact: replace(
                exact,
                E=Dyadic.block([[exact.E, dyadic(extra)]]),
                Dw=Dyadic.block([[exact.Dw, Dyadic.zeros(zeros.shape)]]),
            )
        )
        return replace(
            self, E=np.hstack([self.E, extra]), Dw=np.hstack([self.Dw, zeros]), exact_build=build
        )

    def input_scaled(self, k: np.ndarray) -> LureModel:
        """The model with its attack input a = diag(2^k) a_b: E_b = E diag(2^k), Dw_b = Dw
        diag(2^k), exactly (powers of two), its exact matrices scaled alike.  With k <= 0 the
        a-priori rounding bound stays one (each column's error shrinks with it); otherwise it
        grows by 2^max(k).

        Examples
        --------
        >>> model = LureModel.linear(np.array([[0.5]]), np.array([[1.0, 3.0]]))
        >>> model.input_scaled(np.array([0, -2])).E.tolist()
        [[1.0, 0.75]]
        """
        k = np.asarray(k, dtype=np.int64)
        if k.shape != (self.r,):
            raise ValueError(f"k: expected {self.r} exponents, got {k.tolist()}")
        N, m = self.N, self.Dw.shape[0]
        build = self._exact_derived(
            lambda exact: replace(
                exact,
                E=exact.E.scaled(np.zeros(N, np.int64), k),
                Dw=exact.Dw.scaled(np.zeros(m, np.int64), k),
            )
        )
        w = np.ldexp(1.0, k)
        growth = math.ldexp(1.0, int(max(k.max(initial=0), 0)))
        return replace(
            self,
            E=self.E * w,
            Dw=self.Dw * w,
            exact_build=build,
            formation_error=self.formation_error * growth,
        )

    def _exact_derived(
        self, change: Callable[[ExactLure], ExactLure]
    ) -> Callable[[], ExactLure | None] | None:
        """The exact build of a model derived from this one by ``change`` of its exact
        matrices (None where this model's floats are themselves its data)."""
        if self.exact_build is None:
            return None
        parent = self

        def build() -> ExactLure | None:
            exact = parent.exact()
            return None if exact is None else change(exact)

        return build

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

    def scaled(
        self, s: np.ndarray, sensors: int = 0, channels: np.ndarray | None = None
    ) -> LureModel:
        """The same dynamics in the coordinates xi = diag(s) xi_b, and with ``sensors``
        (an exponent j), the channels, the nonlinearity's output, the attack and the
        threshold in units 2^-j (multiplied by sigma = 2^j); with ``channels`` (one exponent
        per channel), each channel and its part of the nonlinearity's output in units of its
        own (the attack in units 2^-j still).

        A_b = S^-1 A S, B_b = S^-1 B / sigma, Cw_b = sigma Cw S, E_b = S^-1 E / sigma_a,
        Dw_b = sigma Dw / sigma_a, Ce_b = Ce S (sigma diagonal with ``channels``, sigma_a =
        2^j): the soft threshold is positively homogeneous, so its sector stays [0, q] (with
        ``channels``, its threshold is one per channel, and the model's ``threshold`` NaN:
        such a model is for the sector LMIs only); without ``sensors`` the
        channels and the attack keep their units.  With powers of two (``balancing``) every
        entry is scaled exactly.
        """
        s = np.asarray(s, dtype=float)
        sigma_a = math.ldexp(1.0, int(sensors))
        if channels is None:
            sigma = np.full(self.m, sigma_a)
            threshold = self.threshold * sigma_a
            build = self._exact_derived(lambda exact: exact.scaled(s, int(sensors)))
        else:
            j = np.asarray(channels, dtype=np.int64)
            sigma = np.ldexp(1.0, j)
            threshold = math.nan
            build = self._exact_derived(lambda exact: exact.scaled(s, int(sensors), j))
        spread = float(s.max() / s.min()) if s.size else 1.0
        # the 2-norm of [A B E; Cw Dw] grows by at most the largest row factor times the
        # largest column factor of the change: rows 1 / s and sigma, columns s, 1 / sigma
        # and 1 / sigma_a (in numpy floats: a scaling at the floats' ends makes it inf, as
        # the spread)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            rows = max(1.0 / s.min() if s.size else 0.0, float(sigma.max(initial=sigma_a)))
            columns = max(
                float(s.max()) if s.size else 0.0,
                1.0 / float(sigma.min(initial=sigma_a)),
                1.0 / sigma_a,
            )
            growth = float(rows * columns)
        error = None
        if self.exact_error is not None:
            base, k = self.exact_error, np.round(np.log2(s[: self.n_e])).astype(np.int64)

            def error_build() -> Dyadic | None:
                value = base.value
                return None if value is None else value.scaled(-k, k)

            error = ExactMatrix(error_build, None, base.source)
        return LureModel(
            self.A * (s[None, :] / s[:, None]),
            self.B / s[:, None] / sigma[None, :],
            self.Cw * s[None, :] * sigma[:, None],
            self.E / s[:, None] / sigma_a,
            self.Dw if channels is None else sigma[:, None] * self.Dw / sigma_a,
            self.Ce * s[None, :],
            self.q,
            self.n_e,
            threshold,
            build,
            self.formation_error * growth,
            error,
            self.spread * max(spread, growth),
        )

    def balancing(self, spread: float = 16.0, *, canonical: bool = False) -> np.ndarray | None:
        """Powers of two s that balance the large-signal loop A + q B Cw (LAPACK's gebal
        through ``scipy.linalg.matrix_balance``), or None when they spread less than
        ``spread`` or the scaled model would not be exact (an entry under- or overflowing).
        With ``canonical``, the least-squares scaling of the logarithms of A, [B E] and Cw
        with the channels and the attack in their own units (``anchored_units``), where it
        moves the states 2^16 or more from each other or from those units, else None: every
        power-of-two change of the states' units gives the same balanced model.

        An LMI solver fails on a Lur'e model whose states are in very different units; the
        model in the coordinates xi = diag(s) xi_b (``scaled``) is the same system, written
        exactly.
        """
        from scipy.linalg import matrix_balance

        if self.N == 0:
            return None
        with np.errstate(all="ignore"):  # a model at the ends of the float range: no scaling
            if canonical:
                s = anchored_units(self.A, np.hstack([self.B, self.E]), self.Cw)
                if s is None:
                    return None
            else:
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

    def balancings(self) -> list[np.ndarray]:
        """The distinct state scalings to retry an LMI in (``balancing``): gebal's, then the
        canonical one where the states' units are far apart (the same balanced model whatever
        units the spec writes them in)."""
        found: list[np.ndarray] = []
        for canonical in (False, True):
            s = self.balancing(canonical=canonical)
            if s is not None and not any(np.array_equal(s, other) for other in found):
                found.append(s)
        return found

    def finite(self) -> bool:
        """Whether every matrix of the model, and the loop at the sector's vertex, is within
        the float range (an observer step of 1e308 is not): nothing else can be computed."""
        with np.errstate(all="ignore"):
            loop = self.vertex(self.q) if self.m else self.A
        parts = (self.A, self.B, self.Cw, self.E, self.Dw, self.Ce, loop)
        return all(bool(np.all(np.isfinite(part))) for part in parts)

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
    def linear(
        cls,
        F: np.ndarray,
        L: np.ndarray,
        *,
        exact_F: Callable[[], Dyadic | None] | None = None,
        formation_error: float = 0.0,
    ) -> LureModel:
        """e+ = F e + L a with no nonlinearity (a Luenberger-type observer); ``exact_F`` forms
        the exact F when F is a rounded product (``formation_error`` bounds the rounding)."""
        n, r = L.shape
        build = None
        if exact_F is not None:
            make_F = exact_F

            def build() -> ExactLure | None:
                exact = make_F()
                if exact is None:
                    return None
                return ExactLure(
                    exact,
                    Dyadic.zeros((n, 0)),
                    Dyadic.zeros((0, n)),
                    dyadic(L),
                    Dyadic.zeros((0, r)),
                )

        return cls(
            F,
            np.zeros((n, 0)),
            np.zeros((0, n)),
            L,
            np.zeros((0, r)),
            np.eye(n),
            0.0,
            n,
            0.0,
            build,
            formation_error,
        )
