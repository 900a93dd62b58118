"""A validated spec written back as a TOML spec file (the format users write).

Only the structures a spec holds are written: strings, booleans, integers,
floats (``repr``, which round-trips exactly; inf and nan as TOML's inf and
nan), and lists of them; tables and arrays of tables one level deep.
``tomllib.loads(dumps(spec_document(spec)))`` gives the same spec back.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["spec_document", "dumps"]


def spec_document(spec: Any, observer: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The spec file's data for ``spec`` (a ``Spec``), with ``observer`` in place of its own
    ``[observer]`` when given."""
    data: dict[str, Any] = {"name": spec.name}
    system: dict[str, Any] = {"A": spec.system.A, "C": spec.system.C}
    if spec.system.sensors is not None:
        system["sensors"] = list(spec.system.sensors)
    data["system"] = system
    data["attack"] = {"max_attacked": int(spec.max_attacked), "horizon": int(spec.horizon)}
    section = observer if observer is not None else spec.observer
    if section is not None:
        data["observer"] = {k: v for k, v in section.items() if v is not None}
    noise = getattr(spec, "noise", None)
    if noise is not None:
        eta = noise.eta
        one = eta.size and bool((eta == eta[0]).all())
        data["noise"] = {
            **noise.to_dict(),
            "measurement": float(eta[0]) if one else eta,
        }
    if spec.scenarios:
        data["scenario"] = [_scenario(sc) for sc in spec.scenarios]
    return data


def _scenario(scenario: Mapping[str, Any]) -> dict[str, Any]:
    """A scenario's table as its file holds it: no attack takes no magnitude (the reader fills
    in the default range and refuses one written)."""
    # (the process noise's input matrix is the [noise] section's)
    out = {k: v for k, v in scenario.items() if v is not None and k != "process_input"}
    if out.get("attack") == "none":
        out.pop("magnitude", None)
    return out


def dumps(data: Mapping[str, Any]) -> str:
    """TOML text for a spec file's data."""
    lines = []
    for key, value in data.items():
        if not isinstance(value, Mapping) and not _is_table_list(value):
            lines.append(f"{key} = {_value(value)}")
    for key, value in data.items():
        if isinstance(value, Mapping):
            lines += ["", f"[{key}]"] + [f"{k} = {_value(v)}" for k, v in value.items()]
        elif _is_table_list(value):
            for table in value:
                lines += ["", f"[[{key}]]"] + [f"{k} = {_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


def _is_table_list(value: Any) -> bool:
    return (
        isinstance(value, list | tuple)
        and bool(value)
        and all(isinstance(v, Mapping) for v in value)
    )


def _value(v: Any) -> str:
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, bool | np.bool_):
        return "true" if v else "false"
    if isinstance(v, int | np.integer):
        return str(int(v))
    if isinstance(v, float | np.floating):
        f = float(v)
        if math.isnan(f):
            return "nan"
        if math.isinf(f):
            return "inf" if f > 0 else "-inf"
        return repr(f)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, complex | np.complexfloating):  # a pole: real, or its [re, im] pair
        z = complex(v)
        return _value(z.real) if z.imag == 0 else _value([z.real, z.imag])
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} to a spec file")
