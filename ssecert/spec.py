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
"""

from __future__ import annotations

import difflib
import hashlib
import json
import math
import numbers
import re
import tomllib
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._validation import (
    as_choice,
    as_float_option,
    as_index_list,
    as_int_option,
    as_real_matrix,
    describe,
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
]

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
    "name", "attack", "sensors", "count", "magnitude", "period", "noise", "steps", "runs", "seed",
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
    was found.
    """


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
            raise _err(
                source, full, f"unknown key{hint}; allowed here: {', '.join(allowed)}"
            )


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
    name = data.get("name", default_name)
    if name is None:
        raise _err(source, "name", "missing (required)")
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise _err(
            source, "name",
            f"expected a name of letters, digits, '.', '_' or '-' (it names the report files), "
            f"got {describe(name)}",
        )
    system_table = _require(source, data, "system", "")
    _check_keys(source, "system", system_table, _SYSTEM_KEYS)
    A = _convert(source, "system.A", as_real_matrix, _require(source, system_table, "A", "system"),
                 "A")
    if A.shape[0] != A.shape[1]:
        raise _err(source, "system.A", f"expected a square matrix, got shape {A.shape}")
    n = A.shape[0]
    C = _convert(source, "system.C", as_real_matrix, _require(source, system_table, "C", "system"),
                 "C", shape=(None, n), shape_hint="the number of states, from A")
    sensors = system_table.get("sensors")
    try:
        system = System(A, C, sensors=sensors, name=name)
    except (TypeError, ValueError) as exc:
        raise _err(source, "system.sensors", str(exc)) from None
    p = system.p

    attack_table = data.get("attack", {})
    _check_keys(source, "attack", attack_table, _ATTACK_KEYS)
    if max_attacked is not None:
        s = _convert(source, "--max-attacked", as_int_option, max_attacked, "max_attacked",
                     min_value=0)
    elif "max_attacked" in attack_table:
        s = _convert(source, "attack.max_attacked", as_int_option, attack_table["max_attacked"],
                     "max_attacked", min_value=0)
    else:
        raise _err(source, "attack.max_attacked",
                   "missing (required): the number of attacked sensors s; or pass --max-attacked")
    if horizon is not None:
        tau = _convert(source, "--horizon", as_int_option, horizon, "horizon", min_value=1)
    elif "horizon" in attack_table:
        tau = _convert(source, "attack.horizon", as_int_option, attack_table["horizon"],
                       "horizon", min_value=1)
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
        raise _err(source, "scenario", f"expected a list of tables ([[scenario]]), "
                   f"got {describe(raw_scenarios)}")
    seen: set[str] = set()
    for index, table in enumerate(raw_scenarios):
        scenario = _scenario(source, f"scenario[{index}]", table, p)
        if scenario["name"] in seen:
            raise _err(source, f"scenario[{index}].name",
                       f"duplicate scenario name {scenario['name']!r}")
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


def _positive(source: str, key: str, value: Any) -> float:
    return _convert(source, key, as_float_option, value, key.split(".")[-1], min_value=0.0,
                    min_inclusive=False)


def _poles(source: str, key: str, value: Any, n: int) -> list[complex]:
    if not isinstance(value, list):
        raise _err(source, key, f"expected a list of {n} poles, got {describe(value)}")
    poles: list[complex] = []
    for i, item in enumerate(value):
        if isinstance(item, list) and len(item) == 2 and all(
            isinstance(x, numbers.Real) and not isinstance(x, bool) for x in item
        ):
            pole = complex(float(item[0]), float(item[1]))
        elif isinstance(item, numbers.Real) and not isinstance(item, bool):
            pole = complex(float(item), 0.0)
        else:
            raise _err(source, f"{key}[{i}]",
                       f"expected a real number or a [re, im] pair, got {describe(item)}")
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
    kind = _convert(source, "observer.kind", as_choice, _require(source, table, "kind", "observer"),
                    "kind", OBSERVER_KINDS)
    _check_keys(source, "observer", table, _OBSERVER_KEYS[kind])
    out: dict[str, Any] = {"kind": kind}
    if kind != "sso":
        gain = table.get("gain", "ogd" if kind == "ogd" else "deadbeat")
        if isinstance(gain, str):
            allowed = {"ogd": ("ogd",), "dsso": ("deadbeat", "pinv", "place")}.get(
                kind, ("deadbeat", "place", "pinv") if kind == "luenberger" else GAIN_CHOICES
            )
            if kind == "ogd" and gain != "ogd":
                raise _err(source, "observer.gain",
                           f"the ogd observer's gain is fixed (L = step * A C^T); got {gain!r}")
            gain = _convert(source, "observer.gain", as_choice, gain, "gain", allowed)
        elif kind == "ogd":
            raise _err(source, "observer.gain",
                       "the ogd observer's gain is fixed (L = step * A C^T); remove this key")
        else:
            gain = _convert(source, "observer.gain", as_real_matrix, gain, "gain", shape=(n, p),
                            shape_hint="n x p: states by sensors")
        out["gain"] = gain
        if isinstance(gain, str) and gain == "place":
            out["poles"] = _poles(source, "observer.poles",
                                  _require(source, table, "poles", "observer"), n)
        elif "poles" in table:
            raise _err(source, "observer.poles", "poles are only used with gain = \"place\"")
    if kind != "luenberger":
        out["step"] = _positive(source, "observer.step", _require(source, table, "step", "observer"))
    if kind in ("sso", "dsso", "elastic_net"):
        out["threshold"] = _positive(source, "observer.threshold",
                                     _require(source, table, "threshold", "observer"))
    if kind in ("sso", "dsso"):
        if "shrink" in table:
            shrink = _convert(source, "observer.shrink", as_float_option, table["shrink"], "shrink")
            if shrink != 1.0:
                raise _err(source, "observer.shrink",
                           f"the {kind} observer has shrink = 1; use kind = \"elastic_net\" for "
                           f"shrink < 1, got {shrink}")
        out["shrink"] = 1.0
    if kind == "elastic_net":
        out["shrink"] = _convert(
            source, "observer.shrink", as_float_option,
            _require(source, table, "shrink", "observer"), "shrink",
            min_value=0.0, max_value=1.0, min_inclusive=False, max_inclusive=False,
        )
        if "L2" in table:
            out["L2"] = _convert(source, "observer.L2", as_real_matrix, table["L2"], "L2",
                                 shape=(p, p), shape_hint="p x p: sensors by sensors")
    if kind == "sso":
        out["window"] = _convert(source, "observer.window", as_int_option,
                                 table.get("window", 1), "window", min_value=1)
        out["inner_steps"] = _convert(source, "observer.inner_steps", as_int_option,
                                      table.get("inner_steps", 1), "inner_steps", min_value=1)
    return out


