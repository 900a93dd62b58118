"""Structure check of MATLAB v5 (.mat) files before SciPy reads them.

SciPy's v5 reader is not hardened against corrupt files (its documentation
says so): an element whose data-type code has no entry in its type table
makes ``scipy.io.loadmat`` read a null or wild pointer and crash the whole
process, and dimensions whose product overflows wrap around.  ``variables``
walks every element of the file first and refuses, with a ``MatFormatError``:

- tags that run past the end of their container (truncated files);
- data elements whose type code SciPy cannot read, fewer data elements than
  the array flags announce (SciPy would read the next variable's tag as
  data), and anything but arrays inside cell arrays;
- negative dimensions, and arrays with more than ``max_entries`` entries;
- compressed elements that expand beyond ``max_bytes``;
- classes other than numeric, char and cell arrays (structs, objects, sparse
  matrices, function handles), which a plant file never needs and whose
  readers trust more of the file;
- more than ``MAX_NESTING`` levels of cells.

It returns the name, class and shape of every top-level variable, so the
caller can refuse unknown or oversized variables before loading any data.
MATLAB v4 files are read by SciPy in Python (no compiled code) and v7.3
files are HDF5; neither is checked here.
"""

from __future__ import annotations

import math
import struct
import zlib
from dataclasses import dataclass

__all__ = ["MatFormatError", "MatVariable", "variables", "CLASS_NAMES"]

MAX_NESTING = 16

MI_MATRIX = 14
MI_COMPRESSED = 15
# element types SciPy's reader has a dtype for (miINT8 .. miUINT64, miUTF8/16/32)
_DATA_TYPES = frozenset({1, 2, 3, 4, 5, 6, 7, 9, 12, 13, 16, 17, 18})
_INT32_TYPES = frozenset({5, 6})  # miINT32, miUINT32
_NAME_TYPES = frozenset({1, 16})  # miINT8, miUTF8

CLASS_NAMES = {
    1: "cell array",
    2: "struct",
    3: "object",
    4: "char array",
    5: "sparse matrix",
    6: "double",
    7: "single",
    8: "int8",
    9: "uint8",
    10: "int16",
    11: "uint16",
    12: "int32",
    13: "uint32",
    14: "int64",
    15: "uint64",
    16: "function handle",
    17: "opaque object",
}
# cell, char and numeric arrays: all a plant file needs; SciPy's struct reader trusts
# the field names to be NUL-terminated, and sparse matrices their indices
_SUPPORTED = frozenset({1, 4, *range(6, 16)})
_MAX_DIMS = 32  # SciPy's limit
_LOGICAL_FLAG = 0x0200
_COMPLEX_FLAG = 0x0800


class MatFormatError(ValueError):
    """The file is not a well-formed MATLAB v5 file."""


@dataclass(frozen=True)
class MatVariable:
    """A top-level variable: name, MATLAB class and dimensions."""

    name: str
    class_id: int
    shape: tuple[int, ...]
    logical: bool = False

    @property
    def class_name(self) -> str:
        if self.logical:
            return "logical array"
        return CLASS_NAMES.get(self.class_id, f"class {self.class_id}")


