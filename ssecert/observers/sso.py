"""The sparse soft observer (SSO) of the Lasso paper, Algorithm 1.

Spec keys: ``step`` and ``threshold`` (> 0), ``shrink`` (1 if given),
``window`` (tau, default 1) and ``inner_steps`` (ISTA steps per sample,
default 1).  The gain is L = step * A S^T with S = O_tau, the stacked
observability matrix of the window.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..budget import Budget, ResourceLimitError
from ..design.gains import Gain, GainError, ogd_gain
from ..numerics.exact_powers import (
    Dyadic,
    ExactMatrix,
    as_dyadic,
    dyadic,
    exact_observability_matrix,
)
from ..system import System
from ..tolerances import Tolerances, product_rounding
from .base import (
    POSITIVE_SCHEMA,
    SSO_GAIN,
    UNIT_SHRINK_SCHEMA,
    ObserverDesign,
    check_finite,
    parse_unit_shrink,
)
from .dsso import SoftThresholdObserverKind
from .dynamic import DynamicObserver
from .lure import ExactLure, LureModel
from .registry import register
from .simulators import WindowSSO

if TYPE_CHECKING:  # annotations only: the spec package imports the observers
    from hypothesis.strategies import SearchStrategy

    from ..spec.table import SpecTable

__all__ = ["SparseSoftObserverKind", "MAX_DEAD_ZONE_ROWS"]

EXACT_INNER_WORK = 2e7  # word operations for the exact powers of an SSO's inner map
# most threshold inputs (inner steps times attack-estimate entries) of a dead-zone model: each is
# a row of its certificates and a constraint of the LMI that widens its region
MAX_DEAD_ZONE_ROWS = 20_000
# most entries of the noise's input to a dead-zone model (inner steps times the square of the
# measurement vector's length): its threshold inputs' noise terms, formed as a matrix
MAX_NOISE_ENTRIES = 4_000_000


@register
class SparseSoftObserverKind(SoftThresholdObserverKind):
    name = "sso"
    keys = ("kind", "step", "threshold", "shrink", "window", "inner_steps")
    key_schemas: ClassVar[Mapping[str, Any]] = {
        "step": POSITIVE_SCHEMA,
        "threshold": POSITIVE_SCHEMA,
        "shrink": UNIT_SHRINK_SCHEMA,
        "window": {"type": "integer", "minimum": 1, "default": 1},
        "inner_steps": {"type": "integer", "minimum": 1, "default": 1},
    }
    required_keys = ("step", "threshold")

    def parse(self, table: SpecTable, n: int, p: int) -> dict[str, Any]:
        out: dict[str, Any] = {}
        out["step"] = table.positive("step")
        out["threshold"] = table.positive("threshold")
        out["shrink"] = parse_unit_shrink(table, self.name, "elastic_net")
        out["window"] = table.integer("window", 1, min_value=1)
        out["inner_steps"] = table.integer("inner_steps", 1, min_value=1)
        return out

    def build(
        self, system: System, params: Mapping[str, Any], budget: Budget, tolerances: Tolerances
    ) -> ObserverDesign:
        window = int(params.get("window", 1))
        step = params["step"]
        if window > 1:
            n, m = system.n, system.p * window
            budget.require(
                f"observer.window = {window:,}: the SSO's stacked O_tau ({m:,} x {n}) with its "
                f"gain and {m:,} x {m:,} L2",
                nbytes=8.0 * (3 * m * n + m * m + 2 * n * m),
            )
            with np.errstate(over="ignore", invalid="ignore"):
                sensing = system.observability_matrix(window)
            if not np.all(np.isfinite(sensing)):
                raise GainError(
                    f"the stacked observability matrix O_tau overflows for the window "
                    f"tau = {window} (C A^k is not finite in floating point)"
                )
            with np.errstate(over="ignore", invalid="ignore"):  # beyond the floats: inf
                L = step * system.A @ sensing.T
                error = system.A - L @ sensing
            gain = Gain(
                L=L,
                method=SSO_GAIN,
                error_matrix=error,
                verified=True,
                details={"step": step, "window": window},
            )
        else:
            sensing = system.C
            ogd = ogd_gain(system, step)
            gain = Gain(
                L=ogd.L,
                method=SSO_GAIN,
                error_matrix=ogd.error_matrix,
                verified=True,
                details=ogd.details,
            )
        check_finite(gain)
        m = sensing.shape[0]
        return ObserverDesign(
            kind=self.name,
            system=system,
            gain=gain,
            sensing=sensing,
            step=float(step),
            threshold=float(params["threshold"]),
            shrink=float(params.get("shrink", 1.0)),
            L2=np.eye(m),
            window=window,
            inner_steps=int(params.get("inner_steps", 1)),
        )

    def parameter_strategy(self, system: System) -> SearchStrategy[dict[str, Any]]:
        """window 1..n, inner_steps 1..3, step f / ||O_tau||^2 with f in [0.05, 1],
        threshold in [0.01, 0.5]."""
        from hypothesis import strategies as st

        from .strategies import STEP, THRESHOLD, real

        @st.composite
        def tables(draw: Any) -> dict[str, Any]:
            window = draw(st.integers(1, system.n))
            sensing = system.C if window == 1 else system.observability_matrix(window)
            out: dict[str, Any] = {"window": window, "inner_steps": draw(st.integers(1, 3))}
            norm = max(float(np.linalg.norm(sensing, 2)) ** 2, 1e-300)
            out["step"] = real(draw, STEP) / norm
            out["threshold"] = real(draw, THRESHOLD)
            return out

        return tables()

    def _windowed(self, design: ObserverDesign) -> bool:
        return design.window > 1 or design.inner_steps > 1

    def simulator(self, design: ObserverDesign) -> DynamicObserver:
        if not self._windowed(design):
            return super().simulator(design)
        return WindowSSO(
            design.system.A,
            design.system.C,
            step=design.parameter("step"),
            threshold=design.parameter("threshold"),
            window=design.window,
            inner_steps=design.inner_steps,
        )

    def error_matrix(self, design: ObserverDesign) -> np.ndarray:
        """A - L S, or, with m inner ISTA steps per sample, A (I - step S^T S)^m."""
        if design.inner_steps == 1:
            return super().error_matrix(design)
        step = design.parameter("step")
        inner = np.eye(design.system.n) - step * design.sensing.T @ design.sensing
        with np.errstate(over="ignore", invalid="ignore"):  # the callers judge an overflow
            return design.system.A @ np.linalg.matrix_power(inner, design.inner_steps)

    def exact_sensing(self, design: ObserverDesign) -> np.ndarray | Dyadic:
        """C, or for a window tau > 1 the exact O_tau = [C; C A; ...; C A^(tau-1)] (the
        design's float O_tau is its rounding); the floats when the exact one is too large."""
        if design.window == 1:
            return design.sensing
        exact = exact_observability_matrix(design.system.A, design.system.C, design.window)
        return design.sensing if exact is None else exact

    def exact_error(self, design: ObserverDesign) -> ExactMatrix:
        """A - L S, or with m inner steps A (I - step S' S)^m, formed exactly from the spec's
        data (None beyond the budget of its bits: the power's entries grow with m)."""
        if design.inner_steps == 1:
            return super().exact_error(design)
        A, nu, steps = design.system.A, design.parameter("step"), design.inner_steps
        n = A.shape[0]
        S = self.exact_sensing(design)

        def build() -> Dyadic | None:
            powers = _exact_inner_powers(n, S, nu, steps, A)
            return None if powers is None else powers[0]

        return ExactMatrix(
            build,
            _inner_rounding(A, design.sensing, S, nu, steps)[0],
            f"F = A (I - step S' S)^{steps} formed exactly from the floats of A, C and the step",
        )

    def lure_gap(self, design: ObserverDesign) -> str | None:
        if design.inner_steps > 1:
            return (
                f"Certificates for an SSO with {design.inner_steps} inner steps per sample "
                f"are not implemented (the Lur'e model covers one step)."
            )
        return None

    def region_family(self, design: ObserverDesign) -> ObserverDesign | None:
        return None if design.inner_steps > 1 else super().region_family(design)

    def dead_zone_refusal(self, design: ObserverDesign) -> str:
        rows = design.inner_steps * design.sensing.shape[0]
        if design.inner_steps > 1 and not np.all(np.isfinite(self.error_matrix(design))):
            return (
                f"observer.inner_steps = {design.inner_steps:,}: A (I - step S' S)^m "
                f"overflows in floating point, so its dead zone cannot be certified"
            )
        if design.inner_steps > 1 and rows > MAX_DEAD_ZONE_ROWS:
            return (
                f"observer.inner_steps = {design.inner_steps:,}: the dead zone of an SSO with "
                f"that many inner steps has {rows:,} threshold inputs (inner steps times "
                f"{design.sensing.shape[0]:,} entries of the attack estimate), more than the "
                f"{MAX_DEAD_ZONE_ROWS:,} its certificates handle; not attempted"
            )
        return ""

    def dead_zone_model(self, design: ObserverDesign, *, noise: bool = False) -> LureModel | None:
        """With a_hat = 0 and every inner step's threshold input |w| <= threshold, the attack
        estimate stays 0 and each inner ISTA step maps the error by I - step S' S: the error
        follows e+ = A (I - step S' S)^m e, and the threshold inputs of inner step i are
        -step S (I - step S' S)^(i-1) e.

        With ``noise``, the model's input a is the measurement vector's noise (the window's
        stacked samples, entering as an attack on every row does): inner step i moves the
        error by step S' a, so with Sigma_i = sum_(j < i) (I - step S' S)^j its threshold
        input gains (step I - step^2 S Sigma_i S') a and the error step A Sigma_m step S' a.
        None when that input is beyond ``MAX_NOISE_ENTRIES``."""
        if design.inner_steps == 1:
            return None
        refusal = self.dead_zone_refusal(design)
        if refusal:
            raise ResourceLimitError(refusal)
        n = design.system.n
        S = design.sensing
        r = S.shape[0]
        nu = design.parameter("step")
        steps = design.inner_steps
        if noise and steps * r * r > MAX_NOISE_ENTRIES:
            return None
        inner = np.eye(n) - nu * S.T @ S
        rows, noise_rows, power, total = [], [], np.eye(n), np.zeros((n, n))
        nuS, nuSt = nu * S, nu * S.T
        for _ in range(steps):
            rows.append(-nu * S @ power)
            if noise:
                noise_rows.append(nu * np.eye(r) - nuS @ (total @ nuSt))
                total = total + power
            power = inner @ power
        W = np.vstack(rows)
        exact_S = self.exact_sensing(design)
        A = design.system.A
        if noise:
            E, Dw = A @ (total @ nuSt), np.vstack(noise_rows)
        else:
            E, Dw = np.zeros((n, r)), np.zeros((W.shape[0], r))

        def build() -> ExactLure | None:
            powers = _exact_inner_powers(n, exact_S, nu, steps, A, noise=noise)
            if powers is None:
                return None
            F, rows, inputs = powers
            return ExactLure(
                A=F,
                B=Dyadic.zeros((n, W.shape[0])),
                Cw=Dyadic.block([[row] for row in rows]),
                E=inputs[0] if inputs else Dyadic.zeros(E.shape),
                Dw=Dyadic.block([[d] for d in inputs[1:]]) if inputs else Dyadic.zeros(Dw.shape),
            )

        return LureModel(
            A=self.error_matrix(design),
            B=np.zeros((n, W.shape[0])),
            Cw=W,
            E=E,
            Dw=Dw,
            Ce=np.eye(n),
            q=float(design.shrink),
            n_e=n,
            threshold=float(design.threshold or 0.0),
            exact_build=build,
            formation_error=_inner_rounding(A, S, exact_S, nu, steps, noise=noise)[1],
        )

    def simulation_flops(self, design: ObserverDesign) -> float:
        if not self._windowed(design):
            return super().simulation_flops(design)
        n, m = design.system.n, design.sensing.shape[0]
        return design.inner_steps * 2.0 * (n + m) ** 2 + 2.0 * (n + m) * m


def _exact_inner_powers(
    n: int,
    S: np.ndarray | Dyadic,
    nu: float,
    steps: int,
    A: np.ndarray,
    *,
    noise: bool = False,
) -> tuple[Dyadic, list[Dyadic], list[Dyadic]] | None:
    """A (I - nu S' S)^steps, the threshold inputs -nu S (I - nu S' S)^i, i < steps, and with
    ``noise`` the noise's inputs (``dead_zone_model``: A Sigma_m nu S' first, then nu I - nu^2
    S Sigma_i S' of each inner step; empty without), in exact arithmetic; None when their
    bits would exceed ``EXACT_INNER_WORK``."""
    Sd = as_dyadic(S)
    r = Sd.shape[0]
    inner = Dyadic.eye(n) - (Sd.T @ Sd).times(nu)
    # each factor adds the bits of ``inner``: the last power has about steps times them
    words = steps * (inner.bits() + 64) / 64.0
    flops = n**3 + (r * n * (n + r) if noise else 0)
    if steps * flops * words**1.6 > EXACT_INNER_WORK:
        return None
    nuS, nuSt = Sd.times(-nu), Sd.T.times(nu)
    rows, inputs, power, total = [], [], Dyadic.eye(n), Dyadic.zeros((n, n))
    for _ in range(steps):
        rows.append(nuS @ power)
        if noise:
            inputs.append(Dyadic.eye(r).times(nu) + nuS @ (total @ nuSt))
            total = total + power
        power = inner @ power
    if noise:
        inputs.insert(0, dyadic(A) @ (total @ nuSt))
    return dyadic(A) @ power, rows, inputs


def _inner_rounding(
    A: np.ndarray,
    S: np.ndarray,
    exact_S: np.ndarray | Dyadic,
    nu: float,
    steps: int,
    *,
    noise: bool = False,
) -> tuple[float, float]:
    """A-priori bounds on the rounding of A (I - nu S'S)^steps and of the dead-zone model
    (that matrix, every threshold input -nu S (I - nu S'S)^i and with ``noise`` the noise's
    inputs of ``SparseSoftObserverKind.dead_zone_model``) computed in floating point, as
    2-norms of their distance from the exact values: (bound on F, bound on the model).

    One product of n x n matrices X Y is within n gamma_n ||X|| ||Y|| of the exact product of
    its floats (Higham 3.5, with || |X| ||_2 <= sqrt(n) ||X||_2); the recurrence
    e_k <= (dM + n gamma a) p_(k-1) + a e_(k-1), p_k = a p_(k-1) + e_k >= ||P_k||, bounds the
    k-th power's error, a >= ||M|| + dM; it is linear, so its k-th step is a power of a 2 x 2
    matrix.  The power of F is computed by repeated squaring: a product of two computed powers
    with relative errors r and r' has 1 + r'' <= (1 + r)(1 + r')(1 + n gamma), so its bound is
    that of the same factors with at most 2 log2 m <= m - 1 roundings, below the sequential
    one; the bound is doubled besides.

    The noise's inputs: the running sum Sigma_i of the powers carries their errors and one
    rounding of each addition (u sqrt(n) times its norm), sigma_i, and has norm at most s_i
    (the powers' bounds summed, plus sigma_i); nu S is rounded entrywise (u sqrt(n) ||nu S||)
    and off the exact nu S by nu dS; each product, the difference with nu I (u sqrt(r) times
    its norm) and the product by A add theirs; each bound is doubled.
    """
    n = A.shape[0]
    r = S.shape[0]
    u = float(np.finfo(float).eps) / 2
    k = max(n, r) + 3
    gamma = k * u / (1 - k * u)
    with np.errstate(all="ignore"):
        dS = 0.0 if not isinstance(exact_S, Dyadic) else exact_S.distance_bound(S)
        normS = float(np.linalg.norm(S, 2)) * (1 + 1e-12) + dS
        M = np.eye(n) - nu * S.T @ S
        dM = product_rounding(S.T, S, np.eye(n), scale=nu) + abs(nu) * (2 * normS + dS) * dS
        a = (float(np.linalg.norm(M, 2)) * (1 + 1e-12) + dM) * (1 + 1e-12)
        normA = float(np.linalg.norm(A, 2)) * (1 + 1e-12)
        # (e_k, p_k) = T (e_(k-1), p_(k-1)), from (0, 1): powers of T by squaring
        c = dM + k * gamma * a
        T = np.array([[a, c], [a, a + c]])
        e, p = np.linalg.matrix_power(T, steps) @ np.array([0.0, 1.0]) * (1 + 1e-10 * steps)
        dF = 2.0 * (normA * e + k * gamma * normA * p) * (1 + 1e-12)
        # nu S: its norm (and the exact one's) and its distance from the exact nu S
        s_hat = abs(nu) * normS * (1 + u * math.sqrt(n))
        d_hat = abs(nu) * (u * math.sqrt(n) * normS + dS)
        kg = k * gamma
        # the threshold input of inner step i, -nu S P_i, one by one (a model that large is
        # refused before it is built); with the noise, its input nu I - nu^2 S Sigma_i S'
        rows, v = 0.0, np.array([0.0, 1.0])
        sigma, total = 0.0, 0.0  # Sigma_i's error and norm bound (without sigma)
        for _ in range(steps if steps <= MAX_DEAD_ZONE_ROWS else 0):
            row = abs(nu) * (normS * v[0] + dS * v[1] + 2 * k * gamma * normS * v[1])
            rows += row * row
            if noise:
                s_i = total + sigma
                product = (
                    2 * kg * (1 + kg) * s_hat**2 * s_i + 2 * d_hat * s_i * s_hat
                    + s_hat**2 * sigma
                )  # fmt: skip
                top = abs(nu) + s_hat**2 * s_i * (1 + kg) ** 2
                dD = 2.0 * (product + u * math.sqrt(r) * top)
                rows += dD * dD
                sigma += v[0] + u * math.sqrt(n) * (s_i + v[1])
                total += v[1]
            v = T @ v
        if noise:
            s_m = total + sigma
            dE = 2.0 * normA * (kg * s_m * s_hat * (2 + kg) + sigma * s_hat + s_m * d_hat)
            rows += dE * dE
        if steps > MAX_DEAD_ZONE_ROWS:
            rows = math.inf
        model = math.sqrt(dF * dF + rows) * (1 + 1e-10 * min(steps, MAX_DEAD_ZONE_ROWS))
    return (dF if math.isfinite(dF) else math.inf), (model if math.isfinite(model) else math.inf)
