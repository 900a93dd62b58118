"""Reading one table of a spec: errors that name the file and the key.

The spec loader (``ssecert.spec``) and every observer kind
(``ssecert.observers``) read their tables with these helpers, so that a
wrong value gives the same kind of message wherever it is.
"""

from __future__ import annotations

import difflib
import math
import numbers
import re
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..base.validation import (
    MAX_MATRIX_DIM,
    MAX_MATRIX_ENTRIES,
    as_choice,
    as_float_option,
    as_int_option,
    as_real_matrix,
    describe,
)

__all__ = ["SpecError", "SpecTable", "one_line"]

INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1
MAX_NAME_LENGTH = 128
MATRIX_LIMITS = {"max_dim": MAX_MATRIX_DIM, "max_entries": MAX_MATRIX_ENTRIES}


class SpecError(ValueError):
    """A spec file or spec dictionary is invalid.

    The message names the file and the key, says what was expected and what
    was found.  It is one line: control characters from the file (in keys,
    names or paths) are shown escaped.
    """

    def __init__(self, message: str) -> None:
        super().__init__(one_line(message))


# control characters, line and paragraph separators, bidirectional overrides
UNPRINTABLE = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]")


def one_line(text: str) -> str:
    """``text`` with control characters escaped and lone surrogates replaced."""
    text = UNPRINTABLE.sub(lambda m: ascii(m.group())[1:-1], text)
    return text.encode("utf-8", "backslashreplace").decode("utf-8")


def spec_error(source: str, key: str | None, message: str) -> SpecError:
    if key is not None and len(key) > 80:
        key = key[:77] + "..."
    where = f"{source}: key '{key}'" if key else source
    return SpecError(f"{where}: {message}")


