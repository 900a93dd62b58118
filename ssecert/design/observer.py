"""Observer designs: the ``[observer]`` section turned into matrices.

Every observer is written

    x_hat(k+1) = A x_hat(k) + L (y(k) - y_hat(k)),   y_hat = S x_hat + a_hat,
    a_hat(k+1) = shrink * S_threshold(a_hat(k) - step * L2 (y_hat(k) - y(k))),

with S the sensing matrix (C, or the stacked O_tau for an SSO with window
tau > 1) and the attack estimate absent for Luenberger and online-gradient
observers.  The error matrix of the linear part is F = A - L S.

========  =====================================  =========================
kind      L                                      attack estimate
========  =====================================  =========================
luenberger deadbeat, place, pinv or a matrix     none
ogd       step * A C^T (lecture notes Sec. 4.2)  none
sso       step * A S^T (Algorithm 1, Lasso        shrink 1, L2 = I
          paper; S = O_tau)
dsso      deadbeat (default), pinv, place, matrix shrink 1, L2 = I
elastic_net any                                  shrink in (0, 1), L2
========  =====================================  =========================
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..budget import Budget
from ..system import System
from .gains import Gain, GainError, deadbeat_gain, ogd_gain, pinv_gain, place_gain

__all__ = ["ObserverDesign", "build_observer", "SPARSE_KINDS"]

SPARSE_KINDS = ("sso", "dsso", "elastic_net")


@dataclass(frozen=True)
class ObserverDesign:
    """A fully specified observer for a plant.

    Attributes
    ----------
    kind : str
    system : System
    gain : Gain
        L with its verification.
    sensing : ndarray, shape (m, n)
        Output matrix the observer uses: C, or O_tau for an SSO window.
    step, threshold, shrink : float or None
        nu (or epsilon), lambda and q; None for linear observers.
    L2 : ndarray, shape (m, m), or None
    window, inner_steps : int
    """

    kind: str
    system: System
    gain: Gain
    sensing: np.ndarray
    step: float | None = None
    threshold: float | None = None
    shrink: float = 1.0
    L2: np.ndarray | None = None
    window: int = 1
    inner_steps: int = 1

    @property
    def L(self) -> np.ndarray:
        return self.gain.L

    @property
    def error_matrix(self) -> np.ndarray:
        """The linear error dynamics: F = A - L S, or, for an SSO with m inner ISTA steps per
        sample, A (I - step S^T S)^m (the dynamics while the attack estimate is zero)."""
        if self.kind == "sso" and self.inner_steps > 1:
            n = self.system.n
            inner = np.eye(n) - self.step * self.sensing.T @ self.sensing
            return self.system.A @ np.linalg.matrix_power(inner, self.inner_steps)
        return self.system.A - self.gain.L @ self.sensing

    @property
    def sparse(self) -> bool:
        """True for observers that also estimate the attack."""
        return self.kind in SPARSE_KINDS

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "kind": self.kind,
            "gain_method": self.gain.method,
            "L": self.gain.L,
        }
        if self.sparse:
            out.update(
                step=self.step,
                threshold=self.threshold,
                shrink=self.shrink,
                L2=self.L2,
                window=self.window,
                inner_steps=self.inner_steps,
            )
        return out


def build_observer(
    system: System, spec: Mapping[str, Any], *, budget: Budget | None = None
) -> ObserverDesign:
    """Build an observer from a validated ``[observer]`` section.

    Parameters
    ----------
    system : System
    spec : mapping
        As validated by ``ssecert.spec`` (``Spec.observer``).
    budget : Budget, optional
        Memory allowed for the observer's matrices (default ``Budget()``,
        2 GiB): an SSO with window tau stacks O_tau (p tau x n) and an
        identity L2 of size p tau.

    Returns
    -------
    ObserverDesign

    Raises
    ------
    GainError
        If the requested gain cannot be computed (not observable for a
        deadbeat gain, C not of full column rank for pinv, placement missed,
        O_tau or the gain overflows).
    ResourceLimitError
        If the matrices of an SSO window would exceed the memory budget (the
        message gives the estimate).

    Examples
    --------
    >>> from ssecert.examples import load_example
    >>> spec = load_example("ugv")
    >>> design = build_observer(spec.system, spec.observer)
    >>> design.kind, design.gain.method, design.gain.details["nilpotency_index"]
    ('dsso', 'deadbeat', 1)
    """
    kind = spec["kind"]
    window = int(spec.get("window", 1))
    if window > 1:
        n, m = system.n, system.p * window
        (budget or Budget()).require(
            f"observer.window = {window:,}: the SSO's stacked O_tau ({m:,} x {n}) with its gain "
            f"and {m:,} x {m:,} L2",
            nbytes=8.0 * (3 * m * n + m * m + 2 * n * m),
        )
        with np.errstate(over="ignore", invalid="ignore"):
            sensing = system.observability_matrix(window)
        if not np.all(np.isfinite(sensing)):
            raise GainError(
                f"the stacked observability matrix O_tau overflows for the window "
                f"tau = {window} (C A^k is not finite in floating point)"
            )
    else:
        sensing = system.C
    step = spec.get("step")
    if kind in ("ogd", "sso"):
        if kind == "sso" and window > 1:
            L = step * system.A @ sensing.T
            gain = Gain(
                L=L,
                method="sso",
                error_matrix=system.A - L @ sensing,
                verified=True,
                details={"step": step, "window": window},
            )
        else:
            gain = ogd_gain(system, step)
            if kind == "sso":
                gain = Gain(
                    L=gain.L,
                    method="sso",
                    error_matrix=gain.error_matrix,
                    verified=True,
                    details=gain.details,
                )
    else:
        choice = spec.get("gain", "deadbeat")
        if isinstance(choice, str):
            if choice == "deadbeat":
                gain = deadbeat_gain(system)
            elif choice == "place":
                gain = place_gain(system, spec["poles"])
            elif choice == "pinv":
                gain = pinv_gain(system)
            elif choice == "ogd":
                gain = ogd_gain(system, step)
            else:  # pragma: no cover - the spec validator refuses others
                raise GainError(f"unknown gain {choice!r}")
        else:
            L = np.asarray(choice, dtype=float)
            gain = Gain(
                L=L,
                method="matrix",
                error_matrix=system.A - L @ system.C,
                verified=True,
                details={},
            )
    if not (np.all(np.isfinite(gain.L)) and np.all(np.isfinite(gain.error_matrix))):
        raise GainError(
            "the gain L or the error matrix A - L C has entries that overflow in floating point"
        )
    if kind in SPARSE_KINDS:
        m = sensing.shape[0]
        L2 = np.asarray(spec["L2"], dtype=float) if spec.get("L2") is not None else np.eye(m)
        return ObserverDesign(
            kind=kind,
            system=system,
            gain=gain,
            sensing=sensing,
            step=float(step),
            threshold=float(spec["threshold"]),
            shrink=float(spec.get("shrink", 1.0)),
            L2=L2,
            window=window,
            inner_steps=int(spec.get("inner_steps", 1)),
        )
    return ObserverDesign(
        kind=kind,
        system=system,
        gain=gain,
        sensing=sensing,
        step=None if step is None else float(step),
    )
