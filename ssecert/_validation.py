"""Input converters shared by every public entry point.

One converter for matrices and one per kind of scalar option, so that every
error names the argument, what was expected and what was received.  Wrong
kinds raise ``TypeError``; wrong values raise ``ValueError``.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = [
    "as_real_matrix",
    "as_int_option",
    "as_float_option",
    "as_choice",
    "as_index_list",
    "describe",
]


def describe(value: Any) -> str:
    """Short description of a received value for error messages."""
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
    return f"{type(value).__name__} {value!r}"


def _nested_shape(value: Any, name: str) -> tuple[int, ...]:
    """Shape of a nested list, refusing ragged rows with a precise message."""
    if isinstance(value, (list, tuple)):
        if len(value) == 0:
            return (0,)
        shapes = [_nested_shape(item, f"{name}[{i}]") for i, item in enumerate(value)]
        first = shapes[0]
        for i, shape in enumerate(shapes[1:], start=1):
            if shape != first:
                raise ValueError(
                    f"{name} is ragged: row {i} has shape {shape}, row 0 has shape {first}"
                )
        return (len(value),) + first
    return ()


def as_real_matrix(
    value: Any,
    name: str,
    *,
    shape: tuple[int | None, ...] | None = None,
    ndim: int = 2,
    shape_hint: str | None = None,
    allow_empty: bool = False,
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

    Returns
    -------
    numpy.ndarray
        A new C-contiguous float64 array with the write flag cleared.

    Raises
    ------
    TypeError
        If the entries are not real numbers (strings, booleans, complex).
    ValueError
        If the array is ragged, has the wrong shape, or has NaN or inf entries.
    """
    if isinstance(value, (list, tuple)):
        nested = _nested_shape(value, name)
        flat: list[Any] = []

        def _flatten(item: Any) -> None:
            if isinstance(item, (list, tuple)):
                for sub in item:
                    _flatten(sub)
            else:
                flat.append(item)

        _flatten(value)
        for item in flat:
            if isinstance(item, (bool, np.bool_)) or not isinstance(item, numbers.Number):
                raise TypeError(f"{name} must contain real numbers, got {describe(item)}")
            if isinstance(item, numbers.Complex) and not isinstance(item, numbers.Real):
                raise TypeError(f"{name} must be real, got the complex entry {item!r}")
        array = np.array(flat, dtype=np.float64).reshape(nested) if flat else np.zeros(nested)
    else:
        array = np.asarray(value)
        if array.dtype == object or array.dtype.kind in "USV":
            raise TypeError(f"{name} must be a numeric array, got {describe(array)}")
        if array.dtype.kind == "b":
            raise TypeError(f"{name} must contain real numbers, got a boolean array")
        if array.dtype.kind == "c":
            raise TypeError(f"{name} must be real, got a complex array")
        array = np.array(array, dtype=np.float64)
    if array.ndim != ndim:
        what = {1: "a 1-D array", 2: "a 2-D array (a list of rows)"}.get(ndim, f"{ndim}-D")
        raise ValueError(f"{name} must be {what}, got an array of shape {array.shape}")
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


def as_int_option(
    value: Any,
    name: str,
    *,
    min_value: int | None = None,
    max_value: int | None = None,
) -> int:
    """Convert an integer option, refusing booleans and non-integral floats."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Integral, float)):
        raise TypeError(f"{name} must be an integer, got {describe(value)}")
    if isinstance(value, float):
        if not np.isfinite(value) or value != int(value):
            raise TypeError(f"{name} must be an integer, got {value!r}")
    result = int(value)
    if min_value is not None and result < min_value:
        raise ValueError(f"{name} must be >= {min_value}, got {result}")
    if max_value is not None and result > max_value:
        raise ValueError(f"{name} must be <= {max_value}, got {result}")
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
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {describe(value)}")
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
                f"{name}[{i}] = {index} is out of range: {what} indices are 0-based and "
                f"must be < {upper}"
            )
        result.append(index)
    if len(set(result)) != len(result):
        raise ValueError(f"{name} has repeated {what} indices: {result}")
    return tuple(result)
