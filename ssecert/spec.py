"""Design specifications: TOML (primary), JSON, NumPy .npz and MATLAB .mat.

A TOML spec (JSON has the same structure)::

    name = "ugv"
    [system]
    A = [[1.0, 0.0099], [0.0, 0.9876]]
    C = [[1, 0], [0, 1], [0, 1]]
    sensors = ["position", "velocity-a", "velocity-b"]   # optional
    [attack]
    max_attacked = 1        # s
    horizon = 2             # tau, default n
    [observer]              # optional
    kind = "dsso"
    ...
    [[scenario]]            # optional, repeatable
    name = "constant"
    attack = "constant"
    ...

``.npz`` and ``.mat`` files hold the variables ``A`` and ``C`` (and
optionally ``sensors``); s comes from ``max_attacked=`` (``--max-attacked``)
and tau from ``horizon=`` (``--horizon``, default n).  Every key is
validated and unknown keys are refused; errors name the file and the key.

Limits, checked before a file is parsed or an array is built, so that a
wrong or hostile file costs a message and not a frozen machine:

- TOML and JSON files: at most ``MAX_TEXT_BYTES`` (16 MiB: an 800 x 800
  matrix at full precision; TOML is parsed at a few MB/s and every number
  becomes a Python object), .npz and .mat files ``MAX_BINARY_BYTES``
  (256 MiB), the place for larger plants;
- every matrix: at most ``MAX_MATRIX_DIM`` (10,000) rows and columns and
  ``MAX_MATRIX_ENTRIES`` (10,000,000) entries; every list at most
  ``MAX_MATRIX_DIM`` items;
- the horizon: at most ``MAX_HORIZON`` (10,000) steps;
- integers: the 64-bit range TOML allows (-2^63 to 2^63 - 1), also in JSON;
- nesting: ``MAX_NESTING`` (16) levels of tables and lists (a spec needs 4);
- names (the spec's, sensors', scenarios'): at most ``MAX_NAME_LENGTH``
  (128) characters; no text may hold control characters or invalid Unicode.
"""

from __future__ import annotations

import difflib
import hashlib
import io
import json
import math
import numbers
import os
import re
import stat
import tomllib
import warnings
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._validation import (
    MAX_MATRIX_DIM,
    MAX_MATRIX_ENTRIES,
    as_choice,
    as_float_option,
    as_index_list,
    as_int_option,
    as_real_matrix,
    check_size,
    describe,
    show_int,
)
from .system import System

__all__ = [
    "Spec",
    "SpecError",
    "load_spec",
    "spec_from_dict",
    "OBSERVER_KINDS",
    "ATTACK_KINDS",
    "SCENARIO_DEFAULTS",
    "MAX_TEXT_BYTES",
    "MAX_BINARY_BYTES",
    "MAX_MATRIX_DIM",
    "MAX_MATRIX_ENTRIES",
    "MAX_HORIZON",
    "MAX_NESTING",
    "MAX_NAME_LENGTH",
]

MAX_TEXT_BYTES = 16 * 2**20
MAX_BINARY_BYTES = 256 * 2**20
MAX_HORIZON = 10_000
MAX_NESTING = 16
MAX_NAME_LENGTH = 128
_INT64_MIN, _INT64_MAX = -(2**63), 2**63 - 1
_MATRIX_LIMITS = {"max_dim": MAX_MATRIX_DIM, "max_entries": MAX_MATRIX_ENTRIES}

OBSERVER_KINDS = ("luenberger", "ogd", "sso", "dsso", "elastic_net")
GAIN_CHOICES = ("deadbeat", "place", "ogd", "pinv")
ATTACK_KINDS = ("none", "constant", "switching", "sinusoidal", "random", "stealthy")
SCENARIO_DEFAULTS: dict[str, Any] = {
    "magnitude": (4.0, 5.0),
    "noise": 0.0,
    "steps": 300,
    "runs": 50,
    "seed": 0,
}
_TOP_KEYS = ("name", "system", "attack", "observer", "scenario")
_SYSTEM_KEYS = ("A", "C", "sensors")
_ATTACK_KEYS = ("max_attacked", "horizon")
_SCENARIO_KEYS = (
    "name",
    "attack",
    "sensors",
    "count",
    "magnitude",
    "period",
    "noise",
    "steps",
    "runs",
    "seed",
)
# observer keys allowed per kind (DESIGN.md table)
_OBSERVER_KEYS = {
    "luenberger": ("kind", "gain", "poles"),
    "ogd": ("kind", "gain", "step"),
    "sso": ("kind", "step", "threshold", "shrink", "window", "inner_steps"),
    "dsso": ("kind", "gain", "poles", "step", "threshold", "shrink"),
    "elastic_net": ("kind", "gain", "poles", "step", "threshold", "shrink", "L2"),
}
_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")


