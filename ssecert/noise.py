"""Bounded measurement noise: each sensor's noise within a known bound.

The spec's ``[noise]`` section (``measurement``: one bound for every
sensor or one per sensor; ``norm``: ``"inf"`` for a bound on every sample,
``"2"`` for a bound on the window's samples of the sensor together) reads
into a ``MeasurementNoise``; the certificates under noise
(``ssecert.structure.noise``) take it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .base.validation import as_choice, as_float_option, as_real_matrix

__all__ = ["MeasurementNoise", "NORMS"]

#: the norms a sensor's noise bound may be in
NORMS = ("inf", "2")


@dataclass(frozen=True, eq=False)
class MeasurementNoise:
    """Bounded measurement noise: sensor i's noise is at most ``eta[i]`` in ``norm``.

    Attributes
    ----------
    eta : ndarray of float, shape (p,)
        Per-sensor bounds, nonnegative and finite.
    norm : {"inf", "2"}
        ``"inf"``: every sample |N_i(k)| <= eta_i; ``"2"``: the window's samples of sensor i
        have ||N_i||_2 <= eta_i.
    """

    eta: np.ndarray
    norm: str = "inf"

    def __post_init__(self) -> None:
        eta = np.array(self.eta, dtype=float).reshape(-1)
        if not np.all(np.isfinite(eta)) or np.any(eta < 0):
            raise ValueError(f"noise bounds must be finite and >= 0, got {eta.tolist()}")
        object.__setattr__(self, "eta", eta)
        object.__setattr__(self, "norm", as_choice(self.norm, "norm", NORMS))

    @classmethod
    def uniform(cls, eta: float, p: int, norm: str = "inf") -> MeasurementNoise:
        """The same bound on each of ``p`` sensors."""
        return cls(np.full(p, float(eta)), norm)

    @classmethod
    def read(cls, measurement: Any, p: int, norm: Any = "inf") -> MeasurementNoise:
        """The noise of a ``[noise]`` section: ``measurement`` one bound >= 0 for every sensor
        or a list of ``p`` of them, ``norm`` "inf" or "2".

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
            return cls(eta, norm)
        return cls.uniform(as_float_option(measurement, "measurement", min_value=0.0), p, norm)

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
        return self.norm == other.norm and np.array_equal(self.eta, other.eta)

    __hash__ = None  # type: ignore[assignment]

    def to_dict(self) -> dict[str, Any]:
        """The ``[noise]`` section: ``measurement`` (one bound per sensor) and ``norm``."""
        return {"measurement": self.eta, "norm": self.norm}