def suggest(key: Any, allowed: tuple[str, ...]) -> str:
    """' (did you mean 'X'?)' for a misspelt or wrongly capitalised key, else ''."""
    text = str(key)
    close = [a for a in allowed if a.lower() == text.lower()]
    close = close or difflib.get_close_matches(text, allowed, n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def check_keys(source: str, prefix: str, table: Any, allowed: tuple[str, ...]) -> None:
    if not isinstance(table, Mapping):
        raise spec_error(source, prefix or None, f"expected a table, got {describe(table)}")
    for key in table:
        if key not in allowed:
            hint = suggest(key, allowed)
            full = f"{prefix}.{key}" if prefix else str(key)
            raise spec_error(source, full, f"unknown key{hint}; allowed here: {', '.join(allowed)}")


def convert(source: str, key: str, func: Any, *args: Any, **kwargs: Any) -> Any:
    """Run a converter, turning its error into a SpecError naming file and key."""
    try:
        return func(*args, **kwargs)
    except (TypeError, ValueError) as exc:
        message = str(exc)
        # converters name their argument first; the key already names it here
        name = kwargs.get("name") or (args[1] if len(args) > 1 else None)
        if isinstance(name, str) and message.startswith(name + " "):
            message = message[len(name) :].lstrip(" :")
        raise spec_error(source, key, message) from None


def check_name(source: str, key: str, value: Any, what: str) -> str:
    """``value`` when it is a non-empty string of at most ``MAX_NAME_LENGTH`` characters."""
    if not isinstance(value, str) or not value.strip():
        raise spec_error(source, key, f"expected a non-empty string, got {describe(value)}")
    if len(value) > MAX_NAME_LENGTH:
        raise spec_error(
            source, key, f"{what} has {len(value):,} characters; the limit is {MAX_NAME_LENGTH}"
        )
    return value


def require(source: str, table: Mapping[str, Any], key: str, prefix: str) -> Any:
    if key not in table:
        raise spec_error(source, f"{prefix}.{key}" if prefix else key, "missing (required)")
    return table[key]


def spec_int(value: Any, name: str, *, min_value: int, max_value: int = INT64_MAX) -> int:
    """An integer option of a spec: at most 2^63 - 1 also when written as a float."""
    return as_int_option(value, name, min_value=min_value, max_value=max_value)


def positive(source: str, key: str, value: Any) -> float:
    return convert(
        source, key, as_float_option, value, key.split(".")[-1], min_value=0.0, min_inclusive=False
    )


def poles(source: str, key: str, value: Any, n: int) -> list[complex]:
    """``n`` finite poles, complex ones in conjugate pairs: a list (or, from Python, a tuple
    or a 1-D array) of real numbers, [re, im] pairs or complex numbers."""
    if isinstance(value, tuple) or (isinstance(value, np.ndarray) and value.ndim == 1):
        value = list(value)
    if not isinstance(value, list):
        raise spec_error(source, key, f"expected a list of {n} poles, got {describe(value)}")
    if len(value) != n:
        raise spec_error(source, key, f"expected {n} poles (one per state), got {len(value):,}")
    poles: list[complex] = []
    for i, item in enumerate(value):
        if (
            isinstance(item, list | tuple)
            and len(item) == 2
            and all(isinstance(x, numbers.Real) and not isinstance(x, bool) for x in item)
        ):
            pole = complex(float(item[0]), float(item[1]))
        elif isinstance(item, numbers.Real) and not isinstance(item, bool):
            pole = complex(float(item), 0.0)
        elif isinstance(item, numbers.Complex) and not isinstance(item, bool):  # (Python's)
            pole = complex(item)
        else:
            raise spec_error(
                source,
                f"{key}[{i}]",
                f"expected a real number, a [re, im] pair or a complex number, got "
                f"{describe(item)}",
            )
        if not (math.isfinite(pole.real) and math.isfinite(pole.imag)):
            raise spec_error(source, f"{key}[{i}]", f"must be finite, got {pole}")
        poles.append(pole)
    if len(poles) != n:
        raise spec_error(source, key, f"expected {n} poles (one per state), got {len(poles)}")
    remaining = [q for q in poles if q.imag != 0]
    while remaining:
        q = remaining.pop(0)
        match = next((r for r in remaining if r == q.conjugate()), None)
        if match is None:
            raise spec_error(source, key, f"complex pole {q} has no conjugate partner")
        remaining.remove(match)
    return poles


class SpecTable:
    """One table of a spec (``[observer]``, say), read key by key.

    Every error names the file and the full key (``observer.step``), says
    what was expected and what was found, and is a ``SpecError``.

    Parameters
    ----------
    source : str
        The file as the user named it (or ``"<dict>"``).
    prefix : str
        The table's key in the document.
    table : mapping
        The table; ``check_keys`` refuses anything else.

    Examples
    --------
    >>> t = SpecTable("x.toml", "observer", {"step": 0.5})
    >>> t.positive("step")
    0.5
    >>> t.positive("threshold")
    Traceback (most recent call last):
    ...
    ssecert.spec.table.SpecError: x.toml: key 'observer.threshold': missing (required)
    """

    def __init__(self, source: str, prefix: str, table: Any) -> None:
        self.source, self.prefix, self.table = source, prefix, table

    def key(self, name: str) -> str:
        """The full key of ``name`` in this table."""
        return f"{self.prefix}.{name}" if self.prefix else name

    def __contains__(self, name: object) -> bool:
        return name in self.table

    def get(self, name: str, default: Any = None) -> Any:
        return self.table.get(name, default)

    def error(self, name: str | None, message: str) -> SpecError:
        """A SpecError about key ``name`` (the table itself when None)."""
        return spec_error(self.source, self.key(name) if name else self.prefix or None, message)

    def check_keys(self, allowed: tuple[str, ...]) -> None:
        """Refuse a non-table and any key not in ``allowed`` (suggesting a close one)."""
        check_keys(self.source, self.prefix, self.table, allowed)

    def require(self, name: str) -> Any:
        """The value of a required key."""
        return require(self.source, self.table, name, self.prefix)

    def convert(self, name: str, func: Any, *args: Any, **kwargs: Any) -> Any:
        """``func(*args, **kwargs)``, its TypeError or ValueError as a SpecError about ``name``."""
        return convert(self.source, self.key(name), func, *args, **kwargs)

    def positive(self, name: str) -> float:
        """A required real number > 0."""
        return positive(self.source, self.key(name), self.require(name))

    def real(self, name: str, value: Any, **limits: Any) -> float:
        """``value`` as a real number within ``limits`` (as ``as_float_option`` takes them)."""
        return self.convert(name, as_float_option, value, name, **limits)

    def integer(self, name: str, default: int, *, min_value: int) -> int:
        """An optional 64-bit integer >= ``min_value``."""
        return self.convert(
            name, spec_int, self.table.get(name, default), name, min_value=min_value
        )

    def choice(self, name: str, value: Any, allowed: tuple[str, ...]) -> str:
        """``value``, one of ``allowed``."""
        return self.convert(name, as_choice, value, name, allowed)

    def matrix(self, name: str, value: Any, *, shape: tuple[int, ...], shape_hint: str) -> Any:
        """``value`` as a real matrix of ``shape`` within the spec's size limits."""
        return self.convert(
            name, as_real_matrix, value, name, shape=shape, shape_hint=shape_hint, **MATRIX_LIMITS
        )

    def poles(self, name: str, n: int) -> list[complex]:
        """A required list of ``n`` poles, complex ones in conjugate pairs."""
        return poles(self.source, self.key(name), self.require(name), n)