class SpecError(ValueError):
    """A spec file or spec dictionary is invalid.

    The message names the file and the key, says what was expected and what
    was found.  It is one line: control characters from the file (in keys,
    names or paths) are shown escaped.
    """

    def __init__(self, message: str) -> None:
        super().__init__(one_line(message))


# control characters, line and paragraph separators, bidirectional overrides
_UNPRINTABLE = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]")


def one_line(text: str) -> str:
    """``text`` with control characters escaped and lone surrogates replaced."""
    text = _UNPRINTABLE.sub(lambda m: ascii(m.group())[1:-1], text)
    return text.encode("utf-8", "backslashreplace").decode("utf-8")


@dataclass(frozen=True)
class Spec:
    """A validated design: plant, attack bound, optional observer and scenarios.

    Attributes
    ----------
    name : str
        Design name, used for report file names.
    system : System
    max_attacked : int
        s, the number of sensors the adversary may control.
    horizon : int
        tau, the stacked window (default n).
    observer : mapping or None
        Validated ``[observer]`` section (keys as in DESIGN.md).
    scenarios : tuple of mapping
        Validated ``[[scenario]]`` sections with defaults filled in.
    source : str
        File path or ``"<dict>"``.
    sha256 : str or None
        Hash of the file's bytes.
    """

    name: str
    system: System
    max_attacked: int
    horizon: int
    observer: Mapping[str, Any] | None = None
    scenarios: tuple[Mapping[str, Any], ...] = field(default=())
    source: str = "<dict>"
    sha256: str | None = None


def _err(source: str, key: str | None, message: str) -> SpecError:
    if key is not None and len(key) > 80:
        key = key[:77] + "..."
    where = f"{source}: key '{key}'" if key else source
    return SpecError(f"{where}: {message}")


