"""The certificate's matrices as a MATLAB .mat file (``ssecert analyze SPEC --mat PATH``).

Every numeric vector and matrix of the JSON certificate becomes a variable named by where it
sits: ``A`` and ``C`` (the plant), then ``CHECK__KEY__...`` (for instance
``observer_gain__L``, ``sparse_observability__witness__z``,
``observer_stability__evidence__P``), so that a MATLAB user re-checks a certificate with the
matrices it rests on.  Non-finite entries ("Infinity" in the JSON) are MATLAB's Inf and NaN; the
sensors' names are a cell array ``sensors``.  Names are cut to MATLAB's 63 characters (with a
number where two would clash).
"""

from __future__ import annotations

import io
import math
import re
from typing import Any

import numpy as np

from ..results import Certificate

__all__ = ["certificate_arrays", "certificate_mat"]

_NONFINITE = {"Infinity": math.inf, "-Infinity": -math.inf, "NaN": math.nan}
_MAX_NAME = 63  # MATLAB's namelengthmax


def _number(value: Any) -> float | None:
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return float(value)
    if isinstance(value, str) and value in _NONFINITE:
        return _NONFINITE[value]
    return None


def _array(value: Any) -> np.ndarray | None:
    """A rectangular list (of numbers, or of lists of numbers) as a float array, else None."""
    if not isinstance(value, list) or not value:
        return None
    if all(not isinstance(v, list) for v in value):
        numbers = [_number(v) for v in value]
        return None if any(v is None for v in numbers) else np.array(numbers, dtype=float)
    rows = [_array(v) for v in value]
    if any(r is None or r.ndim != 1 for r in rows) or len({r.size for r in rows}) != 1:  # type: ignore[union-attr]
        return None
    return np.vstack(rows)  # type: ignore[arg-type]


def _name(path: list[str]) -> str:
    name = re.sub(r"[^A-Za-z0-9_]", "_", "__".join(path))
    if not name[:1].isalpha():
        name = "v_" + name
    return name[:_MAX_NAME]


def certificate_arrays(certificate: Certificate | dict[str, Any]) -> dict[str, Any]:
    """The certificate's vectors and matrices by variable name (see the module doc)."""
    # the JSON document's values (to_dict is JSON-ready: lists, numbers, "Infinity")
    document = certificate.to_dict() if isinstance(certificate, Certificate) else certificate
    system = document["system"]
    out: dict[str, Any] = {}
    if isinstance(certificate, Certificate):
        out["A"] = np.asarray(certificate.system.A, dtype=float)
        out["C"] = np.asarray(certificate.system.C, dtype=float)
    names = np.empty((1, len(system["sensors"])), dtype=object)
    names[0, :] = system["sensors"]
    out["sensors"] = names

    def walk(node: Any, path: list[str]) -> None:
        array = _array(node)
        if array is not None:
            name = _name(path)
            if name in out:
                stem = name[: _MAX_NAME - 4]
                name = next(f"{stem}_{i}" for i in range(2, 10_000) if f"{stem}_{i}" not in out)
            out[name] = array
            return
        if isinstance(node, dict):
            for key, value in node.items():
                walk(value, [*path, str(key)])
        elif isinstance(node, list):
            for i, value in enumerate(node):
                walk(value, [*path, str(i)])

    for check_id, check in document["checks"].items():
        walk(check, [check_id])
    return out


def certificate_mat(certificate: Certificate) -> bytes:
    """The certificate's vectors and matrices as the bytes of a MATLAB v5 .mat file."""
    import scipy.io

    buffer = io.BytesIO()
    scipy.io.savemat(buffer, certificate_arrays(certificate), long_field_names=True)
    return buffer.getvalue()
