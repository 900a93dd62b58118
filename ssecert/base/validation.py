"""Input converters shared by every public entry point.

One converter for matrices and one per kind of scalar option, so that every
error names the argument, what was expected and what was received.  Wrong
kinds raise ``TypeError``; wrong values raise ``ValueError``.
"""

from __future__ import annotations

import fractions
import math
import numbers
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = [
    "MAX_MATRIX_DIM",
    "MAX_MATRIX_ENTRIES",
    "as_real_matrix",
    "as_int_option",
    "as_float_option",
    "as_choice",
    "as_index_list",
    "check_size",
    "describe",
    "show_int",
]


#: Default limits of ``as_real_matrix(..., limits=True)``: spec files and other
#: untrusted input are refused above them before any array is built.
MAX_MATRIX_DIM = 10_000
MAX_MATRIX_ENTRIES = 10_000_000

_FLOAT_MAX = float(np.finfo(np.float64).max)


def _is_time(value: Any) -> bool:
    """numpy dates and durations: numpy registers timedelta64 as an integer."""
    return isinstance(value, (np.datetime64, np.timedelta64))


def show_int(value: int) -> str:
    """An integer for a message: in full when short, else its number of digits.

    ``str`` refuses integers of more than 4300 digits, and a 300-digit number
    is no help in a one-line message.
    """
    if -(10**20) < value < 10**20:
        return str(value)
    sign = "-" if value < 0 else ""
    try:
        return f"{sign}an integer of {len(str(abs(value))):,} digits"
    except ValueError:  # beyond the conversion limit: estimate
        digits = int(abs(value).bit_length() * 0.30102999566398120) + 1
        return f"{sign}an integer of about {digits:,} digits"


