"""What the checks of one run share: each result computed once, then read.

``analyze``, ``certify`` and ``simulate`` make one ``AnalysisContext`` per
run and hand it to the steps that need a shared result: the observer built
from the spec's ``[observer]`` section (its gain can cost an exact
construction), and the sparse-observability check whose stealthy attack the
simulations replay.  A step that runs alone (a user calling
``observer_checks`` directly) gets no context and computes what it needs.

The context is a plain memo table; the keys are the ``KEYS`` below, each
with the function that computes it named in the comment.  A computation
that raises is remembered too: the next reader gets the same exception
without repeating the work.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Any, TypeVar

__all__ = ["AnalysisContext", "OBSERVER", "sparse_key", "shared"]

T = TypeVar("T")

OBSERVER = "observer"  # observers.build_observer(system, spec.observer, budget)


def sparse_key(max_attacked: int) -> tuple[str, int]:
    """Key of the sparse-observability check for s = ``max_attacked``."""
    return ("sparse_observability", int(max_attacked))


class AnalysisContext:
    """A memo table for one run on one plant.

    Examples
    --------
    >>> ctx = AnalysisContext()
    >>> ctx.once("x", lambda: 2 + 2), ctx.once("x", lambda: 1 / 0)
    (4, 4)
    >>> ctx.stats()
    {'computed': 1, 'reused': 1}
    """

    def __init__(self) -> None:
        self._values: dict[Hashable, tuple[bool, Any]] = {}
        self._computed = 0
        self._reused = 0

    def once(self, key: Hashable, compute: Callable[[], T]) -> T:
        """The value under ``key``, computing it with ``compute()`` the first time.

        An exception raised by ``compute`` is stored and raised again on
        every later call with the same key.
        """
        if key in self._values:
            self._reused += 1
            ok, value = self._values[key]
            if not ok:
                raise value
            return value
        self._computed += 1
        try:
            value = compute()
        except Exception as exc:
            self._values[key] = (False, exc)
            raise
        self._values[key] = (True, value)
        return value

    def put(self, key: Hashable, value: Any) -> None:
        """Record a value computed elsewhere (a check the pipeline ran anyway)."""
        self._values[key] = (True, value)
        self._computed += 1

    def __contains__(self, key: Hashable) -> bool:
        return key in self._values

    def stats(self) -> dict[str, int]:
        """How many values were computed and how many reads reused one."""
        return {"computed": self._computed, "reused": self._reused}


def shared(context: AnalysisContext | None, key: Hashable, compute: Callable[[], T]) -> T:
    """``context.once(key, compute)``, or ``compute()`` without a context."""
    return compute() if context is None else context.once(key, compute)
