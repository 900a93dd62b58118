"""Reading a spec's ``[[scenario]]`` tables: the attacks simulated and how.

Each table names its attack (one of ``ATTACK_KINDS``), the sensors it takes
(a list, a count drawn at random, or none), its magnitude range, period and
the run settings; ``SCENARIO_DEFAULTS`` fills in what a table leaves out.
``ssecert.spec`` reads the scenarios with ``read_scenarios`` and re-exports
the constants.
"""

from __future__ import annotations

import numbers
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..base.validation import (
    as_choice,
    as_float_option,
    as_index_list,
    as_real_matrix,
    describe,
)
from ..noise import DISTRIBUTIONS
from .table import (
    check_keys,
    check_name,
    convert,
    require,
    spec_error,
    spec_int,
    suggest,
)

ATTACK_KINDS = ("none", "constant", "switching", "sinusoidal", "random", "stealthy")
SCENARIO_DEFAULTS: dict[str, Any] = {
    "magnitude": (4.0, 5.0),
    "noise": 0.0,
    "steps": 300,
    "runs": 50,
    "seed": 0,
}
_SCENARIO_KEYS = (
    "name",
    "attack",
    "sensors",
    "count",
    "magnitude",
    "period",
    "noise",
    "process",
    "distribution",
    "truncation",
    "steps",
    "runs",
    "seed",
)


def read_scenarios(
    source: str,
    raw: Any,
    p: int,
    names: tuple[str, ...] = (),
    noise: Sequence[float] | None = None,
    *,
    model: Any = None,
    n: int | None = None,
    process_input: Any = None,
) -> tuple[dict[str, Any], ...]:
    """The ``[[scenario]]`` tables (one table is taken as a list of one), names unique.

    A scenario's ``sensors`` are 0-based indices or the sensors' ``names`` (the system's),
    kept as indices.  Its ``noise`` is one bound or one per sensor on every sample; without
    one, ``noise`` (the spec's ``[noise]`` as a bound on each sample, one per sensor) when given,
    else 0.  Its ``process`` (one bound or one per entry of w on every step, entering the state
    through the ``[noise]`` section's input, the identity without one: kept beside it as
    ``process_input``), ``distribution`` and ``truncation`` default to those of ``model`` (the
    spec's ``MeasurementNoise``) when given; ``n`` is the number of states and
    ``process_input`` the section's input matrix, where it has one."""
    if isinstance(raw, Mapping):
        raw = [raw]
    if not isinstance(raw, list):
        raise spec_error(
            source,
            "scenario",
            f"expected a list of tables ([[scenario]]), got {describe(raw)}",
        )
    scenarios: list[dict[str, Any]] = []
    seen: set[str] = set()
    for index, table in enumerate(raw):
        scenario = _scenario(source, f"scenario[{index}]", table, p, names)
        if noise is not None and isinstance(table, Mapping) and "noise" not in table:
            scenario["noise"] = [float(v) for v in noise]
        _noise_defaults(source, f"scenario[{index}]", scenario, model, n, process_input)
        if scenario["name"] in seen:
            raise spec_error(
                source, f"scenario[{index}].name", f"duplicate scenario name {scenario['name']!r}"
            )
        seen.add(scenario["name"])
        scenarios.append(scenario)
    return tuple(scenarios)


