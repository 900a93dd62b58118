"""The sparse soft observer (SSO) of the Lasso paper, Algorithm 1.

Spec keys: ``step`` and ``threshold`` (> 0), ``shrink`` (1 if given),
``window`` (tau, default 1) and ``inner_steps`` (ISTA steps per sample,
default 1).  The gain is L = step * A S^T with S = O_tau, the stacked
observability matrix of the window.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .._spec_table import SpecTable
from ..budget import Budget
from ..design.gains import Gain, GainError, ogd_gain
from ..system import System
from ..tolerances import Tolerances
from .base import ObserverDesign, check_finite, parse_unit_shrink
from .dsso import SoftThresholdObserverKind
from .dynamic import DynamicObserver
from .lure import LureModel
from .registry import register
from .simulators import WindowSSO

__all__ = ["SparseSoftObserverKind"]


@register
class SparseSoftObserverKind(SoftThresholdObserverKind):
    name = "sso"
    keys = ("kind", "step", "threshold", "shrink", "window", "inner_steps")

    def parse(self, table: SpecTable, n: int, p: int) -> dict[str, Any]:
        out: dict[str, Any] = {}
        out["step"] = table.positive("step")
        out["threshold"] = table.positive("threshold")
        out["shrink"] = parse_unit_shrink(table, self.name)
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
            L = step * system.A @ sensing.T
            gain = Gain(
                L=L,
                method="sso",
                error_matrix=system.A - L @ sensing,
                verified=True,
                details={"step": step, "window": window},
            )
        else:
            sensing = system.C
            ogd = ogd_gain(system, step)
            gain = Gain(
                L=ogd.L,
                method="sso",
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
        return design.system.A @ np.linalg.matrix_power(inner, design.inner_steps)

    def exact_parts(
        self, design: ObserverDesign
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        return None if design.inner_steps > 1 else super().exact_parts(design)

    def lure_gap(self, design: ObserverDesign) -> str | None:
        if design.inner_steps > 1:
            return (
                f"Certificates for an SSO with {design.inner_steps} inner steps per sample "
                f"are not implemented (the Lur'e model covers one step)."
            )
        return None

    def region_family(self, design: ObserverDesign) -> ObserverDesign | None:
        return None if design.inner_steps > 1 else super().region_family(design)

    def dead_zone_model(self, design: ObserverDesign) -> LureModel | None:
        """With a_hat = 0 and every inner step's threshold input |w| <= threshold, the attack
        estimate stays 0 and each inner ISTA step maps the error by I - step S' S: the error
        follows e+ = A (I - step S' S)^m e, and the threshold inputs of inner step i are
        -step S (I - step S' S)^(i-1) e."""
        if design.inner_steps == 1:
            return None
        n = design.system.n
        S = design.sensing
        nu = design.parameter("step")
        inner = np.eye(n) - nu * S.T @ S
        rows, power = [], np.eye(n)
        for _ in range(design.inner_steps):
            rows.append(-nu * S @ power)
            power = inner @ power
        W = np.vstack(rows)
        return LureModel(
            A=self.error_matrix(design),
            B=np.zeros((n, W.shape[0])),
            Cw=W,
            E=np.zeros((n, S.shape[0])),
            Dw=np.zeros((W.shape[0], S.shape[0])),
            Ce=np.eye(n),
            q=float(design.shrink),
            n_e=n,
            threshold=float(design.threshold or 0.0),
        )

    def simulation_flops(self, design: ObserverDesign) -> float:
        if not self._windowed(design):
            return super().simulation_flops(design)
        n, m = design.system.n, design.sensing.shape[0]
        return design.inner_steps * 2.0 * (n + m) ** 2 + 2.0 * (n + m) * m