def _scenario(source: str, prefix: str, table: Any, p: int) -> dict[str, Any]:
    _check_keys(source, prefix, table, _SCENARIO_KEYS)
    name = _require(source, table, "name", prefix)
    if not isinstance(name, str) or not name.strip():
        raise _err(source, f"{prefix}.name", f"expected a non-empty string, got {describe(name)}")
    attack = _convert(source, f"{prefix}.attack", as_choice,
                      _require(source, table, "attack", prefix), "attack", ATTACK_KINDS)
    out: dict[str, Any] = {"name": name, "attack": attack}
    has_sensors, has_count = "sensors" in table, "count" in table
    if attack in ("none", "stealthy"):
        for key in ("sensors", "count"):
            if key in table:
                raise _err(source, f"{prefix}.{key}",
                           f"not used by attack = {attack!r}"
                           + (" (the sensors come from the sparse-observability witness)"
                              if attack == "stealthy" else ""))
    elif attack in ("switching", "random"):
        if has_sensors:
            raise _err(source, f"{prefix}.sensors",
                       f"attack = {attack!r} draws its supports at random; give count instead")
        out["count"] = _convert(source, f"{prefix}.count", as_int_option,
                                _require(source, table, "count", prefix), "count",
                                min_value=1, max_value=p)
    else:
        if has_sensors == has_count:
            raise _err(source, f"{prefix}.sensors",
                       f"attack = {attack!r} needs exactly one of sensors (0-based indices) or "
                       f"count (a random support of that size)")
        if has_sensors:
            sensors = _convert(source, f"{prefix}.sensors", as_index_list, table["sensors"],
                               "sensors", upper=p)
            if not sensors:
                raise _err(source, f"{prefix}.sensors", "expected at least one sensor")
            out["sensors"] = list(sensors)
        else:
            out["count"] = _convert(source, f"{prefix}.count", as_int_option, table["count"],
                                    "count", min_value=1, max_value=p)
    if attack in ("switching", "sinusoidal"):
        out["period"] = _convert(source, f"{prefix}.period", as_int_option,
                                 _require(source, table, "period", prefix), "period", min_value=1)
    elif "period" in table:
        raise _err(source, f"{prefix}.period",
                   f"only used by switching and sinusoidal attacks, not {attack!r}")
    if "magnitude" in table:
        if attack == "none":
            raise _err(source, f"{prefix}.magnitude", "not used by attack = 'none'")
        mag = table["magnitude"]
        if isinstance(mag, numbers.Real) and not isinstance(mag, bool):
            mag = [mag, mag]
        arr = _convert(source, f"{prefix}.magnitude", as_real_matrix, mag, "magnitude",
                       shape=(2,), ndim=1)
        if arr[0] < 0 or arr[0] > arr[1]:
            raise _err(source, f"{prefix}.magnitude",
                       f"expected [low, high] with 0 <= low <= high, got {arr.tolist()}")
        out["magnitude"] = (float(arr[0]), float(arr[1]))
    else:
        out["magnitude"] = SCENARIO_DEFAULTS["magnitude"]
    out["noise"] = _convert(source, f"{prefix}.noise", as_float_option,
                            table.get("noise", SCENARIO_DEFAULTS["noise"]), "noise", min_value=0.0)
    for key in ("steps", "runs"):
        out[key] = _convert(source, f"{prefix}.{key}", as_int_option,
                            table.get(key, SCENARIO_DEFAULTS[key]), key, min_value=1)
    out["seed"] = _convert(source, f"{prefix}.seed", as_int_option,
                           table.get("seed", SCENARIO_DEFAULTS["seed"]), "seed", min_value=0)
    return out


