"""Bounded noise: each sensor's measurement noise and the process noise within known bounds.

The spec's ``[noise]`` section (``measurement``: one bound for every
sensor or one per sensor; ``norm``: ``"inf"`` for a bound on every sample,
``"2"`` for a bound on the window's samples of the sensor together;
``process`` and ``input``: the process noise w(k) of x(k+1) = A x(k) +
G w(k), each entry of w within its bound on every step; ``distribution``
and ``truncation``: how simulations draw noise within the bounds) reads
into a ``MeasurementNoise`` (with its ``ProcessNoise``); the certificates
under noise (``ssecert.structure.noise``, ``ssecert.stability.noise_gain``)
take it.  Every certificate holds for every noise within the bounds,
whatever the distribution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .base.validation import as_choice, as_float_option, as_real_matrix
from .tolerances import interval_product, rows_norm_up, up_by

__all__ = ["DISTRIBUTIONS", "MeasurementNoise", "NORMS", "ProcessNoise"]

#: the norms a sensor's noise bound may be in
NORMS = ("inf", "2")
#: how simulations draw noise within its bounds: uniformly, or Gaussian with standard
#: deviation bound / truncation, truncated at the bound
DISTRIBUTIONS = ("uniform", "gaussian")
DEFAULT_TRUNCATION = 3.0


@dataclass(frozen=True, eq=False)
class ProcessNoise:
    """Bounded process noise: x(k+1) = A x(k) + G w(k) with |w_j(k)| <= omega[j] on every step.

    Attributes
    ----------
    omega : ndarray of float, shape (m,)
        Each entry's bound on every step, nonnegative and finite.
    input : ndarray of float, shape (n, m)
        G, the matrix through which w enters the state.
    """

    omega: np.ndarray
    input: np.ndarray

    def __post_init__(self) -> None:
        omega = np.array(self.omega, dtype=float).reshape(-1)
        G = np.array(self.input, dtype=float)
        if not np.all(np.isfinite(omega)) or np.any(omega < 0):
            raise ValueError(f"process noise bounds must be finite and >= 0, got {omega.tolist()}")
        if G.ndim != 2 or G.shape[1] != omega.size or not np.all(np.isfinite(G)):
            raise ValueError(
                f"process noise input: expected a finite matrix with {omega.size} columns (one "
                f"per bound), got shape {G.shape}"
            )
        object.__setattr__(self, "omega", omega)
        object.__setattr__(self, "input", G)

    @classmethod
    def read(cls, process: Any, input: Any, n: int) -> ProcessNoise:
        """The process noise of a ``[noise]`` section: ``process`` one bound >= 0 or one per
        entry of w, ``input`` G (n x m; default the identity, w one entry per state).

        Examples
        --------
        >>> ProcessNoise.read(0.1, None, 2).input.tolist()
        [[1.0, 0.0], [0.0, 1.0]]
        >>> ProcessNoise.read(0.1, [[1.0], [0.5]], 2).omega.tolist()
        [0.1]
        >>> ProcessNoise.read([0.1, 0.2], [[1.0], [0.5]], 2)
        Traceback (most recent call last):
        ...
        ValueError: process: expected one bound or one per column of input (1), got 2
        """
        G = cls.input_matrix(input, n)
        m = G.shape[1]
        if isinstance(process, (list, tuple, np.ndarray)):
            omega = as_real_matrix(process, "process", ndim=1)
            if omega.size != m:
                raise ValueError(
                    f"process: expected one bound or one per column of input ({m}), got "
                    f"{omega.size}"
                )
            if np.any(omega < 0):
                i = int(np.flatnonzero(omega < 0)[0])
                raise ValueError(f"process must be >= 0, got {omega[i]} on entry {i} (0-based)")
        else:
            omega = np.full(m, as_float_option(process, "process", min_value=0.0))
        return cls(omega, G)

    @property
    def moves_the_state(self) -> bool:
        """Whether some entry of w with a positive bound enters the state (a nonzero column of
        G): without one, the process noise is none."""
        return bool(np.any((self.omega > 0) & np.any(self.input != 0, axis=0)))

    @staticmethod
    def input_matrix(input: Any, n: int) -> np.ndarray:
        """G of a ``[noise]`` section's ``input``: a real matrix with ``n`` rows (the identity
        when None)."""
        if input is None:
            return np.eye(n)
        G = as_real_matrix(input, "input", ndim=2)
        if G.shape[0] != n or G.shape[1] == 0:
            raise ValueError(
                f"input: expected {n} rows (one per state) and at least one column, got shape "
                f"{list(G.shape)}"
            )
        return G

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ProcessNoise):
            return NotImplemented
        return np.array_equal(self.omega, other.omega) and np.array_equal(self.input, other.input)

    __hash__ = None  # type: ignore[assignment]

    def reach(self, A: np.ndarray, C: np.ndarray, horizon: int) -> np.ndarray:
        """r[i, d] >= sum_j |C_i A^d G|_j omega_j for d < horizon - 1: the most the noise of one
        step moves sensor i's reading d + 1 steps later (an upper bound for the exact data,
        every rounding taken up; inf where it leaves the float range), shape (p, horizon - 1).

        Examples
        --------
        >>> w = ProcessNoise.read(0.5, None, 1)
        >>> w.reach(np.array([[2.0]]), np.array([[1.0]]), 3) >= [[0.5, 1.0]]
        array([[ True,  True]])
        """
        A, C = np.asarray(A, dtype=float), np.asarray(C, dtype=float)
        p, n = C.shape
        steps = max(horizon - 1, 0)
        out = np.zeros((p, steps))
        M, R = self.input, np.zeros_like(self.input)  # A^d G, exactly G at d = 0
        zero_A, zero_C = np.zeros_like(A), np.zeros_like(C)
        tiny = 2.0**-1074 * (n + 2)  # underflow: at most a subnormal unit per operation
        with np.errstate(over="ignore", invalid="ignore"):
            for d in range(steps):
                mid, rad = interval_product(C, zero_C, M, R)
                size = np.abs(mid) + rad + tiny * (d + 1)
                # (a product that underflows is taken up by a subnormal unit per term)
                out[:, d] = up_by(size @ self.omega, self.omega.size + 2) + 2.0**-1074 * (
                    self.omega.size + 2
                )
                M, R = interval_product(A, zero_A, M, R)
                R = R + tiny
        return np.where(np.isfinite(out), out, np.inf)

    def to_dict(self) -> dict[str, Any]:
        """``process`` (one bound per entry of w) and ``input`` (G)."""
        return {"process": self.omega, "input": self.input}


@dataclass(frozen=True, eq=False)
class MeasurementNoise:
    """Bounded measurement noise: sensor i's noise is at most ``eta[i]`` in ``norm``; with the
    process noise that comes with it, if any.

    Attributes
    ----------
    eta : ndarray of float, shape (p,)
        Per-sensor bounds, nonnegative and finite.
    norm : {"inf", "2"}
        ``"inf"``: every sample |N_i(k)| <= eta_i; ``"2"``: the window's samples of sensor i
        have ||N_i||_2 <= eta_i.
    process : ProcessNoise or None
        The process noise (``[noise]``'s ``process`` and ``input``).
    distribution : {"uniform", "gaussian"}
        How simulations draw the noise within its bounds (the certificates hold for any).
    truncation : float
        With ``"gaussian"``: the bound in standard deviations (each entry is Gaussian with
        standard deviation bound / truncation, truncated at the bound).
    """

    eta: np.ndarray
    norm: str = "inf"
    process: ProcessNoise | None = None
    distribution: str = "uniform"
    truncation: float = DEFAULT_TRUNCATION

    def __post_init__(self) -> None:
        eta = np.array(self.eta, dtype=float).reshape(-1)
        if not np.all(np.isfinite(eta)) or np.any(eta < 0):
            raise ValueError(f"noise bounds must be finite and >= 0, got {eta.tolist()}")
        object.__setattr__(self, "eta", eta)
        object.__setattr__(self, "norm", as_choice(self.norm, "norm", NORMS))
        object.__setattr__(
            self, "distribution", as_choice(self.distribution, "distribution", DISTRIBUTIONS)
        )
        if self.process is not None and not self.process.moves_the_state:
            object.__setattr__(self, "process", None)  # zero process noise is none
        truncation = as_float_option(self.truncation, "truncation", min_value=0.0)
        if not truncation > 0:
            raise ValueError(f"truncation must be > 0, got {truncation}")
        object.__setattr__(self, "truncation", truncation)

    @classmethod
    def uniform(cls, eta: float, p: int, norm: str = "inf") -> MeasurementNoise:
        """The same bound on each of ``p`` sensors."""
        return cls(np.full(p, float(eta)), norm)

    @classmethod
    def read(cls, measurement: Any, p: int, norm: Any = "inf", **more: Any) -> MeasurementNoise:
        """The noise of a ``[noise]`` section: ``measurement`` one bound >= 0 for every sensor
        or a list of ``p`` of them, ``norm`` "inf" or "2"; ``more``: ``process``,
        ``distribution``, ``truncation`` as the attributes.

        Examples
        --------
        >>> MeasurementNoise.read(1e-4, 2).eta.tolist()
        [0.0001, 0.0001]
        >>> MeasurementNoise.read([0.1, -1.0], 2)
        Traceback (most recent call last):
        ...
        ValueError: measurement must be >= 0 on every sensor, got -1.0 on sensor 1 (0-based)
        """
        norm = as_choice(norm, "norm", NORMS)
        if isinstance(measurement, (list, tuple, np.ndarray)):
            eta = as_real_matrix(measurement, "measurement", ndim=1, shape=(p,),
                                 shape_hint="one bound per sensor")  # fmt: skip
            if np.any(eta < 0):
                i = int(np.flatnonzero(eta < 0)[0])
                raise ValueError(
                    f"measurement must be >= 0 on every sensor, got {eta[i]} on sensor {i} "
                    f"(0-based)"
                )
            return cls(eta, norm, **more)
        bound = as_float_option(measurement, "measurement", min_value=0.0)
        return cls(np.full(p, bound), norm, **more)

    @property
    def per_sample(self) -> bool:
        """Whether each sample is bounded (``norm = "inf"``), rather than a window's samples of
        a sensor together (``"2"``, which bounds each sample by the same number too)."""
        return self.norm == "inf"

    def block_bounds(self, horizon: int) -> np.ndarray:
        """Each sensor's bound on ||N_i||_2 over a window of ``horizon`` steps."""
        return self.eta * math.sqrt(horizon) if self.per_sample else self.eta.copy()

    @staticmethod
    def scale(top: float) -> float:
        """A power of two c >= ``top`` / 2 to divide the bounds by (exactly), so that their
        squares neither under- nor overflow (1 for no noise; at most 2^1023, so a bound at the
        top of the float range is divided into [1, 2))."""
        if not top > 0:
            return 1.0
        return math.ldexp(1.0, min(math.frexp(top)[1], 1023))

    def rows(self, count: int) -> np.ndarray:
        """The bound on each of ``count`` stacked measurement rows, the rows of one sample after
        the other (row r is sensor r mod p): an observer's measurement vector over a window."""
        return self.eta[np.arange(count) % self.eta.size]

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, MeasurementNoise):
            return NotImplemented
        return (
            self.norm == other.norm
            and np.array_equal(self.eta, other.eta)
            and self.process == other.process
            and (self.distribution, self.truncation) == (other.distribution, other.truncation)
        )

    __hash__ = None  # type: ignore[assignment]

    def to_dict(self) -> dict[str, Any]:
        """The ``[noise]`` section: ``measurement`` (one bound per sensor) and ``norm``; with
        process noise ``process`` and ``input``; with a Gaussian distribution ``distribution``
        and ``truncation``."""
        out: dict[str, Any] = {"measurement": self.eta, "norm": self.norm}
        if self.process is not None:
            out.update(self.process.to_dict())
        if self.distribution != "uniform":
            out.update(distribution=self.distribution, truncation=self.truncation)
        return out

    def measurement_only(self) -> MeasurementNoise:
        """The measurement noise alone (no process noise): every noise it allows is one this
        noise allows, so an error reached under it is reached under this noise too."""
        return MeasurementNoise(self.eta, self.norm)

    def at_sensors(self, A: np.ndarray, C: np.ndarray, horizon: int) -> MeasurementNoise | None:
        """The noise a window of ``horizon`` samples from its first state sees at the sensors:
        the measurement noise plus the process noise's reach, y_i(t) = C_i A^t x + sum_(d < t)
        C_i A^d G w(t - 1 - d) + n_i(t), as per-sensor bounds in ``norm`` (an upper bound for
        the exact data).  Itself without process noise; None where the bounds leave the float
        range.  A bound certified for this noise holds for every measurement and process noise
        within their bounds.

        Examples
        --------
        A scalar plant x+ = 2 x + w, |w| <= 0.5, read with noise at most 0.1: over 3 samples
        the last is off by at most 0.1 + 0.5 + 2 * 0.5 = 1.6.

        >>> noise = MeasurementNoise(np.array([0.1]), process=ProcessNoise.read(0.5, None, 1))
        >>> bounds = noise.at_sensors(np.array([[2.0]]), np.array([[1.0]]), 3).eta
        >>> bool(1.6 <= bounds[0] <= 1.6 * (1 + 1e-14))
        True
        """
        if self.process is None:
            return self
        if horizon <= 1:  # the window's one sample: the noise has not reached the state yet
            return self.measurement_only()
        partial = self._partial_reach(A, C, horizon)
        if partial is None:
            return None
        steps = partial.shape[1]
        with np.errstate(over="ignore", invalid="ignore"):
            if self.per_sample:
                extra = partial[:, -1] if steps else np.zeros(self.eta.size)
            else:
                extra = rows_norm_up(partial)
            # the sums' roundings in the subnormal range are absolute: a unit per operation
            eta = up_by(self.eta + extra, 1) + 2.0**-1074 * (steps + 4)
        if not np.all(np.isfinite(eta)):
            return None
        return MeasurementNoise(eta, self.norm)

    def _partial_reach(self, A: np.ndarray, C: np.ndarray, horizon: int) -> np.ndarray | None:
        """(p, horizon - 1): column t - 1 bounds the most the process noise moves sample t
        (1 <= t < horizon) of a window from its first state, the sum of the first t reaches
        (``ProcessNoise.reach``); None where it leaves the float range."""
        assert self.process is not None
        r = self.process.reach(A, C, horizon)
        if not np.all(np.isfinite(r)):
            return None
        steps = r.shape[1]
        with np.errstate(over="ignore", invalid="ignore"):
            partial = up_by(np.cumsum(r, axis=1), steps) if steps else r
        return partial if np.all(np.isfinite(partial)) else None

    def window_rows(self, A: np.ndarray, C: np.ndarray, count: int) -> np.ndarray | None:
        """The bound on each of ``count`` stacked measurement rows over a window of count / p
        samples from its first state (the rows of one sample after the other, as ``rows``):
        row t p + i within eta_i plus the process noise's reach at sample t (the sum of
        ``ProcessNoise.reach`` up to t - 1; every sample of a window within eta_i in either
        norm).  ``rows`` without process noise; None where a bound leaves the float range.

        Examples
        --------
        The scalar plant of ``at_sensors`` over 3 samples: 0.1, 0.1 + 0.5, 0.1 + 0.5 + 1.0.

        >>> noise = MeasurementNoise(np.array([0.1]), process=ProcessNoise.read(0.5, None, 1))
        >>> rows = noise.window_rows(np.array([[2.0]]), np.array([[1.0]]), 3)
        >>> exact = np.array([0.1, 0.6, 1.6])
        >>> bool(np.all(rows >= exact) and np.all(rows <= exact * (1 + 1e-14)))
        True
        """
        p = self.eta.size
        horizon = count // p if p else 0
        if self.process is None or horizon <= 1 or horizon * p != count:
            return self.rows(count)
        partial = self._partial_reach(A, C, horizon)
        if partial is None:
            return None
        with np.errstate(over="ignore", invalid="ignore"):
            reach = np.concatenate([np.zeros((p, 1)), partial], axis=1)  # (p, horizon)
            rows = up_by(self.eta[:, None] + reach, 1) + 2.0**-1074 * 2
            rows[:, 0] = self.eta  # the window's first sample: its measurement noise alone
        if not np.all(np.isfinite(rows)):
            return None
        return np.ascontiguousarray(rows.T).reshape(-1)  # sample-major, as ``rows``
