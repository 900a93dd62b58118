"""Memory and work budgets: estimate from the shapes, then run or refuse.

Every analysis whose cost grows with an option (the horizon tau, the SSO
window, the number of attack supports, the runs and steps of a scenario)
estimates its peak memory in bytes and its work in floating-point operations
from the shapes alone, before allocating anything, and compares them with a
``Budget``.  What does not fit is not attempted: a check becomes inconclusive,
a simulation is refused, and the message states the estimate and the budget.

Defaults: 2 GiB of memory (``--memory-budget``) and 1e12 floating-point
operations per analysis step (``--work-budget``; about one to two minutes of
one core).  Estimates are upper bounds of the dominant arrays and operation
counts, not measurements.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import re
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from enum import StrEnum
from typing import Protocol, TypeVar

__all__ = [
    "Budget",
    "Refusal",
    "Resource",
    "ResourceLimitError",
    "DEFAULT_MEMORY",
    "DEFAULT_WORK",
    "DEFAULT_TIME_BUDGET",
    "format_bytes",
    "format_count",
    "parse_bytes",
    "parse_operations",
    "bounded_comb",
    "log10_comb",
    "StageListener",
    "stage",
    "watching_stages",
]

DEFAULT_MEMORY = 2 * 2**30  # bytes
DEFAULT_WORK = 1e12  # floating-point operations
# seconds spent refining max_removable once the verdict is settled (None: exact, however long)
DEFAULT_TIME_BUDGET = 5.0


class ResourceLimitError(ValueError):
    """A request whose estimated memory or work exceeds the budget.

    The message names what was requested, the estimate and the budget.
    """


def format_bytes(size: float) -> str:
    """``6.39 PiB``-style size, binary prefixes.

    Examples
    --------
    >>> format_bytes(2 * 2**30), format_bytes(1536)
    ('2 GiB', '1.5 KiB')
    """
    size = float(size)
    if not math.isfinite(size):
        return "an unbounded amount of memory"
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"):
        if abs(size) < 1024 or unit == "EiB":
            text = f"{size:.3g}"
            return f"{text} {unit}"
        size /= 1024
    raise AssertionError("unreachable")  # pragma: no cover


def format_count(value: float) -> str:
    """An exact count below 1e9 (``12,345``), a rounded power of ten above.

    Examples
    --------
    >>> format_count(12345), format_count(2.7e299)
    ('12,345', 'about 2.7e+299')
    """
    if isinstance(value, int) and value < 10**9:
        return f"{value:,}"
    if isinstance(value, int) and value.bit_length() > 1000:  # beyond the float range
        digits = len(str(value))
        return f"about {str(value)[0]}.{str(value)[1]}e+{digits - 1}"
    value = float(value)
    if value < 1e9:
        return f"{int(value):,}"
    return f"about {value:.2g}"


_SIZE_RE = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([KMGTP]?)(i?B?)\s*$", re.I)


def parse_bytes(text: str) -> int:
    """Parse ``"512M"``, ``"2G"``, ``"2GiB"``, ``"1.5e9"`` (bytes; K, M, G are powers of 1024).

    Raises
    ------
    ValueError
        With the accepted forms, for anything else or for a size below 1 MiB.

    Examples
    --------
    >>> parse_bytes("2G"), parse_bytes("512MiB"), parse_bytes("3e9")
    (2147483648, 536870912, 3000000000)
    """
    match = _SIZE_RE.match(str(text))
    if not match:
        raise ValueError(f"expected a size such as 512M, 2G or 2GiB, got {text!r}")
    number, prefix = float(match.group(1)), match.group(2).upper()
    size = number * 1024 ** "KMGTP".find(prefix) * 1024 if prefix else number
    if not math.isfinite(size) or size < 2**20:
        raise ValueError(f"expected a size of at least 1M, got {text!r}")
    return int(size)


def parse_operations(text: str) -> float:
    """Parse a number of floating-point operations such as ``1e12`` (at least 1e6).

    Raises
    ------
    ValueError
        For anything else.

    Examples
    --------
    >>> parse_operations("5e11")
    500000000000.0
    """
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"expected a number of operations such as 1e12, got {text!r}") from None
    if not (value >= 1e6 and math.isfinite(value)):
        raise ValueError(f"expected a finite number of operations >= 1e6, got {text!r}")
    return value


def bounded_comb(n: int, k: int, cap: int) -> int | None:
    """C(n, k) when it is at most ``cap``, else None, in time independent of n and k.

    Examples
    --------
    >>> bounded_comb(10, 3, 1000), bounded_comb(10**12, 10**6, 10**9)
    (120, None)
    """
    if k < 0 or k > n:
        return 0
    k = min(k, n - k)
    value = 1
    for j in range(1, k + 1):
        value = value * (n - k + j) // j
        if value > cap:
            return None
    return value


def log10_comb(n: int, k: int) -> float:
    """log10 C(n, k) from log-gamma, for counts too large to form."""
    if k < 0 or k > n:
        return -math.inf
    return (math.lgamma(n + 1) - math.lgamma(k + 1) - math.lgamma(n - k + 1)) / math.log(10)


class Resource(StrEnum):
    """What a refused analysis step would need too much of."""

    MEMORY = "memory"  # bytes, over ``Budget.memory``
    WORK = "work"  # floating-point operations, over ``Budget.work``
    ROWS = "rows"  # rows of an LMI, over a fixed limit of its own


@dataclass(frozen=True)
class Refusal:
    """An analysis step not attempted: what it is, what it would need and what it may have.

    ``str()`` is the sentence a report shows; code reads the fields.

    Examples
    --------
    >>> r = Budget(memory=2**30).check("a matrix", nbytes=3 * 2**30)
    >>> r.resource, r.need / r.limit
    (<Resource.MEMORY: 'memory'>, 3.0)
    >>> str(r)
    'a matrix needs about 3 GiB of memory, over the memory budget of 1 GiB (--memory-budget)'
    """

    what: str
    resource: Resource
    need: float
    limit: float

    def __str__(self) -> str:
        if self.resource is Resource.MEMORY:
            return (
                f"{self.what} needs about {format_bytes(self.need)} of memory, over the memory "
                f"budget of {format_bytes(self.limit)} (--memory-budget)"
            )
        if self.resource is Resource.WORK:
            need, have = _apart(self.need, self.limit)
            return (
                f"{self.what} needs about {need} floating-point operations, over the work "
                f"budget of {have} (--work-budget)"
            )
        return f"{self.what} has {self.need:.0f} rows, more than {self.limit:.0f}"


@dataclass(frozen=True)
class Budget:
    """Largest memory and work an analysis step may use.

    Parameters
    ----------
    memory : int, default 2 GiB
        Bytes for the arrays of one analysis step (estimated before they are
        allocated).
    work : float, default 1e12
        Floating-point operations of one analysis step (one LMI solve, one
        enumeration, one scenario's simulation).

    Examples
    --------
    >>> Budget().refusal("O_tau", nbytes=6.39 * 2**50)[:39]
    'O_tau needs about 6.39 PiB of memory, o'
    >>> Budget().refusal("a small product", nbytes=800, flops=1e3)
    ''
    """

    memory: int = DEFAULT_MEMORY
    work: float = DEFAULT_WORK

    def __post_init__(self) -> None:
        if not (isinstance(self.memory, (int, float)) and self.memory > 0):
            raise ValueError(f"memory must be a positive number of bytes, got {self.memory!r}")
        if not (isinstance(self.work, (int, float)) and self.work > 0):
            raise ValueError(f"work must be a positive number of operations, got {self.work!r}")

    def check(self, what: str, *, nbytes: float = 0.0, flops: float = 0.0) -> Refusal | None:
        """None when ``what`` fits; otherwise the ``Refusal`` (memory first)."""
        if nbytes > self.memory:
            return Refusal(what, Resource.MEMORY, nbytes, self.memory)
        if flops > self.work:
            return Refusal(what, Resource.WORK, flops, self.work)
        return None

    def refusal(self, what: str, *, nbytes: float = 0.0, flops: float = 0.0) -> str:
        """Empty when ``what`` fits; otherwise the reason, with estimate and budget (the
        words of ``check``)."""
        refused = self.check(what, nbytes=nbytes, flops=flops)
        return "" if refused is None else str(refused)

    def require(self, what: str, *, nbytes: float = 0.0, flops: float = 0.0) -> None:
        """Raise ``ResourceLimitError`` with the reason when ``what`` does not fit."""
        refused = self.check(what, nbytes=nbytes, flops=flops)
        if refused is not None:
            raise ResourceLimitError(str(refused))

    def to_dict(self) -> dict[str, float]:
        return {"memory_bytes": self.memory, "work_flops": self.work}


def _apart(a: float, b: float) -> tuple[str, str]:
    """``a`` and ``b`` in two significant digits, or as many more as tell them apart
    (1.0000001e12 over a budget of 1e12 is not "1e+12 over 1e+12")."""
    for digits in range(2, 18):
        left, right = f"{a:.{digits}g}", f"{b:.{digits}g}"
        if left != right:
            return left, right
    return f"{a!r}", f"{b!r}"


_T = TypeVar("_T")


# who is told of each step as it ends (``reporting``): the command line's --verbose
_REPORT: contextvars.ContextVar[Callable[[str, float], None] | None] = contextvars.ContextVar(
    "ssecert_step_report", default=None
)


@contextlib.contextmanager
def reporting(report: Callable[[str, float], None]) -> Iterator[None]:
    """Call ``report(step, seconds)`` as each step of the analyses ends (every ``Laps.lap``:
    the checks of ``analyze`` and the observer checks), within the ``with`` block."""
    token = _REPORT.set(report)
    try:
        yield
    finally:
        _REPORT.reset(token)


class StageListener(Protocol):
    """Told when each stage of an analysis begins and ends (``watching_stages``)."""

    def begin(self, name: str) -> None:
        """Stage ``name`` begins (inside the stages begun and not yet ended)."""

    def end(self, name: str, seconds: float) -> None:
        """Stage ``name``, the innermost one begun, ends after ``seconds``."""


# who is told of each stage as it begins and ends (``watching_stages``): the progress display
_STAGES: contextvars.ContextVar[StageListener | None] = contextvars.ContextVar(
    "ssecert_stages", default=None
)


@contextlib.contextmanager
def watching_stages(listener: StageListener) -> Iterator[None]:
    """Tell ``listener`` of each stage (``stage``, and every step of a ``Laps``) as it begins
    and ends, within the ``with`` block.  Stages nest: a step of the observer checks begins and
    ends inside the step ``observer_checks`` of ``analyze``.

    Examples
    --------
    >>> class Printed:
    ...     def begin(self, name): print("begin", name)
    ...     def end(self, name, seconds): print("end", name)
    >>> with watching_stages(Printed()), stage("outer"), stage("inner"):
    ...     pass
    begin outer
    begin inner
    end inner
    end outer
    """
    token = _STAGES.set(listener)
    try:
        yield
    finally:
        _STAGES.reset(token)


@contextlib.contextmanager
def stage(name: str) -> Iterator[None]:
    """A stage of an analysis named ``name`` (say ``"piecewise LMIs, radius 10"``), told to the
    ``watching_stages`` listener as it begins and ends; nothing without one."""
    listener = _STAGES.get()
    if listener is None:
        yield
        return
    start = time.monotonic()
    listener.begin(name)
    try:
        yield
    finally:
        listener.end(name, time.monotonic() - start)


class Laps:
    """Wall-clock seconds of each step of a run, into ``seconds`` (the caller's dict when
    given), for the certificate's ``meta.timings``; each step is also told to the ``reporting``
    callback when there is one, and to the ``watching_stages`` listener as it begins
    (``begin``) and ends."""

    def __init__(self, seconds: dict[str, float] | None = None) -> None:
        self.start = self.last = time.monotonic()
        self.seconds: dict[str, float] = {} if seconds is None else seconds
        self.begun: str | None = None

    def begin(self, name: str) -> None:
        """Step ``name`` begins (its ``lap`` ends it): told to the stage listener."""
        listener = _STAGES.get()
        if listener is not None:
            self.begun = name
            listener.begin(name)

    def lap(self, name: str, result: _T) -> _T:
        """Record the seconds since the previous lap under ``name``; return ``result``."""
        now = time.monotonic()
        self.seconds[name] = now - self.last
        self.last = now
        listener = _STAGES.get()
        if listener is not None and self.begun == name:
            listener.end(name, self.seconds[name])
        self.begun = None
        report = _REPORT.get()
        if report is not None:
            report(name, self.seconds[name])
        return result