class _Walker:
    def __init__(self, endian: str, max_entries: int, max_bytes: int) -> None:
        self.endian = endian
        self.max_entries = max_entries
        self.max_bytes = max_bytes

    def tag(self, buf: bytes, pos: int, end: int) -> tuple[int, int, int, int]:
        """(type, data size, data start, next element) of the element at ``pos``."""
        if end - pos < 8:
            raise MatFormatError(f"truncated element tag at byte {pos}")
        first, second = struct.unpack_from(self.endian + "II", buf, pos)
        if first >> 16:  # small data element: type and size packed in one word
            mdtype, nbytes = first & 0xFFFF, first >> 16
            if nbytes > 4:
                raise MatFormatError(f"malformed small data element at byte {pos}")
            return mdtype, nbytes, pos + 4, pos + 8
        data = pos + 8
        if second > end - data:
            raise MatFormatError(
                f"element at byte {pos} claims {second:,} bytes, only {end - data:,} remain "
                f"(truncated or corrupt file)"
            )
        return first, second, data, data + second

    def matrix(
        self, buf: bytes, start: int, end: int, depth: int, name_out: list[str]
    ) -> tuple[int, tuple[int, ...], bool]:
        """Check one miMATRIX body ``buf[start:end]``; return class, shape, logical."""
        if depth > MAX_NESTING:
            raise MatFormatError(f"cell arrays nested more than {MAX_NESTING} deep")
        if start == end:  # an empty array (MATLAB writes these inside cells)
            return 6, (0, 0), False
        pos = start
        mdtype, nbytes, data, nxt = self.tag(buf, pos, end)
        if mdtype != 6 or nbytes != 8:
            raise MatFormatError(f"malformed array flags at byte {pos}")
        (flags,) = struct.unpack_from(self.endian + "I", buf, data)
        class_id = flags & 0xFF
        logical = bool(flags & _LOGICAL_FLAG)
        if class_id == 17:  # no dimensions in an opaque object's header
            raise _unsupported(class_id, None)
        pos = _pad(nxt, start)
        mdtype, nbytes, data, nxt = self.tag(buf, pos, end)
        if mdtype not in _INT32_TYPES or nbytes % 4 or not 8 <= nbytes <= 4 * _MAX_DIMS:
            raise MatFormatError(f"malformed array dimensions at byte {pos}")
        shape = struct.unpack_from(f"{self.endian}{nbytes // 4}i", buf, data)
        if any(d < 0 for d in shape):
            raise MatFormatError(f"negative array dimension {shape} at byte {pos}")
        entries = math.prod(shape)
        if entries > self.max_entries:
            dims = " x ".join(f"{d:,}" for d in shape)
            raise MatFormatError(
                f"an array of {dims} = {entries:,} entries is larger than "
                f"the limit of {self.max_entries:,} entries"
            )
        pos = _pad(nxt, start)
        mdtype, nbytes, data, nxt = self.tag(buf, pos, end)
        if mdtype not in _NAME_TYPES:
            raise MatFormatError(f"malformed array name at byte {pos}")
        name = buf[data : data + nbytes].decode("latin1")
        name_out.append(name)
        if class_id not in _SUPPORTED:
            raise _unsupported(class_id, name if depth == 0 else None)
        pos = _pad(nxt, start)
        # SciPy reads as many elements as the flags and dimensions announce, past the
        # end of this array if need be: the count must match exactly.
        if class_id == 1:  # a cell array: one array per entry
            for _ in range(entries):
                mdtype, nbytes, data, nxt = self.tag(buf, pos, end)
                if mdtype != MI_MATRIX:
                    raise MatFormatError(f"expected an array inside a cell array at byte {pos}")
                self.matrix(buf, data, data + nbytes, depth + 1, [])
                pos = _pad(nxt, start)
        else:  # numeric or char: the real part, and the imaginary part of complex numbers
            parts = 2 if flags & _COMPLEX_FLAG and class_id != 4 else 1
            for _ in range(parts):
                if pos >= end:
                    raise MatFormatError(f"missing array data at byte {pos}")
                mdtype, nbytes, data, nxt = self.tag(buf, pos, end)
                if mdtype not in _DATA_TYPES:
                    raise MatFormatError(f"array data of unknown type {mdtype} at byte {pos}")
                pos = _pad(nxt, start)
        return class_id, tuple(shape), logical


def _unsupported(class_id: int, name: str | None) -> MatFormatError:
    what = CLASS_NAMES.get(class_id, f"array of unknown class {class_id}")
    where = f"variable {name!r} is" if name is not None else "a cell array holds"
    way_out = ""
    if "object" in what:  # a state-space model saved whole, say
        way_out = (
            "; save its matrices instead: [A, B, C, D, Ts] = ssdata(sys); "
            "save(file, 'A', 'B', 'C', 'D', 'Ts', '-v7')"
        )
    return MatFormatError(
        f"{where} a MATLAB {what}; only numeric and char arrays (and cell arrays of them) are "
        f"read{way_out}"
    )


def _pad(pos: int, start: int) -> int:
    """Elements inside an array start on 8-byte boundaries."""
    return start + -(-(pos - start) // 8) * 8


def variables(raw: bytes, *, max_entries: int, max_bytes: int) -> list[MatVariable]:
    """Check the structure of a MATLAB v5 file; list its top-level variables.

    Parameters
    ----------
    raw : bytes
        The whole file.
    max_entries : int
        Largest number of entries of any array, nested ones included.
    max_bytes : int
        Largest size of a compressed variable once expanded.

    Returns
    -------
    list of MatVariable

    Raises
    ------
    MatFormatError
        If the file is not a well-formed v5 file within the limits.
    """
    if len(raw) < 128:
        raise MatFormatError("too short for a MATLAB v5 file header")
    endian = {b"IM": "<", b"MI": ">"}.get(raw[126:128])
    if endian is None:
        raise MatFormatError("not a MATLAB v5 file (no byte-order mark in the header)")
    walker = _Walker(endian, max_entries, max_bytes)
    found: list[MatVariable] = []
    pos, end = 128, len(raw)
    while pos < end:
        mdtype, nbytes, data, nxt = walker.tag(raw, pos, end)
        if mdtype == MI_COMPRESSED:
            inflater = zlib.decompressobj()
            try:
                body = inflater.decompress(raw[data:nxt], max_bytes + 1)
            except zlib.error as exc:
                raise MatFormatError(f"corrupt compressed variable at byte {pos}: {exc}") from None
            if len(body) > max_bytes:
                raise MatFormatError(
                    f"a compressed variable at byte {pos} expands beyond {max_bytes:,} bytes"
                )
            inner, size, inner_data, inner_end = walker.tag(body, 0, len(body))
            if inner != MI_MATRIX:
                raise MatFormatError(f"expected an array in the compressed element at byte {pos}")
            buf, start, stop = body, inner_data, inner_end
        elif mdtype == MI_MATRIX:
            buf, start, stop = raw, data, nxt
        else:
            raise MatFormatError(f"expected an array at byte {pos}, found element type {mdtype}")
        names: list[str] = []
        if start == stop:
            raise MatFormatError(f"empty variable record at byte {pos}")
        class_id, shape, logical = walker.matrix(buf, start, stop, 0, names)
        found.append(MatVariable(names[0], class_id, shape, logical))
        pos = nxt
    return found