def _noise_defaults(
    source: str,
    prefix: str,
    scenario: dict[str, Any],
    model: Any,
    n: int | None,
    process_input: Any = None,
) -> None:
    """The scenario's process noise (with its input matrix), distribution and truncation:
    its own, else the spec's ``[noise]`` (``model``); none of them where neither has one
    (uniform draws, no process noise)."""
    process = getattr(model, "process", None)
    if "process" in scenario or process is not None:
        if process is not None:
            G = process.input
        else:  # the section's input even where its own process noise is zero (none)
            G = np.eye(n or 0) if process_input is None else np.asarray(process_input, float)
        m = G.shape[1]
        bounds: Any = scenario.get("process")
        if bounds is None and process is not None:
            bounds = process.omega.tolist()
        if isinstance(bounds, list) and len(bounds) != m:
            what = (
                "one per state"
                if process_input is None and process is None
                else "the columns of [noise] input"
            )
            raise spec_error(
                source,
                f"{prefix}.process",
                f"expected one bound or one per entry of w ({m}: {what}), got a list of "
                f"{len(bounds)}",
            )
        values = bounds if isinstance(bounds, list) else [bounds] * m
        scenario["process"] = [float(v) for v in values]
        scenario["process_input"] = G.tolist()
    distribution = scenario.get("distribution", getattr(model, "distribution", "uniform"))
    if "truncation" in scenario and distribution != "gaussian":
        raise spec_error(
            source, f"{prefix}.truncation", 'truncation applies to distribution = "gaussian" only'
        )
    if distribution == "gaussian":
        scenario["distribution"] = "gaussian"
        scenario.setdefault("truncation", getattr(model, "truncation", 3.0))
    elif getattr(model, "distribution", "uniform") == "gaussian":
        scenario["distribution"] = "uniform"  # its own, against the section's (kept written)
    else:
        scenario.pop("distribution", None)


def _scenario(
    source: str, prefix: str, table: Any, p: int, names: tuple[str, ...] = ()
) -> dict[str, Any]:
    """One ``[[scenario]]`` table, checked against its attack, with defaults filled in."""
    check_keys(source, prefix, table, _SCENARIO_KEYS)
    name = check_name(
        source, f"{prefix}.name", require(source, table, "name", prefix), "a scenario name"
    )
    attack = convert(
        source,
        f"{prefix}.attack",
        as_choice,
        require(source, table, "attack", prefix),
        "attack",
        ATTACK_KINDS,
    )
    out: dict[str, Any] = {"name": name, "attack": attack}
    out.update(_attack_support(source, prefix, table, attack, p, names))
    if attack in ("switching", "sinusoidal"):
        out["period"] = convert(
            source,
            f"{prefix}.period",
            spec_int,
            require(source, table, "period", prefix),
            "period",
            min_value=1,
        )
    elif "period" in table:
        raise spec_error(
            source,
            f"{prefix}.period",
            f"only used by switching and sinusoidal attacks, not {attack!r}",
        )
    out["magnitude"] = _attack_magnitude(source, prefix, table, attack)
    out.update(_run_settings(source, prefix, table, p))
    return out


def _attack_support(
    source: str, prefix: str, table: Any, attack: str, p: int, names: tuple[str, ...] = ()
) -> dict[str, Any]:
    """Which sensors the attack takes: ``{"sensors": [...]}``, ``{"count": k}`` or nothing.

    No attack and the stealthy one (whose sensors come from the witness)
    take neither; switching and random attacks draw supports of a given
    count; the others take exactly one of sensors or count.
    """
    if attack in ("none", "stealthy"):
        for key in ("sensors", "count"):
            if key in table:
                why = (
                    " (the sensors come from the sparse-observability witness)"
                    if attack == "stealthy"
                    else ""
                )
                raise spec_error(source, f"{prefix}.{key}", f"not used by attack = {attack!r}{why}")
        return {}
    has_sensors, has_count = "sensors" in table, "count" in table
    if attack in ("switching", "random"):
        if has_sensors:
            raise spec_error(
                source,
                f"{prefix}.sensors",
                f"attack = {attack!r} draws its supports at random; give count instead",
            )
        return {"count": _attack_count(source, prefix, require(source, table, "count", prefix), p)}
    if has_sensors == has_count:
        raise spec_error(
            source,
            f"{prefix}.sensors",
            f"attack = {attack!r} needs exactly one of sensors (0-based indices) or "
            f"count (a random support of that size)",
        )
    if not has_sensors:
        return {"count": _attack_count(source, prefix, table["count"], p)}
    sensors = convert(
        source,
        f"{prefix}.sensors",
        as_index_list,
        _by_name(source, f"{prefix}.sensors", table["sensors"], names),
        "sensors",
        upper=p,
    )
    if not sensors:
        raise spec_error(source, f"{prefix}.sensors", "expected at least one sensor")
    return {"sensors": list(sensors)}


