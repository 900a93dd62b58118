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

``SparseSoftObserver.run`` on one run, and ``WindowSSO.run`` on any number
of runs, write every step into one preallocated trajectory (no state dict,
no concatenation, no new array per step) with the arithmetic of the batched
loop and of repeated ``step`` calls respectively, bit for bit: one run of
n = 10 states and 15 sensors costs a few microseconds per step.

Each observer kind (``ssecert.observers``) picks one of these for its
designs; ``ssecert.observers.observer_from_design`` asks it.
"""

from __future__ import annotations

from collections.abc import Iterable

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
    its linear part is a single matrix product per step for all runs.  One
    run (``runs = 1``) takes a loop with the same arithmetic and no
    allocation per step, whose steps are written straight into the
    trajectory; both give the same numbers bit for bit.

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
        runs = y.shape[1]
        st = self.initial_state(runs) if state is None else state
        z = np.hstack([st["x_hat"], st["a_hat"]])
        if runs == 1:
            return self._run_single(z, y)
        return self._run_batched(z, y)

    def _run_batched(self, z: np.ndarray, y: np.ndarray) -> Trajectory:
        """The loop over time for all runs at once, from z = (x_hat, a_hat) of shape (runs, n + m).

        ``run`` uses it for more than one run; on one run it is the loop that ``run``
        used before ``_run_single`` (kept callable so that the two can be compared).
        """
        steps, runs = y.shape[0], y.shape[1]
        n = self.n
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

    def _run_single(self, z: np.ndarray, y: np.ndarray) -> Trajectory:
        """One run: the arithmetic of ``_run_batched`` with no allocation per step.

        Each step writes z(k + 1) straight into its row of the preallocated
        trajectory: one vector-matrix product (``np.dot`` into that row, the same
        BLAS call as ``z @ M^T`` on one row, at less call overhead), the measurement
        term added in place, and the soft threshold in place with one scratch
        vector, in the same order of operations as the batched loop, so that both
        give the same numbers bit for bit.
        """
        steps = y.shape[0]
        n = self.n
        out = np.empty((steps + 1, 1, n + self.m))
        out[0] = z
        injected = y @ self._N_T  # (steps, 1, n + m), the product the batched loop uses
        M_T = self._M_T
        # the scalars as 0-d arrays: a ufunc converts a Python float on every call
        lam, zero, q = np.array(self.threshold), np.array(0.0), np.array(self.shrink)
        shrinks = self.shrink != 1.0
        mag = np.empty((1, self.m))
        dot, add, absolute, subtract = np.dot, np.add, np.absolute, np.subtract
        maximum, sign, multiply = np.maximum, np.sign, np.multiply
        prev = out[0]
        # the output as the last positional argument (parsed faster than out=)
        for cur, a, term in zip(out[1:], out[1:, :, n:], injected):
            dot(prev, M_T, cur)
            add(cur, term, cur)
            absolute(a, mag)
            subtract(mag, lam, mag)
            maximum(mag, zero, out=mag)  # (np.maximum deprecates a positional output)
            sign(a, a)
            multiply(a, mag, a)
            if shrinks:
                multiply(a, q, a)
            prev = cur
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

    def run(self, y: np.ndarray, state: dict[str, np.ndarray] | None = None) -> Trajectory:
        """Estimates over y of shape (steps, runs, m), written into one preallocated array.

        The arithmetic of repeated ``step`` calls, operation for operation (the same
        products with the same operands, the same soft threshold), so that both give
        the same numbers bit for bit; per sample there is no state dict, no
        concatenation and no new array.
        """
        if self.inner_steps < 1:  # no ISTA step: the estimates only move by A
            return super().run(y, state)
        y = np.asarray(y, dtype=float)
        steps, runs = y.shape[0], y.shape[1]
        st = self.initial_state(runs) if state is None else state
        n, width = self.n, self.n + self.O.shape[0]
        out = np.empty((steps + 1, runs, width))
        out[0, :, :n] = st["x_hat"]
        out[0, :, n:] = st["a_hat"]
        # ``step`` runs the ISTA once its window is full: from sample window - 1 - filled on
        first = min(steps, max(0, self.window - 1 - int(st["filled"])))
        out[1 : first + 1] = out[0]  # the estimates wait for the window to fill
        if first < steps:
            if self.threshold < 0:
                raise ValueError(f"threshold must be >= 0, got {self.threshold}")
            self._run_full_windows(out, y, np.asarray(st["buffer"], dtype=float), first)
        return Trajectory(out[:, :, :n], out[:, :, n:], self.delay)

    def _run_full_windows(
        self, out: np.ndarray, y: np.ndarray, buffer: np.ndarray, first: int
    ) -> None:
        """Fill out[first + 1 :] from out[first] (samples first, ... of y have full windows)."""
        steps, runs = y.shape[0], y.shape[1]
        n, window = self.n, self.window
        G_T, H_T, A_T = self._G_T, self._H_T, self.A.T
        terms: Iterable[np.ndarray]
        if window == 1:
            terms = y[first:] @ H_T  # the measurement term of every sample, as ``step`` forms it
        else:
            # the buffer's measurements then y, per run: sample k's window is history[:, k + 1 :][:window]
            history = np.concatenate([buffer, y.transpose(1, 0, 2)], axis=1)
            terms = (
                history[:, k + 1 : k + 1 + window].reshape(runs, -1) @ H_T
                for k in range(first, steps)
            )
        # one row: np.dot, the BLAS call of ``@`` on one row at less call overhead
        product = np.dot if runs == 1 else np.matmul
        scratch = np.empty((2, runs, out.shape[2]))
        # inner step i writes scratch[i % 2] (references to two pairs of views, not copies)
        pairs = [(z, z[:, n:]) for z in scratch]
        inner = pairs * (self.inner_steps // 2) + pairs[: self.inner_steps % 2]
        last_x, last_a = inner[-1][0][:, :n], inner[-1][1]
        mag = np.empty((runs, out.shape[2] - n))
        # the scalars as 0-d arrays (a ufunc converts a Python float on every call), the
        # outputs as the last positional argument (parsed faster than out=)
        lam, zero = np.array(self.threshold), np.array(0.0)
        add, absolute, subtract = np.add, np.absolute, np.subtract
        maximum, sign, multiply = np.maximum, np.sign, np.multiply
        for term, z, row_x, row_a in zip(
            terms, out[first:], out[first + 1 :, :, :n], out[first + 1 :, :, n:]
        ):
            for nxt, a in inner:
                product(z, G_T, nxt)
                add(nxt, term, nxt)
                # soft_threshold(a, threshold), in place
                absolute(a, mag)
                subtract(mag, lam, mag)
                maximum(mag, zero, out=mag)  # (np.maximum deprecates a positional output)
                sign(a, a)
                multiply(a, mag, a)
                z = nxt
            product(last_x, A_T, row_x)
            row_a[...] = last_a

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
