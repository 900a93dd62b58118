"""Reading spec files: text (TOML, JSON) and arrays (.npz, .mat), before any key is read.

The checks that keep a hostile or mistaken file from costing more than it
should: size limits on the raw bytes, nesting depth, unprintable text,
integers beyond 64 bits, duplicate JSON keys; and the array files' own
formats (an .npz holds only .npy members, a .mat file only numeric arrays
of the expected variables).  ``ssecert.spec`` turns what they return into
a validated ``Spec``.
"""

from __future__ import annotations

import io
import json
import math
import re
import tomllib
import warnings
import zipfile
from collections.abc import Collection, Mapping
from typing import Any

import numpy as np

from ..base.validation import (
    MAX_MATRIX_DIM,
    MAX_MATRIX_ENTRIES,
    check_size,
    describe,
    show_int,
)
from .table import (
    INT64_MAX,
    INT64_MIN,
    MATRIX_LIMITS,
    UNPRINTABLE,
    SpecError,
    spec_error,
    suggest,
)

MAX_TEXT_BYTES = 16 * 2**20
MAX_BINARY_BYTES = 256 * 2**20
MAX_NESTING = 16
_SYSTEM_KEYS = ("A", "C", "sensors")
# the variables of an .npz or .mat file: the system's, and those of a MATLAB save of a
# state-space model (``[A, B, C, D, Ts] = ssdata(sys)``), which are checked and not used
_ARRAY_KEYS = ("A", "B", "C", "D", "Ts", "sensors")
UNUSED_KEYS = ("B", "D", "Ts")
_NPY_MAGIC = b"\x93NUMPY"


class _TooLongInteger:
    """An integer literal too long to convert (JSON ``parse_int``)."""

    def __init__(self, text: str) -> None:
        self.digits = len(text.lstrip("+-"))


