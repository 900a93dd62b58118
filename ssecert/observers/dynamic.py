"""One interface for every dynamic observer, batched over Monte Carlo runs.

An observer holds, for each run, estimates of the state and (for sparse
observers) of the attack or sparse input.  At step k it has x_hat(k) and
receives y(k); ``step`` returns the estimates for k + 1.  Arrays carry the
runs on their first axis: states (runs, n), measurements (runs, m).
"""

from __future__ import annotations

import abc
from dataclasses import dataclass

import numpy as np

__all__ = ["DynamicObserver", "Trajectory"]


@dataclass(frozen=True)
class Trajectory:
    """Estimates over a horizon.

    Attributes
    ----------
    x_hat : ndarray, shape (steps + 1, runs, n)
        ``x_hat[k]`` estimates x(k - delay).
    a_hat : ndarray, shape (steps + 1, runs, m), or None
        Attack (or sparse input) estimates, when the observer has them.
    delay : int
        0 for online observers; tau - 1 for an SSO with window tau, whose
        estimate at time k is of x(k - tau + 1).
    """

    x_hat: np.ndarray
    a_hat: np.ndarray | None
    delay: int = 0


class DynamicObserver(abc.ABC):
    """Base class of dynamic observers (Luenberger, OGD, SSO, D-SSO, elastic net, SISE, ...).

    Subclasses set ``n`` (estimated state size), ``m`` (measurement size)
    and ``delay``, and implement ``initial_state`` and ``step``; ``run``
    loops over time (subclasses may override it with a faster equivalent).
    """

    n: int
    m: int
    delay: int = 0

    @abc.abstractmethod
    def initial_state(self, runs: int) -> dict[str, np.ndarray]:
        """Estimates before the first measurement, arrays with a leading runs axis."""

    @abc.abstractmethod
    def step(self, state: dict[str, np.ndarray], y: np.ndarray) -> dict[str, np.ndarray]:
        """Estimates at k + 1 from those at k and the measurements y(k), shape (runs, m)."""

    def estimate(self, state: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray | None]:
        """(x_hat, a_hat) of a state; a_hat is None for observers without one."""
        return state["x_hat"], state.get("a_hat")

    def run(self, y: np.ndarray, state: dict[str, np.ndarray] | None = None) -> Trajectory:
        """Estimates over a measurement sequence y of shape (steps, runs, m)."""
        y = np.asarray(y, dtype=float)
        steps, runs = y.shape[0], y.shape[1]
        state = self.initial_state(runs) if state is None else state
        x0, a0 = self.estimate(state)
        xs = np.empty((steps + 1,) + x0.shape)
        As = None if a0 is None else np.empty((steps + 1,) + a0.shape)
        xs[0] = x0
        if As is not None:
            As[0] = a0
        for k in range(steps):
            state = self.step(state, y[k])
            xk, ak = self.estimate(state)
            xs[k + 1] = xk
            if As is not None:
                As[k + 1] = ak
        return Trajectory(xs, As, self.delay)
