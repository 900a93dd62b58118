"""Dynamic observers, batched over Monte Carlo runs.

All follow ssecert's convention x_hat(k+1) = A x_hat(k) + L (y(k) - y_hat(k))
(the thesis's L1 is -L):

* ``LinearObserver``: Luenberger and online-gradient observers
  (y_hat = C x_hat);
* ``SparseSoftObserver``: the D-SSO and the elastic-net observer of the
  thesis, and the SSO of the Lasso paper with window 1 and one inner step
  (L = step A C^T):

      y_hat = C x_hat + a_hat,   r = y - y_hat,
      x_hat+ = A x_hat + L r,    a_hat+ = shrink * S_threshold(a_hat + step L2 r);

* ``WindowSSO``: Algorithm 1 of the Lasso paper with window tau and
  repeated inner ISTA steps: at time k >= tau - 1 it stacks the last tau
  measurements, runs ``inner_steps`` ISTA steps on (x_hat, a_hat) for the
  stacked model y = O_tau x(k - tau + 1) + a, and moves x_hat forward by A.
  Its estimate at time k is of x(k - tau + 1) (``delay = tau - 1``).  As in
  the paper, the stacked attack estimate is not shifted when the window
  moves (the attack support is taken as constant).

Each observer kind (``ssecert.observers``) picks one of these for its
designs; ``ssecert.observers.observer_from_design`` asks it.
"""

from __future__ import annotations

import numpy as np

from .dynamic import DynamicObserver, Trajectory
from .shrinkage import soft_threshold

__all__ = ["LinearObserver", "SparseSoftObserver", "WindowSSO"]


class LinearObserver(DynamicObserver):
    """x_hat+ = A x_hat + L (y - C x_hat), batched over runs.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    C : ndarray, shape (m, n)
    L : ndarray, shape (n, m)

    Examples
    --------
    >>> import numpy as np
    >>> obs = LinearObserver(np.array([[1.0]]), np.array([[1.0]]), np.array([[1.0]]))
    >>> obs.run(np.full((3, 2, 1), 5.0)).x_hat[-1].ravel().tolist()
    [5.0, 5.0]
    """

    def __init__(self, A: np.ndarray, C: np.ndarray, L: np.ndarray) -> None:
        self.A, self.C, self.L = (np.asarray(M, dtype=float) for M in (A, C, L))
        self.n, self.m = self.A.shape[0], self.C.shape[0]
        self._F_T = (self.A - self.L @ self.C).T
        self._L_T = self.L.T

    def initial_state(self, runs: int) -> dict[str, np.ndarray]:
        return {"x_hat": np.zeros((runs, self.n))}

    def step(self, state: dict[str, np.ndarray], y: np.ndarray) -> dict[str, np.ndarray]:
        return {"x_hat": state["x_hat"] @ self._F_T + y @ self._L_T}

    def run(self, y: np.ndarray, state: dict[str, np.ndarray] | None = None) -> Trajectory:
        y = np.asarray(y, dtype=float)
        steps, runs = y.shape[0], y.shape[1]
        x = (self.initial_state(runs) if state is None else state)["x_hat"]
        out = np.empty((steps + 1, runs, self.n))
        out[0] = x
        injected = y @ self._L_T  # all input terms in one product
        for k in range(steps):
            x = x @ self._F_T
            x += injected[k]
            out[k + 1] = x
        return Trajectory(out, None, 0)


