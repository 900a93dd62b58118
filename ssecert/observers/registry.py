"""The observer kinds a spec may name, by name.

Built-in kinds register themselves when ``ssecert.observers`` is imported;
a new kind is a subclass of ``ObserverKind`` decorated with ``register``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    from .base import ObserverKind

__all__ = ["register", "get_kind", "observer_kinds", "unregister", "BUILTIN_KINDS"]

BUILTIN_KINDS = ("luenberger", "ogd", "sso", "dsso", "elastic_net")

_KINDS: dict[str, ObserverKind] = {}

K = TypeVar("K", bound="type[ObserverKind]")


def register(cls: K) -> K:
    """Class decorator: make ``cls`` the observer kind its ``name`` names.

    Examples
    --------
    >>> from ssecert.observers import ObserverKind, register, observer_kinds, unregister
    >>> @register
    ... class Mine(ObserverKind):
    ...     name, keys = "mine", ("kind",)
    >>> "mine" in observer_kinds()
    True
    >>> unregister("mine")
    """
    name = getattr(cls, "name", None)
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"an observer kind needs a name that is an identifier, got {name!r}")
    keys = getattr(cls, "keys", None)
    if not isinstance(keys, tuple) or "kind" not in keys:
        raise ValueError(f"observer kind {name!r}: keys must be a tuple including 'kind'")
    _KINDS[name] = cls()
    return cls


def unregister(name: str) -> None:
    """Remove a kind (tests that register their own use it to clean up)."""
    _KINDS.pop(name, None)


def get_kind(name: str) -> ObserverKind:
    """The registered kind called ``name``; ValueError listing the kinds otherwise."""
    try:
        return _KINDS[name]
    except KeyError:
        raise ValueError(
            f"unknown observer kind {name!r}; registered: {', '.join(observer_kinds())}"
        ) from None


def observer_kinds() -> tuple[str, ...]:
    """The names of the registered kinds: the built-in ones in their order, then the others."""
    builtin = tuple(k for k in BUILTIN_KINDS if k in _KINDS)
    return builtin + tuple(k for k in _KINDS if k not in BUILTIN_KINDS)