def _by_name(source: str, key: str, value: Any, names: tuple[str, ...]) -> Any:
    """The sensors of a list as indices: each a 0-based index or a sensor's name."""
    if not isinstance(value, list) or not any(isinstance(item, str) for item in value):
        return value
    out = []
    for i, item in enumerate(value):
        if isinstance(item, str):
            if item not in names:
                hint = suggest(item, names)
                raise spec_error(
                    source,
                    f"{key}[{i}]",
                    f"no sensor is named {item!r}{hint}; the sensors are "
                    f"{', '.join(names[:12])}{', ...' if len(names) > 12 else ''}",
                )
            item = names.index(item)
        out.append(item)
    return out


def _attack_count(source: str, prefix: str, value: Any, p: int) -> int:
    """The number of attacked sensors a scenario draws, from 1 to p."""
    return convert(source, f"{prefix}.count", spec_int, value, "count", min_value=1, max_value=p)


def _attack_magnitude(source: str, prefix: str, table: Any, attack: str) -> tuple[float, float]:
    """The attack's [low, high] magnitude range (one number is both), or the default."""
    if "magnitude" not in table:
        return SCENARIO_DEFAULTS["magnitude"]
    if attack == "none":
        raise spec_error(source, f"{prefix}.magnitude", "not used by attack = 'none'")
    mag = table["magnitude"]
    if isinstance(mag, numbers.Real) and not isinstance(mag, bool):
        mag = [mag, mag]
    arr = convert(
        source, f"{prefix}.magnitude", as_real_matrix, mag, "magnitude", shape=(2,), ndim=1
    )
    if arr[0] < 0 or arr[0] > arr[1]:
        raise spec_error(
            source,
            f"{prefix}.magnitude",
            f"expected [low, high] with 0 <= low <= high, got {arr.tolist()}",
        )
    return (float(arr[0]), float(arr[1]))


def _run_settings(source: str, prefix: str, table: Any, p: int) -> dict[str, Any]:
    """The scenario's noise, steps, runs and seed, with their defaults."""
    raw = table.get("noise", SCENARIO_DEFAULTS["noise"])
    if isinstance(raw, (list, tuple)):
        if len(raw) != p:
            raise spec_error(
                source,
                f"{prefix}.noise",
                f"expected one bound or one per sensor ({p}), got a list of {len(raw)}",
            )
        values = [
            convert(source, f"{prefix}.noise[{i}]", as_float_option, v, "noise", min_value=0.0)
            for i, v in enumerate(raw)
        ]
        noise: float | list[float] = values
    else:
        noise = convert(source, f"{prefix}.noise", as_float_option, raw, "noise", min_value=0.0)
    out: dict[str, Any] = {"noise": noise}
    if "process" in table:
        raw = table["process"]
        items = raw if isinstance(raw, (list, tuple)) else [raw]
        values = [
            convert(source, f"{prefix}.process", as_float_option, v, "process", min_value=0.0)
            for v in items
        ]
        out["process"] = values if isinstance(raw, (list, tuple)) else values[0]
    if "distribution" in table:
        out["distribution"] = convert(
            source,
            f"{prefix}.distribution",
            as_choice,
            table["distribution"],
            "distribution",
            DISTRIBUTIONS,
        )
    if "truncation" in table:
        out["truncation"] = convert(
            source,
            f"{prefix}.truncation",
            as_float_option,
            table["truncation"],
            "truncation",
            min_value=0.0,
            min_inclusive=False,
        )
    for key in ("steps", "runs"):
        out[key] = convert(
            source,
            f"{prefix}.{key}",
            spec_int,
            table.get(key, SCENARIO_DEFAULTS[key]),
            key,
            min_value=1,
        )
    out["seed"] = convert(
        source,
        f"{prefix}.seed",
        spec_int,
        table.get("seed", SCENARIO_DEFAULTS["seed"]),
        "seed",
        min_value=0,
    )
    return out