def describe(value: Any) -> str:
    """Short description of a received value for error messages."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)):
        if _is_time(value):
            return f"the {type(value).__name__} value {value}"
        return f"{type(value).__name__} {show_int(int(value))}"
    if isinstance(value, np.ndarray):
        return f"an array of shape {value.shape} and dtype {value.dtype}"
    if isinstance(value, bool):
        return f"the boolean {value}"
    if isinstance(value, str):
        text = value if len(value) <= 40 else value[:37] + "..."
        return f"the string {text!r}"
    if isinstance(value, (list, tuple)):
        return f"a {type(value).__name__} of length {len(value)}"
    if value is None:
        return "nothing (None)"
    text = repr(value)
    if len(text) > 60:
        text = text[:57] + "..."
    return f"{type(value).__name__} {text}"


def _ndim_text(ndim: int) -> str:
    return {1: "a 1-D array", 2: "a 2-D array (a list of rows)"}.get(ndim, f"{ndim}-D")


def check_size(
    name: str, shape: tuple[int, ...], max_dim: int | None, max_entries: int | None
) -> None:
    """Refuse a shape beyond the limits, before any array of it is built.

    Raises
    ------
    ValueError
        Naming ``name``, the offending size and the limits.
    """
    limits = "; ".join(
        text
        for text in (
            f"at most {max_dim:,} rows and columns" if max_dim is not None else "",
            f"{max_entries:,} entries" if max_entries is not None else "",
        )
        if text
    )
    if max_dim is not None:
        for axis, size in enumerate(shape):
            if size > max_dim:
                part = {0: "rows", 1: "columns"}.get(axis, f"entries along axis {axis}")
                raise ValueError(f"{name} is too large: {size:,} {part} (the limit is {limits})")
    if max_entries is not None:
        total = math.prod(shape)
        if total > max_entries:
            dims = " x ".join(f"{d:,}" for d in shape)
            raise ValueError(
                f"{name} is too large: {dims} = {total:,} entries (the limit is {limits})"
            )


def _nested_shape(
    value: Any, name: str, ndim: int, max_dim: int | None, max_entries: int | None
) -> tuple[int, ...]:
    """Shape of nested lists of at most ``ndim`` levels, refusing ragged rows.

    Lists too long or nested too deep are refused as soon as they are seen,
    so a huge or deeply nested document costs neither time nor recursion.
    """
    shape: list[int] = []
    level = [value]
    for axis in range(ndim + 1):
        lists = [isinstance(item, (list, tuple)) for item in level]
        if not any(lists):
            return tuple(shape)
        if axis == ndim:
            raise ValueError(
                f"{name} must be {_ndim_text(ndim)}, got lists nested more than {ndim} deep"
            )
        if not all(lists):
            i = lists.index(not lists[0])
            raise ValueError(
                f"{name} is ragged: row {i} is "
                f"{'a list' if lists[i] else 'a number'}, row 0 is "
                f"{'a list' if lists[0] else 'a number'}"
            )
        lengths = {len(item) for item in level}
        if len(lengths) > 1:
            first = len(level[0])
            i = next(j for j, item in enumerate(level) if len(item) != first)
            raise ValueError(
                f"{name} is ragged: row {i} has {len(level[i])} entries, row 0 has {first}"
            )
        size = lengths.pop()
        shape.append(size)
        check_size(name, tuple(shape), max_dim, max_entries)
        if size == 0:
            return tuple(shape)
        level = [sub for item in level for sub in item]
    return tuple(shape)  # pragma: no cover - the loop returns or raises


def as_real_matrix(
    value: Any,
    name: str,
    *,
    shape: tuple[int | None, ...] | None = None,
    ndim: int = 2,
    shape_hint: str | None = None,
    allow_empty: bool = False,
    max_dim: int | None = None,
    max_entries: int | None = None,
) -> np.ndarray:
    """Convert ``value`` to a finite real float64 array, read-only.

    Parameters
    ----------
    value : array_like
        Nested lists or an array.
    name : str
        Name used in error messages ("A", "system.C", ...).
    shape : tuple of int or None, optional
        Expected shape; ``None`` entries accept any size.
    ndim : int, default 2
        Required number of dimensions.
    shape_hint : str, optional
        Explains the expected shape ("the number of states"), appended to
        shape errors.
    allow_empty : bool, default False
        Accept arrays with a zero dimension.
    max_dim, max_entries : int, optional
        Refuse more rows or columns than ``max_dim``, or more entries than
        ``max_entries``, before building the array (untrusted input; see
        ``MAX_MATRIX_DIM`` and ``MAX_MATRIX_ENTRIES``).

    Returns
    -------
    numpy.ndarray
        A new C-contiguous float64 array with the write flag cleared.

    Raises
    ------
    TypeError
        If the entries are not real numbers (strings, booleans, complex,
        dates and durations).
    ValueError
        If the array is ragged, has the wrong shape or size, or has entries
        that are NaN, inf or too large for a float64.
    """
    if isinstance(value, (list, tuple)):
        nested = _nested_shape(value, name, ndim, max_dim, max_entries)
        if len(nested) != ndim:
            raise ValueError(f"{name} must be {_ndim_text(ndim)}, got an array of shape {nested}")
        flat: list[Any] = [value]
        for _ in range(ndim):
            flat = [sub for item in flat for sub in item]
        kinds = set(map(type, flat))
        # plain floats and ints (what JSON and TOML give) need no per-entry type checks
        checked = flat if not kinds <= {float, int} else [x for x in flat if type(x) is int]
        for item in checked:
            if (
                isinstance(item, (bool, np.bool_))
                or _is_time(item)
                or not isinstance(item, numbers.Number)
            ):
                raise TypeError(f"{name} must contain real numbers, got {describe(item)}")
            if isinstance(item, numbers.Complex) and not isinstance(item, numbers.Real):
                raise TypeError(f"{name} must be real, got the complex entry {item!r}")
            if isinstance(item, numbers.Integral) and not -_FLOAT_MAX <= int(item) <= _FLOAT_MAX:
                raise ValueError(
                    f"{name} has an entry too large for a float64: {show_int(int(item))}"
                )
            if isinstance(item, numbers.Integral) and int(float(int(item))) != int(item):
                raise ValueError(_not_a_float(name, int(item), float(int(item))))
            if _rounded(item):  # (a float128 or a Fraction the float64 does not hold)
                raise ValueError(_not_a_float(name, repr(item), float(item)))  # type: ignore[arg-type]
        array = np.array(flat, dtype=np.float64).reshape(nested) if flat else np.zeros(nested)
    else:
        if not isinstance(value, np.ndarray) and callable(getattr(value, "toarray", None)):
            raise TypeError(
                f"{name} must be a dense array, got a {type(value).__name__} (a sparse "
                f"matrix): pass {name}.toarray()"
            )
        array = np.asarray(value)
        kind = array.dtype.kind
        if kind == "b":
            raise TypeError(f"{name} must contain real numbers, got a boolean array")
        if kind == "c":
            raise TypeError(f"{name} must be real, got a complex array")
        if kind in "mM":
            what = "datetime64" if kind == "M" else "timedelta64"
            raise TypeError(
                f"{name} must contain real numbers, got a {what} array (dates or durations)"
            )
        if kind not in "iuf":
            raise TypeError(f"{name} must be a numeric array, got {describe(array)}")
        if array.ndim == ndim:
            check_size(name, array.shape, max_dim, max_entries)
        given = array
        with np.errstate(over="ignore"):  # float128 beyond float64: inf, refused below
            array = np.array(array, dtype=np.float64)
        _check_exactly_float64(given, array, name)
    if array.ndim != ndim:
        raise ValueError(f"{name} must be {_ndim_text(ndim)}, got an array of shape {array.shape}")
    if shape is not None:
        for axis, (got, want) in enumerate(zip(array.shape, shape)):
            if want is not None and got != want:
                part = {0: "rows", 1: "columns"}.get(axis, f"entries along axis {axis}")
                hint = f" ({shape_hint})" if shape_hint else ""
                raise ValueError(
                    f"{name} has the wrong number of {part}: expected {want}{hint}, got {got}"
                )
    if not allow_empty and 0 in array.shape:
        raise ValueError(f"{name} must not be empty, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        bad = np.argwhere(~np.isfinite(array))[0]
        raise ValueError(
            f"{name} must be finite, got {array[tuple(bad)]} at index {tuple(int(b) for b in bad)}"
        )
    array = np.ascontiguousarray(array)
    array.flags.writeable = False
    return array


def _not_a_float(name: str, given: Any, nearest: float) -> str:
    return (
        f"{name} has an entry that is not a float64: {show_int(given) if isinstance(given, int) else given}"
        f" (the nearest float64 is {nearest!r}); ssecert's checks, the exact ones "
        "included, are on the float64 values, so write the entry as the float64 you mean "
        "(or rescale its row)"
    )


def _rounded(item: Any) -> bool:
    """Whether a wider float or a non-integer rational is not exactly its float64."""
    if isinstance(item, np.floating) and item.dtype.itemsize > 8:
        return bool(np.isfinite(item)) and np.longdouble(float(item)) != item
    if isinstance(item, numbers.Rational) and not isinstance(item, numbers.Integral):
        value = float(item)
        return math.isfinite(value) and fractions.Fraction(value) != item
    return False


def _check_exactly_float64(given: np.ndarray, array: np.ndarray, name: str) -> None:
    """ValueError where an integer above 2^53 or a wider float (float128) of ``given`` is
    not exactly its float64 in ``array`` (NaN and inf are refused by the caller)."""
    kind, size = given.dtype.kind, given.dtype.itemsize
    if kind in "iu" and size >= 8:
        large = np.flatnonzero(np.abs(given.astype(np.float64).ravel()) >= 2.0**53)
        for i in large:
            exact = int(given.ravel()[i])
            if int(array.ravel()[i]) != exact:
                raise ValueError(_not_a_float(name, exact, float(array.ravel()[i])))
    elif kind == "f" and size > 8:
        with np.errstate(over="ignore", invalid="ignore"):
            back = array.astype(given.dtype)
        lost = np.isfinite(array) & (back != given)
        if np.any(lost):
            first = int(np.flatnonzero(lost.ravel())[0])
            raise ValueError(
                _not_a_float(name, repr(given.ravel()[first]), float(array.ravel()[first]))
            )


def as_int_option(
    value: Any,
    name: str,
    *,
    min_value: int | None = None,
    max_value: int | None = None,
) -> int:
    """Convert an integer option, refusing booleans and non-integral floats."""
    if (
        isinstance(value, (bool, np.bool_))
        or _is_time(value)
        or not isinstance(value, (numbers.Integral, float, np.floating))
    ):
        raise TypeError(f"{name} must be an integer, got {describe(value)}")
    if isinstance(value, (float, np.floating)):
        if not np.isfinite(value) or value != int(value):
            raise TypeError(f"{name} must be an integer, got {value!r}")
    result = int(value)
    if min_value is not None and result < min_value:
        raise ValueError(f"{name} must be >= {min_value}, got {show_int(result)}")
    if max_value is not None and result > max_value:
        raise ValueError(f"{name} must be <= {max_value:,}, got {show_int(result)}")
    return result


def as_float_option(
    value: Any,
    name: str,
    *,
    min_value: float | None = None,
    max_value: float | None = None,
    min_inclusive: bool = True,
    max_inclusive: bool = True,
) -> float:
    """Convert a finite real option within optional bounds."""
    if (
        isinstance(value, (bool, np.bool_))
        or _is_time(value)
        or not isinstance(value, numbers.Real)
    ):
        raise TypeError(f"{name} must be a real number, got {describe(value)}")
    if isinstance(value, numbers.Integral) and not -_FLOAT_MAX <= int(value) <= _FLOAT_MAX:
        raise ValueError(f"{name} must be finite, got {show_int(int(value))}")
    result = float(value)
    if not np.isfinite(result):
        raise ValueError(f"{name} must be finite, got {result}")
    if min_value is not None:
        if result < min_value or (not min_inclusive and result == min_value):
            op = ">=" if min_inclusive else ">"
            raise ValueError(f"{name} must be {op} {min_value}, got {result}")
    if max_value is not None:
        if result > max_value or (not max_inclusive and result == max_value):
            op = "<=" if max_inclusive else "<"
            raise ValueError(f"{name} must be {op} {max_value}, got {result}")
    return result


def as_choice(value: Any, name: str, choices: Sequence[str]) -> str:
    """Check that ``value`` is one of ``choices`` (strings)."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be one of {', '.join(choices)}; got {describe(value)}")
    if value not in choices:
        import difflib

        close = difflib.get_close_matches(value, choices, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise ValueError(f"{name} must be one of {', '.join(choices)}; got {value!r}{hint}")
    return value


def as_index_list(value: Any, name: str, *, upper: int, what: str = "sensor") -> tuple[int, ...]:
    """Validate a list of distinct 0-based indices below ``upper``."""
    if isinstance(value, (str, bytes)) or not isinstance(value, (Sequence, np.ndarray)):
        raise TypeError(f"{name} must be a list of {what} indices, got {describe(value)}")
    result = []
    for i, item in enumerate(value):
        index = as_int_option(item, f"{name}[{i}]", min_value=0)
        if index >= upper:
            raise ValueError(
                f"{name}[{i}] = {show_int(index)} is out of range: {what} indices are 0-based and "
                f"must be < {upper}"
            )
        result.append(index)
    if len(set(result)) != len(result):
        raise ValueError(f"{name} has repeated {what} indices: {result}")
    return tuple(result)