def _check_text(source: str, path: str, text: str, what: str) -> None:
    """Refuse text that cannot be shown on one line or written as UTF-8."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise spec_error(
            source,
            path or None,
            f"{what} is not valid Unicode (a lone surrogate "
            f"{text[exc.start]!a} at position {exc.start})",
        ) from None
    bad = UNPRINTABLE.search(text)
    if bad:
        raise spec_error(
            source,
            path or None,
            f"{what} contains the control character {bad.group()!a} at position "
            f"{bad.start()}; text in a spec must be printable on one line",
        )


def _check_document(source: str, data: Mapping[str, Any]) -> None:
    """One pass over the whole document before any key is interpreted.

    Refuses, naming the key: integers outside the 64-bit range TOML allows
    (also in JSON, so that both formats mean the same), text with control
    characters or invalid Unicode, lists longer than MAX_MATRIX_DIM (no list
    of a spec may be longer than a matrix may be tall or wide) and nesting
    deeper than MAX_NESTING (which also stops on self-containing Python
    lists).  Iterative, and key paths are built only for messages: a large
    document costs one quick pass.
    """
    # (container, its parent's path, its key in the parent, depth)
    stack: list[tuple[Any, str, Any, int]] = [(data, "", None, 0)]
    while stack:
        container, parent, name, depth = stack.pop()
        path = _path(parent, name)
        if depth > MAX_NESTING:
            raise spec_error(
                source,
                path or None,
                f"nested more than {MAX_NESTING} levels deep (a spec needs at most 4)",
            )
        is_table = isinstance(container, Mapping)
        if not is_table and len(container) > MAX_MATRIX_DIM:
            raise spec_error(
                source,
                path or None,
                f"a list of {len(container):,} entries: more rows, columns or items than "
                f"the limit of {MAX_MATRIX_DIM:,}",
            )
        entries: Any = container.items() if is_table else enumerate(container)
        children = []
        for key, item in entries:
            if is_table and isinstance(key, str):
                _check_text(source, path, key, f"the key {key[:40]!r}")
            if isinstance(item, (bool, float)):
                continue
            index = key if is_table else [key]
            if isinstance(item, (Mapping, list, tuple)):
                children.append((item, path, index, depth + 1))
            elif isinstance(item, _TooLongInteger):
                raise spec_error(
                    source,
                    _path(path, index),
                    f"an integer of {item.digits:,} digits is out of range: spec "
                    f"integers must fit in 64 bits (-2^63 to 2^63 - 1)",
                )
            elif isinstance(item, int) and not INT64_MIN <= item <= INT64_MAX:
                text = show_int(item)
                text = text if "digits" in text else f"the integer {text}"
                raise spec_error(
                    source,
                    _path(path, index),
                    f"{text} is out of range: spec integers "
                    f"must fit in 64 bits (-2^63 to 2^63 - 1)",
                )
            elif isinstance(item, str):
                _check_text(source, _path(path, index), item, "the text")
        stack.extend(reversed(children))


def _path(parent: str, key: Any) -> str:
    """'system.A[0]': a table key as [key], a list index as a one-item list."""
    if key is None:
        return parent
    if isinstance(key, list):
        return f"{parent}[{key[0]}]"
    return f"{parent}.{key}" if parent else str(key)


def _read_npz(raw: bytes, source: str) -> dict[str, Any]:
    """Variables of an .npz archive: names, then headers (shape, dtype), then data."""
    if raw.startswith(_NPY_MAGIC):
        raise SpecError(
            f"{source}: cannot read the .npz file: it is a single .npy array; "
            f"expected an .npz archive of named arrays (numpy.savez)"
        )
    try:
        archive = zipfile.ZipFile(io.BytesIO(raw))
        members = archive.namelist()
    except Exception as exc:
        raise SpecError(f"{source}: cannot read the .npz file: {_reason(exc)}") from None
    keys: list[str] = []
    for member in members:
        key = member[:-4] if member.endswith(".npy") else member
        _check_variable(source, key, keys, "the archive")
        keys.append(key)
    data: dict[str, Any] = {}
    for member, key in zip(members, keys):
        try:
            with archive.open(member) as handle:
                version = np.lib.format.read_magic(handle)
                if version == (1, 0):
                    shape, _, dtype = np.lib.format.read_array_header_1_0(handle)
                elif version == (2, 0):
                    shape, _, dtype = np.lib.format.read_array_header_2_0(handle)
                else:
                    raise ValueError(f"unsupported .npy format version {version}")
            if dtype.hasobject:
                raise SpecError(
                    f"{source}: cannot read the .npz file: variable {key!r} holds Python objects "
                    f"(dtype object), which are not loaded (unpickling can run code); expected "
                    f"{'strings' if key == 'sensors' else 'real numbers'}"
                )
            if key == "sensors":
                limits = {"max_dim": MAX_MATRIX_DIM, "max_entries": MAX_MATRIX_DIM}
            else:
                limits = MATRIX_LIMITS
            _check_array_size(source, key, tuple(shape), dtype, **limits)
            with archive.open(member) as handle:
                data[key] = np.lib.format.read_array(handle, allow_pickle=False)
        except SpecError:
            raise
        except Exception as exc:
            raise SpecError(
                f"{source}: cannot read the .npz file: variable {key!r}: {_reason(exc)}"
            ) from None
    return data


def _check_array_size(
    source: str,
    name: str,
    shape: tuple[int, ...],
    dtype: np.dtype,
    *,
    max_dim: int,
    max_entries: int,
) -> None:
    """Refuse an array by its header: the limits on rows, columns, entries and bytes."""
    try:
        check_size("the variable", shape, max_dim, max_entries)
    except ValueError as exc:
        raise spec_error(source, name, str(exc)) from None
    if math.prod(shape) * dtype.itemsize > 16 * max_entries:
        raise spec_error(
            source,
            name,
            f"the variable is too large: {math.prod(shape):,} entries of {dtype.itemsize:,} bytes",
        )


def _read_mat(raw: bytes, source: str) -> dict[str, Any]:
    """Variables of a MATLAB .mat file (v4 or v5), checked before SciPy reads them."""
    import scipy.io

    from ..base.matfile import MatFormatError, variables

    try:
        major, _ = scipy.io.matlab.matfile_version(io.BytesIO(raw))
    except Exception as exc:
        raise SpecError(f"{source}: cannot read the .mat file: {_reason(exc)}") from None
    if major == 2:
        raise SpecError(
            f"{source}: MATLAB v7.3 (HDF5) files are not supported; save with "
            f"save(file, 'A', 'C', '-v7')"
        )
    try:
        if major == 1:
            found = [
                (v.name, v.class_name, v.shape)
                for v in variables(
                    raw, max_entries=MAX_MATRIX_ENTRIES, max_bytes=16 * MAX_MATRIX_ENTRIES + 2**20
                )
            ]
        else:  # v4: read by SciPy in Python
            found = [
                (name, cls, tuple(shape)) for name, shape, cls in scipy.io.whosmat(io.BytesIO(raw))
            ]
    except MatFormatError as exc:
        raise SpecError(f"{source}: cannot read the .mat file: {exc}") from None
    except Exception as exc:
        raise SpecError(f"{source}: cannot read the .mat file: {_reason(exc)}") from None
    seen: set[str] = set()
    for name, class_name, shape in found:
        _check_variable(source, name, seen, "the file")
        seen.add(name)
        numeric = class_name in ("double", "single") or class_name.startswith(("int", "uint"))
        if name != "sensors" and not numeric:
            raise spec_error(
                source, f"system.{name}", f"must contain real numbers, got a MATLAB {class_name}"
            )
        limits = (
            MATRIX_LIMITS
            if name != "sensors"
            else {"max_dim": MAX_MATRIX_DIM, "max_entries": MAX_MATRIX_ENTRIES}
        )
        _check_array_size(source, name, shape, np.dtype(np.float64), **limits)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            raw_vars = scipy.io.loadmat(io.BytesIO(raw))
        for warning in caught:  # SciPy warns about what it could not read, and goes on
            if not issubclass(
                warning.category, (DeprecationWarning, PendingDeprecationWarning, FutureWarning)
            ):
                raise ValueError(str(warning.message))
    except NotImplementedError:
        raise SpecError(
            f"{source}: MATLAB v7.3 (HDF5) files are not supported; save with "
            f"save(file, 'A', 'C', '-v7')"
        ) from None
    except Exception as exc:
        raise SpecError(f"{source}: cannot read the .mat file: {_reason(exc)}") from None
    return {k: v for k, v in raw_vars.items() if not k.startswith("__")}


def _reason(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def _read_arrays(raw: bytes, suffix: str, source: str) -> dict[str, Any]:
    """Variables of an .npz or .mat file."""
    data = _read_npz(raw, source) if suffix == ".npz" else _read_mat(raw, source)
    for key in data:
        if key not in _ARRAY_KEYS:  # pragma: no cover - refused before loading
            raise spec_error(source, key, "unknown variable; expected A, C and optionally sensors")
    if "sensors" in data:
        data["sensors"] = _names(source, data["sensors"])
    return data


def unused_variables(source: str, arrays: dict[str, Any]) -> str | None:
    """Check the B, D and Ts of a state-space save against A and C, and say they are not used
    (None when the file has none of them).

    B (n x m) and D (p x m) must have the rows of A and C and the same columns; Ts is the
    sampling time, positive or -1 (MATLAB's unspecified), never 0 (a continuous-time model).
    """
    present = [key for key in UNUSED_KEYS if key in arrays]
    if not present:
        return None
    n = np.shape(arrays["A"])[0]
    p = np.shape(np.atleast_2d(arrays["C"]))[0]
    columns: dict[str, int] = {}
    for key, rows, of in (("B", n, "A"), ("D", p, "C")):
        if key in arrays:
            value = np.asarray(arrays[key], dtype=float)
            if value.ndim == 1 or (value.ndim == 2 and value.shape[0] == 1 and rows > 1):
                value = value.reshape(-1, 1)  # one input, saved as a vector
            if value.ndim != 2 or value.shape[0] != rows:
                raise spec_error(
                    source,
                    key,
                    f"expected {rows} rows (those of {of}), got shape {value.shape}",
                )
            if not np.all(np.isfinite(value)):  # (not used, but a NaN there is a broken model)
                raise spec_error(source, key, "expected finite entries, got NaN or inf")
            columns[key] = value.shape[1]
    if len(set(columns.values())) > 1:
        raise spec_error(
            source, "D", f"expected the columns of B ({columns['B']}), got {columns['D']}"
        )
    if "Ts" in arrays:
        ts = np.asarray(arrays["Ts"], dtype=float).ravel()
        if ts.size != 1 or not np.isfinite(ts[0]) or not (ts[0] > 0 or ts[0] == -1):
            got = ts.tolist() if ts.size != 1 else ts[0]
            if ts.size == 1 and ts[0] == 0:
                raise spec_error(
                    source,
                    "Ts",
                    "0: a continuous-time model; ssecert certifies discrete-time plants, "
                    "discretise it first (sysd = c2d(sys, T) in MATLAB, control.c2d in Python)",
                )
            raise spec_error(
                source, "Ts", f"expected a sampling time > 0 (or -1, unspecified), got {got}"
            )
    names = " and ".join([", ".join(present[:-1]), present[-1]] if len(present) > 1 else present)
    return (
        f"{source}: {names} read and not used (a known input cancels in the estimation error; "
        "the certificates do not depend on the sampling time)"
    )


def _names(source: str, value: Any) -> list[str]:
    """Sensor names from an array of strings or a MATLAB cell array."""
    arr = np.asarray(value)
    names: list[str] = []
    for item in arr.ravel():
        if isinstance(item, np.ndarray):
            item = item.ravel()
            if item.size != 1:
                raise spec_error(source, "sensors", "expected one name per sensor")
            item = item[0]
        if not isinstance(item, (str, np.str_)):
            raise spec_error(source, "sensors", f"expected strings, got {describe(item)}")
        names.append(str(item).strip())
    return names


def _parse_text(raw: bytes, suffix: str, source: str) -> dict[str, Any]:
    """Parse a TOML or JSON spec: a table at the top level, or SpecError."""
    fmt = "TOML" if suffix == ".toml" else "JSON"
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise SpecError(f"{source}: not a UTF-8 text file: it is UTF-16 text; save it as UTF-8")
    if b"\x00" in raw:
        raise SpecError(f"{source}: not a {fmt} text file: it contains NUL bytes (a binary file?)")
    try:
        text = raw.decode("utf-8-sig")  # a byte-order mark is not content
    except UnicodeDecodeError as exc:
        raise SpecError(
            f"{source}: not a UTF-8 text file: invalid byte "
            f"0x{raw[exc.start]:02x} at offset {exc.start:,}"
        ) from None
    try:
        if fmt == "TOML":
            data = tomllib.loads(text)
        else:
            data = json.loads(text, object_pairs_hook=_json_object, parse_int=_json_int)
    except (tomllib.TOMLDecodeError, json.JSONDecodeError) as exc:
        raise SpecError(f"{source}: invalid {fmt}: {exc}") from None
    except _DuplicateKey as exc:
        raise SpecError(
            f"{source}: invalid JSON: the key {exc.key!r} appears twice in one object"
        ) from None
    except RecursionError:
        raise SpecError(
            f"{source}: invalid {fmt}: nested too deeply to read (a spec needs at most 4 levels)"
        ) from None
    except ValueError as exc:  # tomllib: an integer literal of more than 4300 digits
        match = re.search(r"[0-9_]{4300,}", text)
        if match is None:
            raise SpecError(f"{source}: invalid {fmt}: {_reason(exc)}") from None
        line = text.count("\n", 0, match.start()) + 1
        digits = len(match.group().replace("_", ""))
        raise SpecError(
            f"{source}: line {line}: an integer of {digits:,} digits is out of range: "
            f"spec integers must fit in 64 bits (-2^63 to 2^63 - 1)"
        ) from None
    if not isinstance(data, dict):
        raise SpecError(f"{source}: expected a JSON object at the top level, got {describe(data)}")
    return data


class _DuplicateKey(Exception):
    def __init__(self, key: str) -> None:
        super().__init__(key)
        self.key = key


def _json_object(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """JSON objects without repeated keys (TOML refuses them too)."""
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(key)
        out[key] = value
    return out


def _json_int(text: str) -> int | _TooLongInteger:
    """JSON integers; literals too long to convert are reported with their key."""
    if len(text) > 40:
        return _TooLongInteger(text)
    return int(text)


def _check_variable(source: str, name: str, seen: Collection[str], holder: str) -> None:
    """SpecError unless ``name`` is a variable of an array file (A, C, sensors, or B, D and Ts
    of a state-space save) not already read."""
    if name not in _ARRAY_KEYS:
        hint = suggest(name, _ARRAY_KEYS)
        raise spec_error(
            source,
            name,
            f"unknown variable{hint}; expected A, C and optionally sensors (B, D and Ts are "
            "read and not used)",
        )
    if name in seen:
        raise spec_error(source, name, f"{holder} holds this variable twice")
