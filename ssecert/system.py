"""The plant: x(k+1) = A x(k), y(k) = C x(k) + a(k)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .base.validation import as_int_option, as_real_matrix, describe

__all__ = ["System"]


@dataclass(frozen=True, eq=False)
class System:
    """A discrete-time LTI plant whose p sensors may be attacked.

    ``x(k+1) = A x(k)``, ``y(k) = C x(k) + a(k)`` with ``x`` in R^n and
    ``y`` in R^p; row ``i`` of ``C`` is sensor ``i`` (0-based).

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix, real and finite.
    C : array_like, shape (p, n)
        Output matrix, one row per sensor, at least one sensor.
    sensors : sequence of str, optional
        Unique sensor names; default ``y1``, ..., ``yp`` (1-based, for people).
    name : str, default "system"
        Name used in reports.

    Raises
    ------
    TypeError
        If a matrix has non-real entries or a name is not a string.
    ValueError
        If a matrix has the wrong shape or non-finite entries, or the sensor
        names are not unique.

    Examples
    --------
    >>> sys = System([[1.0, 0.0099], [0.0, 0.9876]], [[1, 0], [0, 1], [0, 1]],
    ...              sensors=["position", "velocity-a", "velocity-b"], name="ugv")
    >>> sys.n, sys.p
    (2, 3)
    >>> sys.observability_matrix(2).shape
    (6, 2)
    """

    A: np.ndarray
    C: np.ndarray
    # None (default names) is resolved to a tuple in __post_init__; a dataclass field
    # cannot type its __init__ argument apart from the stored value.
    sensors: tuple[str, ...] = field(default=None)  # type: ignore[arg-type]
    name: str = "system"

    def __post_init__(self) -> None:
        A = as_real_matrix(self.A, "A")
        if A.shape[0] != A.shape[1]:
            raise ValueError(f"A must be square, got shape {A.shape}")
        n = A.shape[0]
        C = as_real_matrix(self.C, "C", shape=(None, n), shape_hint="the number of states, from A")
        if not isinstance(self.name, str) or not self.name.strip():
            raise TypeError(f"name must be a non-empty string, got {describe(self.name)}")
        p = C.shape[0]
        if self.sensors is None:
            sensors = tuple(f"y{i + 1}" for i in range(p))
        else:
            if isinstance(self.sensors, str) or not isinstance(self.sensors, Sequence):
                raise TypeError(f"sensors must be a list of names, got {describe(self.sensors)}")
            sensors = tuple(self.sensors)
            if len(sensors) != p:
                raise ValueError(
                    f"sensors has the wrong length: expected {p} (the number of rows of C), "
                    f"got {len(sensors)}"
                )
            for i, label in enumerate(sensors):
                if not isinstance(label, str) or not label.strip():
                    raise TypeError(
                        f"sensors[{i}] must be a non-empty string, got {describe(label)}"
                    )
            seen: dict[str, int] = {}
            for i, label in enumerate(sensors):
                if label in seen:
                    raise ValueError(
                        f"sensors must be unique: {label!r} names sensors {seen[label]} and {i}"
                    )
                seen[label] = i
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "C", C)
        object.__setattr__(self, "sensors", sensors)

    @classmethod
    def from_control(
        cls, sys: Any, *, sensors: Sequence[str] | None = None, name: str | None = None
    ) -> System:
        """The plant of a discrete-time python-control ``StateSpace`` (``control.ss(A, B, C,
        D, dt)``, dt > 0 or True).

        B and D are not used: a known input enters the plant and the estimate alike and
        cancels in the estimation error, so it changes no verdict (an observer exported back,
        ``ObserverDesign.to_control(plant)``, takes it as an input).  The sensors are named
        after the system's output labels unless ``sensors`` is given.

        Raises
        ------
        TypeError
            If ``sys`` is not a python-control state-space system (a transfer function is
            converted by ``control.ss`` first).
        ValueError
            If ``sys`` is a continuous-time system (discretise it first, for example with
            ``control.c2d(sys, Ts)``).

        Examples
        --------
        >>> import control as ct
        >>> plant = ct.ss([[1.0, 0.0099], [0.0, 0.9876]], [[0.0], [1.0]],
        ...               [[1, 0], [0, 1], [0, 1]], 0, 0.01, outputs=["pos", "vel-a", "vel-b"])
        >>> System.from_control(plant, name="ugv").sensors
        ('pos', 'vel-a', 'vel-b')
        """
        if not all(hasattr(sys, key) for key in ("A", "C", "dt")):
            raise TypeError(
                "sys must be a python-control StateSpace (control.ss(A, B, C, D, dt)), got "
                f"{describe(sys)}"
            )
        discrete_time(sys, "sys", "discretise it first, for example with control.c2d(sys, Ts)")
        labels = getattr(sys, "output_labels", None)
        if sensors is None and labels is not None and len(labels) == np.shape(sys.C)[0]:
            sensors = [str(label) for label in labels]
        given = str(getattr(sys, "name", "") or "")
        if not given or given.startswith("sys["):  # python-control's generated name
            given = "system"
        _check_unused(sys, "sys")
        return cls._from_matrices(sys.A, sys.C, sensors, name or given)

    @classmethod
    def from_scipy(
        cls, sys: Any, *, sensors: Sequence[str] | None = None, name: str = "system"
    ) -> System:
        """The plant of a discrete-time ``scipy.signal.dlti`` (state space, transfer function
        or zeros-poles-gain, converted by ``to_ss``).  B and D are not used (see
        ``from_control``).

        Raises
        ------
        TypeError
            If ``sys`` is not a ``scipy.signal`` LTI system.
        ValueError
            If ``sys`` is continuous-time (``scipy.signal.lti``: discretise it first, for
            example with its ``to_discrete(dt)``).

        Examples
        --------
        >>> from scipy import signal
        >>> plant = signal.dlti([[0.5, 1.0], [0.0, 0.7]], [[0.0], [1.0]], [[1.0, 0.0]], [[0.0]],
        ...                     dt=0.1)
        >>> System.from_scipy(plant).C
        array([[1., 0.]])
        """
        from scipy import signal

        if not isinstance(sys, signal.lti) and not isinstance(sys, signal.dlti):
            raise TypeError(f"sys must be a scipy.signal dlti system, got {describe(sys)}")
        if not isinstance(sys, signal.dlti):
            raise ValueError(
                "sys must be a discrete-time system (scipy.signal.dlti), got a continuous-time "
                "scipy.signal.lti: discretise it first, for example with sys.to_discrete(dt)"
            )
        ss = sys.to_ss()
        _check_unused(ss, "sys")
        return cls._from_matrices(ss.A, ss.C, sensors, name)

    @classmethod
    def _from_matrices(cls, A: Any, C: Any, sensors: Sequence[str] | None, name: str) -> System:
        names = sensors if sensors is None or isinstance(sensors, str) else tuple(sensors)
        # (as given: the constructor refuses complex data rather than dropping its imaginary part)
        return cls(np.asarray(A), np.asarray(C), names, name)  # type: ignore[arg-type]

    @property
    def n(self) -> int:
        """Number of states."""
        return self.A.shape[0]

    @property
    def p(self) -> int:
        """Number of sensors."""
        return self.C.shape[0]

    def __eq__(self, other: Any) -> bool:
        if not isinstance(other, System):
            return NotImplemented
        return (
            self.name == other.name
            and self.sensors == other.sensors
            and np.array_equal(self.A, other.A)
            and np.array_equal(self.C, other.C)
        )

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"System(name={self.name!r}, n={self.n}, p={self.p})"

    def _horizon(self, horizon: int | None) -> int:
        if horizon is None:
            return self.n
        return as_int_option(horizon, "horizon", min_value=1)

    def sensor_blocks(self, horizon: int | None = None) -> np.ndarray:
        """Per-sensor rows of the observability matrix.

        Parameters
        ----------
        horizon : int, optional
            Number of steps tau; default n.

        Returns
        -------
        numpy.ndarray, shape (p, tau, n)
            ``blocks[i, k] = C[i] @ A^k``.
        """
        tau = self._horizon(horizon)
        blocks = np.empty((self.p, tau, self.n))
        row = np.array(self.C)
        for k in range(tau):
            blocks[:, k, :] = row
            if k + 1 < tau:
                row = row @ self.A
        return blocks

    def observability_matrix(self, horizon: int | None = None) -> np.ndarray:
        """Stacked observability matrix O_tau = [C; C A; ...; C A^(tau-1)].

        Parameters
        ----------
        horizon : int, optional
            Number of steps tau; default n.

        Returns
        -------
        numpy.ndarray, shape (p * tau, n)
            Row ``k * p + i`` is sensor ``i`` at step ``k``.
        """
        blocks = self.sensor_blocks(horizon)
        return np.ascontiguousarray(blocks.transpose(1, 0, 2).reshape(-1, self.n))

    def select_sensors(self, keep: Sequence[int]) -> System:
        """The plant seen through the sensors ``keep`` only (0-based, in order)."""
        from .base.validation import as_index_list

        keep = as_index_list(keep, "keep", upper=self.p)
        if not keep:
            raise ValueError("keep must name at least one sensor")
        return System(
            self.A, self.C[list(keep)], sensors=tuple(self.sensors[i] for i in keep), name=self.name
        )

    def to_dict(self) -> dict[str, Any]:
        """Identity of the system for JSON: name, n, p and sensor names."""
        return {"name": self.name, "n": self.n, "p": self.p, "sensors": list(self.sensors)}


def _check_unused(sys: Any, name: str) -> None:
    """B and D of a library's system, real and finite: they are not used, but a NaN, an inf
    or a complex entry there is a broken model, not one to certify."""
    for key in ("B", "D"):
        value = getattr(sys, key, None)
        if value is not None and np.size(value):
            as_real_matrix(np.atleast_2d(np.asarray(value)), f"{name}.{key}")


def discrete_time(sys: Any, name: str, hint: str) -> Any:
    """The sampling time of a python-control system, which must be discrete (dt > 0 or
    True); ValueError naming ``name`` with ``hint`` otherwise."""
    dt = sys.dt
    if dt is None or dt is False or (not isinstance(dt, bool) and float(dt) == 0.0):
        raise ValueError(
            f"{name} must be a discrete-time system (dt > 0 or True), got dt = {dt!r}: {hint}"
        )
    return dt