def _suggest(key: Any, allowed: tuple[str, ...]) -> str:
    """' (did you mean 'X'?)' for a misspelt or wrongly capitalised key, else ''."""
    text = str(key)
    close = [a for a in allowed if a.lower() == text.lower()]
    close = close or difflib.get_close_matches(text, allowed, n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def _check_keys(source: str, prefix: str, table: Any, allowed: tuple[str, ...]) -> None:
    if not isinstance(table, Mapping):
        raise _err(source, prefix or None, f"expected a table, got {describe(table)}")
    for key in table:
        if key not in allowed:
            hint = _suggest(key, allowed)
            full = f"{prefix}.{key}" if prefix else str(key)
            raise _err(source, full, f"unknown key{hint}; allowed here: {', '.join(allowed)}")


def _convert(source: str, key: str, func: Any, *args: Any, **kwargs: Any) -> Any:
    """Run a converter, turning its error into a SpecError naming file and key."""
    try:
        return func(*args, **kwargs)
    except (TypeError, ValueError) as exc:
        message = str(exc)
        # converters name their argument first; the key already names it here
        name = kwargs.get("name") or (args[1] if len(args) > 1 else None)
        if isinstance(name, str) and message.startswith(name + " "):
            message = message[len(name) :].lstrip(" :")
        raise _err(source, key, message) from None


class _TooLongInteger:
    """An integer literal too long to convert (JSON ``parse_int``)."""

    def __init__(self, text: str) -> None:
        self.digits = len(text.lstrip("+-"))


def _check_text(source: str, path: str, text: str, what: str) -> None:
    """Refuse text that cannot be shown on one line or written as UTF-8."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise _err(
            source,
            path or None,
            f"{what} is not valid Unicode (a lone surrogate "
            f"{text[exc.start]!a} at position {exc.start})",
        ) from None
    bad = _UNPRINTABLE.search(text)
    if bad:
        raise _err(
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
            raise _err(
                source,
                path or None,
                f"nested more than {MAX_NESTING} levels deep (a spec needs at most 4)",
            )
        is_table = isinstance(container, Mapping)
        if not is_table and len(container) > MAX_MATRIX_DIM:
            raise _err(
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
                raise _err(
                    source,
                    _path(path, index),
                    f"an integer of {item.digits:,} digits is out of range: spec "
                    f"integers must fit in 64 bits (-2^63 to 2^63 - 1)",
                )
            elif isinstance(item, int) and not _INT64_MIN <= item <= _INT64_MAX:
                text = show_int(item)
                text = text if "digits" in text else f"the integer {text}"
                raise _err(
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


def _check_name(source: str, key: str, value: Any, what: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise _err(source, key, f"expected a non-empty string, got {describe(value)}")
    if len(value) > MAX_NAME_LENGTH:
        raise _err(
            source, key, f"{what} has {len(value):,} characters; the limit is {MAX_NAME_LENGTH}"
        )
    return value


def _require(source: str, table: Mapping[str, Any], key: str, prefix: str) -> Any:
    if key not in table:
        raise _err(source, f"{prefix}.{key}" if prefix else key, "missing (required)")
    return table[key]


def spec_from_dict(
    data: Mapping[str, Any],
    *,
    source: str = "<dict>",
    max_attacked: int | None = None,
    horizon: int | None = None,
    sha256: str | None = None,
    default_name: str | None = None,
) -> Spec:
    """Validate a spec given as a dictionary (the parsed TOML/JSON document).

    Parameters
    ----------
    data : mapping
        Top-level keys ``name``, ``system``, ``attack``, ``observer``,
        ``scenario``.
    source : str
        Name used in error messages.
    max_attacked, horizon : int, optional
        Override ``attack.max_attacked`` and ``attack.horizon``.
    sha256 : str, optional
        Hash recorded in the Spec.
    default_name : str, optional
        Name used when ``name`` is absent.

    Returns
    -------
    Spec

    Raises
    ------
    SpecError
        If anything is missing, unknown, of the wrong kind or out of range.

    Examples
    --------
    >>> spec = spec_from_dict({"name": "demo", "system": {"A": [[1.0]], "C": [[1.0], [2.0]]},
    ...                        "attack": {"max_attacked": 0}})
    >>> spec.system.p, spec.horizon
    (2, 1)
    """
    _check_keys(source, "", data, _TOP_KEYS)
    _check_document(source, data)
    name = data.get("name", default_name)
    if name is None:
        raise _err(source, "name", "missing (required)")
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise _err(
            source,
            "name",
            f"expected a name of letters, digits, '.', '_' or '-' (it names the report files), "
            f"got {describe(name)}",
        )
    _check_name(source, "name", name, "the name")
    system_table = _require(source, data, "system", "")
    _check_keys(source, "system", system_table, _SYSTEM_KEYS)
    A = _convert(
        source,
        "system.A",
        as_real_matrix,
        _require(source, system_table, "A", "system"),
        "A",
        **_MATRIX_LIMITS,
    )
    if A.shape[0] != A.shape[1]:
        raise _err(source, "system.A", f"expected a square matrix, got shape {A.shape}")
    n = A.shape[0]
    C = _convert(
        source,
        "system.C",
        as_real_matrix,
        _require(source, system_table, "C", "system"),
        "C",
        shape=(None, n),
        shape_hint="the number of states, from A",
        **_MATRIX_LIMITS,
    )
    sensors = system_table.get("sensors")
    if isinstance(sensors, (list, tuple)) and len(sensors) == C.shape[0]:
        for i, label in enumerate(sensors):
            if isinstance(label, str) and len(label) > MAX_NAME_LENGTH:
                raise _err(
                    source,
                    "system.sensors",
                    f"sensors[{i}] has {len(label):,} characters; the limit is {MAX_NAME_LENGTH}",
                )
    try:
        system = System(A, C, sensors=sensors, name=name)
    except (TypeError, ValueError) as exc:
        raise _err(source, "system.sensors", str(exc)) from None
    p = system.p

    attack_table = data.get("attack", {})
    _check_keys(source, "attack", attack_table, _ATTACK_KEYS)
    if max_attacked is not None:
        s = _convert(
            source,
            "--max-attacked",
            _spec_int,
            max_attacked,
            "max_attacked",
            min_value=0,
            max_value=_INT64_MAX,
        )
    elif "max_attacked" in attack_table:
        s = _convert(
            source,
            "attack.max_attacked",
            _spec_int,
            attack_table["max_attacked"],
            "max_attacked",
            min_value=0,
        )
    else:
        raise _err(
            source,
            "attack.max_attacked",
            "missing (required): the number of attacked sensors s; or pass --max-attacked",
        )
    if horizon is not None:
        tau = _convert(
            source, "--horizon", _spec_int, horizon, "horizon", min_value=1, max_value=MAX_HORIZON
        )
    elif "horizon" in attack_table:
        tau = _convert(
            source,
            "attack.horizon",
            _spec_int,
            attack_table["horizon"],
            "horizon",
            min_value=1,
            max_value=MAX_HORIZON,
        )
    else:
        tau = n

    observer = None
    if "observer" in data:
        observer = _observer(source, data["observer"], n, p)
    scenarios: list[dict[str, Any]] = []
    raw_scenarios = data.get("scenario", [])
    if isinstance(raw_scenarios, Mapping):
        raw_scenarios = [raw_scenarios]
    if not isinstance(raw_scenarios, list):
        raise _err(
            source,
            "scenario",
            f"expected a list of tables ([[scenario]]), got {describe(raw_scenarios)}",
        )
    seen: set[str] = set()
    for index, table in enumerate(raw_scenarios):
        scenario = _scenario(source, f"scenario[{index}]", table, p)
        if scenario["name"] in seen:
            raise _err(
                source, f"scenario[{index}].name", f"duplicate scenario name {scenario['name']!r}"
            )
        seen.add(scenario["name"])
        scenarios.append(scenario)
    return Spec(
        name=name,
        system=system,
        max_attacked=s,
        horizon=tau,
        observer=observer,
        scenarios=tuple(scenarios),
        source=source,
        sha256=sha256,
    )


def _spec_int(value: Any, name: str, *, min_value: int, max_value: int = _INT64_MAX) -> int:
    """An integer option of a spec: at most 2^63 - 1 also when written as a float."""
    return as_int_option(value, name, min_value=min_value, max_value=max_value)


def _positive(source: str, key: str, value: Any) -> float:
    return _convert(
        source, key, as_float_option, value, key.split(".")[-1], min_value=0.0, min_inclusive=False
    )


def _poles(source: str, key: str, value: Any, n: int) -> list[complex]:
    if not isinstance(value, list):
        raise _err(source, key, f"expected a list of {n} poles, got {describe(value)}")
    if len(value) != n:
        raise _err(source, key, f"expected {n} poles (one per state), got {len(value):,}")
    poles: list[complex] = []
    for i, item in enumerate(value):
        if (
            isinstance(item, list)
            and len(item) == 2
            and all(isinstance(x, numbers.Real) and not isinstance(x, bool) for x in item)
        ):
            pole = complex(float(item[0]), float(item[1]))
        elif isinstance(item, numbers.Real) and not isinstance(item, bool):
            pole = complex(float(item), 0.0)
        else:
            raise _err(
                source,
                f"{key}[{i}]",
                f"expected a real number or a [re, im] pair, got {describe(item)}",
            )
        if not (math.isfinite(pole.real) and math.isfinite(pole.imag)):
            raise _err(source, f"{key}[{i}]", f"must be finite, got {pole}")
        poles.append(pole)
    if len(poles) != n:
        raise _err(source, key, f"expected {n} poles (one per state), got {len(poles)}")
    remaining = [q for q in poles if q.imag != 0]
    while remaining:
        q = remaining.pop(0)
        match = next((r for r in remaining if r == q.conjugate()), None)
        if match is None:
            raise _err(source, key, f"complex pole {q} has no conjugate partner")
        remaining.remove(match)
    return poles


def _observer(source: str, table: Any, n: int, p: int) -> dict[str, Any]:
    if not isinstance(table, Mapping):
        raise _err(source, "observer", f"expected a table, got {describe(table)}")
    kind = _convert(
        source,
        "observer.kind",
        as_choice,
        _require(source, table, "kind", "observer"),
        "kind",
        OBSERVER_KINDS,
    )
    _check_keys(source, "observer", table, _OBSERVER_KEYS[kind])
    out: dict[str, Any] = {"kind": kind}
    if kind != "sso":
        gain = table.get("gain", "ogd" if kind == "ogd" else "deadbeat")
        if isinstance(gain, str):
            allowed = {"ogd": ("ogd",), "dsso": ("deadbeat", "pinv", "place")}.get(
                kind, ("deadbeat", "place", "pinv") if kind == "luenberger" else GAIN_CHOICES
            )
            if kind == "ogd" and gain != "ogd":
                raise _err(
                    source,
                    "observer.gain",
                    f"the ogd observer's gain is fixed (L = step * A C^T); got {gain!r}",
                )
            gain = _convert(source, "observer.gain", as_choice, gain, "gain", allowed)
        elif kind == "ogd":
            raise _err(
                source,
                "observer.gain",
                "the ogd observer's gain is fixed (L = step * A C^T); remove this key",
            )
        else:
            gain = _convert(
                source,
                "observer.gain",
                as_real_matrix,
                gain,
                "gain",
                shape=(n, p),
                shape_hint="n x p: states by sensors",
                **_MATRIX_LIMITS,
            )
        out["gain"] = gain
        if isinstance(gain, str) and gain == "place":
            out["poles"] = _poles(
                source, "observer.poles", _require(source, table, "poles", "observer"), n
            )
        elif "poles" in table:
            raise _err(source, "observer.poles", 'poles are only used with gain = "place"')
    if kind != "luenberger":
        out["step"] = _positive(
            source, "observer.step", _require(source, table, "step", "observer")
        )
    if kind in ("sso", "dsso", "elastic_net"):
        out["threshold"] = _positive(
            source, "observer.threshold", _require(source, table, "threshold", "observer")
        )
    if kind in ("sso", "dsso"):
        if "shrink" in table:
            shrink = _convert(source, "observer.shrink", as_float_option, table["shrink"], "shrink")
            if shrink != 1.0:
                raise _err(
                    source,
                    "observer.shrink",
                    f'the {kind} observer has shrink = 1; use kind = "elastic_net" for '
                    f"shrink < 1, got {shrink}",
                )
        out["shrink"] = 1.0
    if kind == "elastic_net":
        out["shrink"] = _convert(
            source,
            "observer.shrink",
            as_float_option,
            _require(source, table, "shrink", "observer"),
            "shrink",
            min_value=0.0,
            max_value=1.0,
            min_inclusive=False,
            max_inclusive=False,
        )
        if "L2" in table:
            out["L2"] = _convert(
                source,
                "observer.L2",
                as_real_matrix,
                table["L2"],
                "L2",
                shape=(p, p),
                shape_hint="p x p: sensors by sensors",
                **_MATRIX_LIMITS,
            )
    if kind == "sso":
        out["window"] = _convert(
            source, "observer.window", _spec_int, table.get("window", 1), "window", min_value=1
        )
        out["inner_steps"] = _convert(
            source,
            "observer.inner_steps",
            _spec_int,
            table.get("inner_steps", 1),
            "inner_steps",
            min_value=1,
        )
    return out


def _scenario(source: str, prefix: str, table: Any, p: int) -> dict[str, Any]:
    _check_keys(source, prefix, table, _SCENARIO_KEYS)
    name = _check_name(
        source, f"{prefix}.name", _require(source, table, "name", prefix), "a scenario name"
    )
    attack = _convert(
        source,
        f"{prefix}.attack",
        as_choice,
        _require(source, table, "attack", prefix),
        "attack",
        ATTACK_KINDS,
    )
    out: dict[str, Any] = {"name": name, "attack": attack}
    has_sensors, has_count = "sensors" in table, "count" in table
    if attack in ("none", "stealthy"):
        for key in ("sensors", "count"):
            if key in table:
                raise _err(
                    source,
                    f"{prefix}.{key}",
                    f"not used by attack = {attack!r}"
                    + (
                        " (the sensors come from the sparse-observability witness)"
                        if attack == "stealthy"
                        else ""
                    ),
                )
    elif attack in ("switching", "random"):
        if has_sensors:
            raise _err(
                source,
                f"{prefix}.sensors",
                f"attack = {attack!r} draws its supports at random; give count instead",
            )
        out["count"] = _convert(
            source,
            f"{prefix}.count",
            _spec_int,
            _require(source, table, "count", prefix),
            "count",
            min_value=1,
            max_value=p,
        )
    else:
        if has_sensors == has_count:
            raise _err(
                source,
                f"{prefix}.sensors",
                f"attack = {attack!r} needs exactly one of sensors (0-based indices) or "
                f"count (a random support of that size)",
            )
        if has_sensors:
            sensors = _convert(
                source, f"{prefix}.sensors", as_index_list, table["sensors"], "sensors", upper=p
            )
            if not sensors:
                raise _err(source, f"{prefix}.sensors", "expected at least one sensor")
            out["sensors"] = list(sensors)
        else:
            out["count"] = _convert(
                source,
                f"{prefix}.count",
                _spec_int,
                table["count"],
                "count",
                min_value=1,
                max_value=p,
            )
    if attack in ("switching", "sinusoidal"):
        out["period"] = _convert(
            source,
            f"{prefix}.period",
            _spec_int,
            _require(source, table, "period", prefix),
            "period",
            min_value=1,
        )
    elif "period" in table:
        raise _err(
            source,
            f"{prefix}.period",
            f"only used by switching and sinusoidal attacks, not {attack!r}",
        )
    if "magnitude" in table:
        if attack == "none":
            raise _err(source, f"{prefix}.magnitude", "not used by attack = 'none'")
        mag = table["magnitude"]
        if isinstance(mag, numbers.Real) and not isinstance(mag, bool):
            mag = [mag, mag]
        arr = _convert(
            source, f"{prefix}.magnitude", as_real_matrix, mag, "magnitude", shape=(2,), ndim=1
        )
        if arr[0] < 0 or arr[0] > arr[1]:
            raise _err(
                source,
                f"{prefix}.magnitude",
                f"expected [low, high] with 0 <= low <= high, got {arr.tolist()}",
            )
        out["magnitude"] = (float(arr[0]), float(arr[1]))
    else:
        out["magnitude"] = SCENARIO_DEFAULTS["magnitude"]
    out["noise"] = _convert(
        source,
        f"{prefix}.noise",
        as_float_option,
        table.get("noise", SCENARIO_DEFAULTS["noise"]),
        "noise",
        min_value=0.0,
    )
    for key in ("steps", "runs"):
        out[key] = _convert(
            source,
            f"{prefix}.{key}",
            _spec_int,
            table.get(key, SCENARIO_DEFAULTS[key]),
            key,
            min_value=1,
        )
    out["seed"] = _convert(
        source,
        f"{prefix}.seed",
        _spec_int,
        table.get("seed", SCENARIO_DEFAULTS["seed"]),
        "seed",
        min_value=0,
    )
    return out


_NPY_MAGIC = b"\x93NUMPY"


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
    keys = []
    for member in members:
        key = member[:-4] if member.endswith(".npy") else member
        if key not in _SYSTEM_KEYS:
            hint = _suggest(key, _SYSTEM_KEYS)
            raise _err(source, key, f"unknown variable{hint}; expected A, C and optionally sensors")
        if key in keys:
            raise _err(source, key, "the archive holds this variable twice")
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
                limits = _MATRIX_LIMITS
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
        raise _err(source, name, str(exc)) from None
    if math.prod(shape) * dtype.itemsize > 16 * max_entries:
        raise _err(
            source,
            name,
            f"the variable is too large: {math.prod(shape):,} entries of {dtype.itemsize:,} bytes",
        )


def _read_mat(raw: bytes, source: str) -> dict[str, Any]:
    """Variables of a MATLAB .mat file (v4 or v5), checked before SciPy reads them."""
    import scipy.io

    from ._matfile import MatFormatError, variables

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
    seen = set()
    for name, class_name, shape in found:
        if name not in _SYSTEM_KEYS:
            hint = _suggest(name, _SYSTEM_KEYS)
            raise _err(
                source, name, f"unknown variable{hint}; expected A, C and optionally sensors"
            )
        if name in seen:
            raise _err(source, name, "the file holds this variable twice")
        seen.add(name)
        numeric = class_name in ("double", "single") or class_name.startswith(("int", "uint"))
        if name != "sensors" and not numeric:
            raise _err(
                source, f"system.{name}", f"must contain real numbers, got a MATLAB {class_name}"
            )
        limits = (
            _MATRIX_LIMITS
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
        if key not in _SYSTEM_KEYS:  # pragma: no cover - refused before loading
            raise _err(source, key, "unknown variable; expected A, C and optionally sensors")
    if "sensors" in data:
        data["sensors"] = _names(source, data["sensors"])
    return data


def _names(source: str, value: Any) -> list[str]:
    """Sensor names from an array of strings or a MATLAB cell array."""
    arr = np.asarray(value)
    names: list[str] = []
    for item in arr.ravel():
        if isinstance(item, np.ndarray):
            item = item.ravel()
            if item.size != 1:
                raise _err(source, "sensors", "expected one name per sensor")
            item = item[0]
        if not isinstance(item, (str, np.str_)):
            raise _err(source, "sensors", f"expected strings, got {describe(item)}")
        names.append(str(item).strip())
    return names


def load_spec(
    path: str | os.PathLike[str],
    *,
    max_attacked: int | None = None,
    horizon: int | None = None,
    source: str | None = None,
) -> Spec:
    """Load and validate a spec file (.toml, .json, .npz or .mat).

    Parameters
    ----------
    path : str or path-like
    max_attacked : int, optional
        s; required for .npz and .mat files, overrides the spec otherwise.
    horizon : int, optional
        tau; overrides the spec (default n).
    source : str, optional
        How messages and reports name the file; default ``path`` exactly as
        given (a relative path stays relative).

    Returns
    -------
    Spec

    Raises
    ------
    SpecError
        If the file cannot be read, is larger than the limits (see the module
        documentation) or its content is invalid.
    TypeError
        If ``path`` is not a path.

    Examples
    --------
    >>> from ssecert.examples import example_path
    >>> spec = load_spec(example_path("ugv"))
    >>> spec.name, spec.system.sensors[0], spec.max_attacked
    ('ugv', 'position', 1)
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a file path (str or os.PathLike), got {describe(path)}")
    if source is None:
        source = path if isinstance(path, str) else os.fspath(path)
    source = one_line(str(source))
    path = Path(path)
    suffix = path.suffix.lower()
    raw = _read_file(path, source, suffix)
    digest = hashlib.sha256(raw).hexdigest()
    if suffix in (".npz", ".mat"):
        arrays = _read_arrays(raw, suffix, source)
        for key in ("A", "C"):
            if key not in arrays:
                raise _err(source, key, "missing (required variable)")
        if max_attacked is None:
            raise SpecError(
                f"{source}: a {suffix} file holds only the plant; give the number of attacked "
                f"sensors with --max-attacked (max_attacked=...)"
            )
        data: Any = {"system": {k: arrays[k] for k in _SYSTEM_KEYS if k in arrays}}
        default = "system"
    else:
        data = _parse_text(raw, suffix, source)
        default = "spec"
    stem = re.sub(r"[^A-Za-z0-9._-]", "-", path.stem)[:MAX_NAME_LENGTH].lstrip("._-") or default
    return spec_from_dict(
        data,
        source=source,
        max_attacked=max_attacked,
        horizon=horizon,
        sha256=digest,
        default_name=stem,
    )


def _read_file(path: Path, source: str, suffix: str) -> bytes:
    """The file's bytes, refused before reading when it is not a spec file or too large."""
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise SpecError(f"{source}: no such file") from None
    except NotADirectoryError:
        raise SpecError(f"{source}: no such file (a part of the path is not a folder)") from None
    except ValueError:  # a NUL byte in the name
        raise SpecError(f"{source}: not a valid file name") from None
    except OSError as exc:
        raise SpecError(f"{source}: cannot read: {exc.strerror or exc}") from None
    if stat.S_ISDIR(info.st_mode):
        raise SpecError(f"{source}: is a directory, expected a spec file")
    if not stat.S_ISREG(info.st_mode):
        raise SpecError(
            f"{source}: not a regular file (a device, pipe or socket); expected a spec file"
        )
    if suffix not in (".toml", ".json", ".npz", ".mat"):
        raise SpecError(
            f"{source}: unknown file type {suffix or '(none)'!r}; expected .toml, .json, .npz "
            f"or .mat"
        )
    limit = MAX_TEXT_BYTES if suffix in (".toml", ".json") else MAX_BINARY_BYTES
    kind = "TOML and JSON specs" if suffix in (".toml", ".json") else ".npz and .mat files"
    if info.st_size > limit:
        raise SpecError(
            f"{source}: the file has {info.st_size:,} bytes "
            f"({info.st_size / 2**20:.1f} MiB); {kind} are limited to "
            f"{limit // 2**20} MiB ({limit:,} bytes)"
        )
    try:
        with open(path, "rb") as handle:
            raw = handle.read(limit + 1)
    except OSError as exc:
        raise SpecError(f"{source}: cannot read: {exc.strerror or exc}") from None
    if len(raw) > limit:  # grew since stat
        raise SpecError(
            f"{source}: the file has more than {limit:,} bytes; {kind} are "
            f"limited to {limit // 2**20} MiB"
        )
    if not raw.strip():
        raise SpecError(
            f"{source}: the file is empty; expected a spec (see 'ssecert examples ugv' for one)"
        )
    return raw


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