def _read_arrays(path: Path, source: str) -> dict[str, Any]:
    """Variables of an .npz or .mat file."""
    if path.suffix.lower() == ".npz":
        try:
            with open(path, "rb") as handle:  # closed even when numpy fails
                loaded = np.load(handle, allow_pickle=False)
                if not isinstance(loaded, np.lib.npyio.NpzFile):
                    raise ValueError("expected an .npz archive of named arrays (numpy.savez), "
                                     "got a single .npy array")
                with loaded as npz:
                    data = {k: npz[k] for k in npz.files}
        except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
            raise SpecError(f"{source}: cannot read the .npz file: {exc}") from None
    else:
        import scipy.io

        try:
            raw = scipy.io.loadmat(str(path))
        except NotImplementedError:
            raise SpecError(
                f"{source}: MATLAB v7.3 (HDF5) files are not supported; save with -v7"
            ) from None
        except (ValueError, OSError, TypeError, EOFError, scipy.io.matlab.MatReadError) as exc:
            raise SpecError(f"{source}: cannot read the .mat file: {exc}") from None
        data = {k: v for k, v in raw.items() if not k.startswith("__")}
    for key in data:
        if key not in _SYSTEM_KEYS:
            hint = _suggest(key, _SYSTEM_KEYS)
            raise _err(source, key, f"unknown variable{hint}; expected A, C and optionally sensors")
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
    path: str | Path,
    *,
    max_attacked: int | None = None,
    horizon: int | None = None,
) -> Spec:
    """Load and validate a spec file (.toml, .json, .npz or .mat).

    Parameters
    ----------
    path : str or Path
    max_attacked : int, optional
        s; required for .npz and .mat files, overrides the spec otherwise.
    horizon : int, optional
        tau; overrides the spec (default n).

    Returns
    -------
    Spec

    Raises
    ------
    SpecError
        If the file cannot be read or its content is invalid.

    Examples
    --------
    >>> from ssecert.examples import example_path
    >>> spec = load_spec(example_path("ugv"))
    >>> spec.name, spec.system.sensors[0], spec.max_attacked
    ('ugv', 'position', 1)
    """
    path = Path(path)
    source = str(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise SpecError(f"{source}: no such file") from None
    except IsADirectoryError:
        raise SpecError(f"{source}: is a directory, expected a spec file") from None
    except OSError as exc:
        raise SpecError(f"{source}: cannot read: {exc.strerror or exc}") from None
    digest = hashlib.sha256(raw).hexdigest()
    suffix = path.suffix.lower()
    if suffix == ".toml":
        try:
            data = tomllib.loads(raw.decode("utf-8"))
        except UnicodeDecodeError:
            raise SpecError(f"{source}: not a UTF-8 text file") from None
        except tomllib.TOMLDecodeError as exc:
            raise SpecError(f"{source}: invalid TOML: {exc}") from None
    elif suffix == ".json":
        try:
            data = json.loads(raw.decode("utf-8"))
        except UnicodeDecodeError:
            raise SpecError(f"{source}: not a UTF-8 text file") from None
        except json.JSONDecodeError as exc:
            raise SpecError(f"{source}: invalid JSON: {exc}") from None
        if not isinstance(data, dict):
            raise SpecError(f"{source}: expected a JSON object at the top level")
    elif suffix in (".npz", ".mat"):
        arrays = _read_arrays(path, source)
        if max_attacked is None:
            raise SpecError(
                f"{source}: a {suffix} file holds only the plant; give the number of attacked "
                f"sensors with --max-attacked (max_attacked=...)"
            )
        system = {k: arrays[k] for k in _SYSTEM_KEYS if k in arrays}
        for key in ("A", "C"):
            if key not in system:
                raise _err(source, key, "missing (required variable)")
        data = {"system": system}
        stem = re.sub(r"[^A-Za-z0-9._-]", "-", path.stem) or "system"
        return spec_from_dict(data, source=source, max_attacked=max_attacked, horizon=horizon,
                              sha256=digest, default_name=stem)
    else:
        raise SpecError(
            f"{source}: unknown file type {suffix or '(none)'!r}; expected .toml, .json, .npz "
            f"or .mat"
        )
    stem = re.sub(r"[^A-Za-z0-9._-]", "-", path.stem) or "spec"
    return spec_from_dict(data, source=source, max_attacked=max_attacked, horizon=horizon,
                          sha256=digest, default_name=stem)