class SparseSoftObserver(DynamicObserver):
    """D-SSO / elastic-net observer / SSO (window 1), batched over runs.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    C : ndarray, shape (m, n)
    L : ndarray, shape (n, m)
    step : float
        nu (the thesis's epsilon for the elastic-net observer).
    threshold : float
        Level of the soft threshold applied each step.
    shrink : float, default 1
        q; 1 for SSO and D-SSO.
    L2 : ndarray, shape (m, m), optional
        Default identity.

    Notes
    -----
    The error state is propagated as one stacked array z = (x_hat, a_hat):
    its linear part is a single matrix product per step for all runs.

    Examples
    --------
    >>> import numpy as np
    >>> obs = SparseSoftObserver(np.eye(1), np.ones((3, 1)), np.ones((1, 3)) / 3,
    ...                          step=0.5, threshold=0.1)
    >>> y = np.tile([1.0, 1.0, 9.0], (200, 1, 1))   # sensor 2 attacked by +8
    >>> traj = obs.run(y)
    >>> int(np.argmax(abs(traj.a_hat[-1, 0])))   # the attacked sensor is found
    2
    >>> round(float(traj.x_hat[-1, 0, 0]), 3)    # x = 1, with the Lasso bias threshold / step
    1.1
    """

    def __init__(
        self,
        A: np.ndarray,
        C: np.ndarray,
        L: np.ndarray,
        *,
        step: float,
        threshold: float,
        shrink: float = 1.0,
        L2: np.ndarray | None = None,
    ) -> None:
        self.A, self.C, self.L = (np.asarray(M, dtype=float) for M in (A, C, L))
        self.n, self.m = self.A.shape[0], self.C.shape[0]
        self.step_size, self.threshold, self.shrink = float(step), float(threshold), float(shrink)
        self.L2 = np.eye(self.m) if L2 is None else np.asarray(L2, dtype=float)
        m = self.m
        nuL2 = self.step_size * self.L2
        # z+ (before shrinkage of the a-part) = z @ M^T + y @ N^T
        M = np.block([[self.A - self.L @ self.C, -self.L], [-nuL2 @ self.C, np.eye(m) - nuL2]])
        N = np.vstack([self.L, nuL2])
        self._M_T = np.ascontiguousarray(M.T)
        self._N_T = np.ascontiguousarray(N.T)

    def initial_state(self, runs: int) -> dict[str, np.ndarray]:
        return {"x_hat": np.zeros((runs, self.n)), "a_hat": np.zeros((runs, self.m))}

    def step(self, state: dict[str, np.ndarray], y: np.ndarray) -> dict[str, np.ndarray]:
        z = np.hstack([state["x_hat"], state["a_hat"]]) @ self._M_T + y @ self._N_T
        a = self.shrink * soft_threshold(z[:, self.n :], self.threshold)
        return {"x_hat": z[:, : self.n], "a_hat": a}

    def run(self, y: np.ndarray, state: dict[str, np.ndarray] | None = None) -> Trajectory:
        y = np.asarray(y, dtype=float)
        steps, runs = y.shape[0], y.shape[1]
        st = self.initial_state(runs) if state is None else state
        n = self.n
        z = np.hstack([st["x_hat"], st["a_hat"]])
        out = np.empty((steps + 1, runs, n + self.m))
        out[0] = z
        injected = y @ self._N_T
        q, lam = self.shrink, self.threshold
        for k in range(steps):
            z = z @ self._M_T
            z += injected[k]
            a = z[:, n:]
            # in-place q * soft_threshold(a, lam)
            mag = np.abs(a)
            mag -= lam
            np.maximum(mag, 0.0, out=mag)
            np.sign(a, out=a)
            a *= mag
            if q != 1.0:
                a *= q
            out[k + 1] = z
        return Trajectory(out[:, :, :n], out[:, :, n:], 0)


class WindowSSO(DynamicObserver):
    """Sparse soft observer of the Lasso paper (Algorithm 1), window tau, inner steps.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    C : ndarray, shape (p, n)
    step : float
        nu.
    threshold : float
        Level of the soft threshold (the paper's S_(nu lambda) is
        threshold = nu * lambda).
    window : int, default 1
        tau.
    inner_steps : int, default 1
        ISTA steps per sample (the paper repeats step 3 5 tau times).

    Examples
    --------
    >>> import numpy as np
    >>> obs = WindowSSO(np.eye(1), np.ones((3, 1)), step=0.25, threshold=0.05, window=2)
    >>> obs.delay, obs.m
    (1, 3)
    """

    def __init__(
        self,
        A: np.ndarray,
        C: np.ndarray,
        *,
        step: float,
        threshold: float,
        window: int = 1,
        inner_steps: int = 1,
    ) -> None:
        self.A, self.C = np.asarray(A, dtype=float), np.asarray(C, dtype=float)
        self.n, self.m = self.A.shape[0], self.C.shape[0]
        self.window, self.inner_steps = int(window), int(inner_steps)
        self.delay = self.window - 1
        self.step_size, self.threshold = float(step), float(threshold)
        blocks = [self.C]
        for _ in range(self.window - 1):
            blocks.append(blocks[-1] @ self.A)
        self.O = np.vstack(blocks)  # (p tau, n), step-major
        nu = self.step_size
        mp = self.O.shape[0]
        G = np.block(
            [
                [np.eye(self.n) - nu * self.O.T @ self.O, -nu * self.O.T],
                [-nu * self.O, (1 - nu) * np.eye(mp)],
            ]
        )
        H = np.vstack([nu * self.O.T, nu * np.eye(mp)])
        self._G_T = np.ascontiguousarray(G.T)
        self._H_T = np.ascontiguousarray(H.T)

    def initial_state(self, runs: int) -> dict[str, np.ndarray]:
        return {
            "x_hat": np.zeros((runs, self.n)),
            "a_hat": np.zeros((runs, self.O.shape[0])),
            "buffer": np.zeros((runs, self.window, self.m)),
            "filled": np.zeros((), dtype=np.int64),
        }

    def step(self, state: dict[str, np.ndarray], y: np.ndarray) -> dict[str, np.ndarray]:
        buffer = np.concatenate([state["buffer"][:, 1:], y[:, None, :]], axis=1)
        filled = int(state["filled"]) + 1
        x, a = state["x_hat"], state["a_hat"]
        if filled >= self.window:
            stacked = buffer.reshape(buffer.shape[0], -1)
            x, a = self._ista(x, a, stacked)
            x = x @ self.A.T
        return {
            "x_hat": x,
            "a_hat": a,
            "buffer": buffer,
            "filled": np.asarray(min(filled, self.window)),
        }

    def _ista(
        self, x: np.ndarray, a: np.ndarray, stacked: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        n = self.n
        z = np.hstack([x, a])
        injected = stacked @ self._H_T
        for _ in range(self.inner_steps):
            z = z @ self._G_T + injected
            z[:, n:] = soft_threshold(z[:, n:], self.threshold)
        return z[:, :n], z[:, n:]
