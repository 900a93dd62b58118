"""JSON Schemas of the spec file and of the certificate, built from the code that reads and
writes them.

``spec_schema()`` describes a spec file (TOML or JSON, as parsed): its tables and their keys
are those the spec reader accepts (the key lists it checks against, and each observer kind's
``keys`` with its ``key_schemas``), so a key added to the reader without a schema makes the
schema fail to build.  ``certificate_schema()`` describes the JSON of ``ssecert analyze`` and
``ssecert certify``: the document, every check's common fields, and the fields scripts rely on
for each check (docs/architecture.md, "JSON").

A schema says what a document looks like; what it cannot say (finite numbers, matrix shapes
that agree with each other, poles in conjugate pairs, sensors below p, which keys one attack
needs) ssecert checks when it reads the spec, naming the key.

    ssecert schema spec > spec.schema.json

Examples
--------
>>> import jsonschema
>>> from ssecert.schemas import spec_schema
>>> jsonschema.validate({"system": {"A": [[1.0]], "C": [[1.0]]}}, spec_schema())
"""

from __future__ import annotations

import copy
from typing import Any

__all__ = ["certificate_schema", "spec_schema", "SCHEMAS"]

DRAFT = "https://json-schema.org/draft/2020-12/schema"

_NUMBER: dict[str, Any] = {"type": "number"}
# a float of the certificate: a number, or "Infinity", "-Infinity", "NaN" (strict JSON)
_REAL: dict[str, Any] = {"oneOf": [{"type": "number"}, {"enum": ["Infinity", "-Infinity", "NaN"]}]}
_INDEX_LIST: dict[str, Any] = {"type": "array", "items": {"type": "integer", "minimum": 0}}

# the spec's top-level keys and their schemas; the system's, the attack's and a scenario's keys
# (each list is checked against the one the reader uses)
#: one bound >= 0, or a list of them (one per sensor, or per entry of the process noise)
_BOUNDS: dict[str, Any] = {
    "oneOf": [
        {"type": "number", "minimum": 0},
        {"type": "array", "items": {"type": "number", "minimum": 0}, "minItems": 1},
    ]
}
_SCENARIO: dict[str, dict[str, Any]] = {
    "name": {"type": "string", "minLength": 1},
    "attack": {"enum": None},  # ATTACK_KINDS, filled in
    "sensors": {
        "type": "array",
        "items": {"oneOf": [{"type": "integer", "minimum": 0}, {"type": "string"}]},
        "minItems": 1,
        "description": "attacked sensors: 0-based indices or the sensors' names",
    },
    "count": {"type": "integer", "minimum": 1, "description": "a random support of this size"},
    "magnitude": {
        "oneOf": [
            {"type": "number", "minimum": 0},
            {
                "type": "array",
                "items": {"type": "number", "minimum": 0},
                "minItems": 2,
                "maxItems": 2,
            },
        ],
        "description": "the range [low, high] of |a_i| (one number: both)",
    },
    "period": {"type": "integer", "minimum": 1},
    "noise": {
        **_BOUNDS,
        "description": "bound of the measurement noise on every sample, one or one per sensor "
        "(default: the [noise] section's, else 0)",
    },
    "process": {
        **_BOUNDS,
        "description": "bound of each entry of the process noise w on every step, one or one "
        "per entry (it enters the state through [noise]'s input, the identity without one; "
        "default: the [noise] section's, else none)",
    },
    "distribution": {
        "enum": ["uniform", "gaussian"],
        "description": "how the noise is drawn within its bounds (default: the [noise] "
        "section's, else uniform)",
    },
    "truncation": {
        "type": "number",
        "exclusiveMinimum": 0,
        "description": 'with distribution = "gaussian": the bounds in standard deviations',
    },
    "steps": {"type": "integer", "minimum": 1},
    "runs": {"type": "integer", "minimum": 1},
    "seed": {"type": "integer", "minimum": 0},
}


def _keys(table: dict[str, Any], keys: tuple[str, ...], where: str) -> dict[str, Any]:
    """The schemas of ``keys``, which must be exactly those of ``table``."""
    if set(keys) != set(table):
        missing = sorted(set(keys) - set(table))
        extra = sorted(set(table) - set(keys))
        raise RuntimeError(
            f"the schema of {where} is out of date: missing {missing}, extra {extra}"
        )
    return {key: table[key] for key in keys}


def _observer_schemas() -> list[dict[str, Any]]:
    """One schema per registered observer kind, told apart by ``kind``."""
    from .observers import get_kind, observer_kinds

    out = []
    for name in observer_kinds():
        kind = get_kind(name)
        if kind.key_schemas is None:  # a kind registered without schemas: its kind alone
            out.append({"type": "object", "properties": {"kind": {"const": name}},
                        "required": ["kind"]})  # fmt: skip
            continue
        others = tuple(k for k in kind.keys if k != "kind")
        properties = {"kind": {"const": name}, **_keys(dict(kind.key_schemas), others, name)}
        schema: dict[str, Any] = {
            "type": "object",
            "title": f"observer kind {name}",
            "properties": properties,
            "required": ["kind", *kind.required_keys],
            "additionalProperties": False,
        }
        out.append(schema)
    return out


def spec_schema() -> dict[str, Any]:
    """The JSON Schema of a spec file (the parsed TOML or JSON document)."""
    from .noise import DISTRIBUTIONS, NORMS
    from .observers.base import MATRIX_SCHEMA
    from .spec import ATTACK_KINDS, MAX_HORIZON, MAX_NAME_LENGTH, NAME_PATTERN, TABLE_KEYS

    scenario = copy.deepcopy(_SCENARIO)
    scenario["attack"] = {"enum": list(ATTACK_KINDS)}
    scenario_schema = {
        "type": "object",
        "properties": _keys(scenario, TABLE_KEYS["scenario"], "a scenario"),
        "required": ["name", "attack"],
        "additionalProperties": False,
        "allOf": [
            {
                "if": {"properties": {"attack": {"enum": ["switching", "sinusoidal"]}}},
                "then": {"required": ["period"]},
                "else": {"not": {"required": ["period"]}},
            },
            {
                "if": {"properties": {"attack": {"enum": ["none", "stealthy"]}}},
                "then": {"not": {"anyOf": [{"required": ["sensors"]}, {"required": ["count"]}]}},
            },
        ],
    }
    system = {
        "A": {**MATRIX_SCHEMA, "description": "n x n state matrix"},
        "C": {**MATRIX_SCHEMA, "description": "p x n output matrix, a row per sensor"},
        "sensors": {
            "type": "array",
            "items": {"type": "string", "minLength": 1, "maxLength": MAX_NAME_LENGTH},
            "uniqueItems": True,
            "description": "unique sensor names (default y1 ... yp)",
        },
    }
    attack = {
        "max_attacked": {"type": "integer", "minimum": 0, "description": "s"},
        "horizon": {"type": "integer", "minimum": 1, "maximum": MAX_HORIZON,
                    "description": "tau (default n)"},
    }  # fmt: skip
    noise = {
        "measurement": {
            **_BOUNDS,
            "description": "each sensor's noise bound (one number: every sensor's)",
        },
        "norm": {"enum": list(NORMS), "description": '"inf" (every sample, default) or "2" '
                 "(the window's samples of the sensor together)"},
        "process": {
            **_BOUNDS,
            "description": "process noise: x(k+1) = A x(k) + G w(k), each entry of w within "
            "its bound on every step (one number: every entry's)",
        },
        "input": {**MATRIX_SCHEMA, "description": "G, n x m: how w enters the state "
                  "(default the identity; needs process)"},
        "distribution": {"enum": list(DISTRIBUTIONS), "description": "how simulations draw "
                         "the noise within its bounds: uniform (default) or gaussian, with "
                         "standard deviation bound / truncation, truncated at the bound"},
        "truncation": {"type": "number", "exclusiveMinimum": 0,
                       "description": 'with distribution = "gaussian": the bounds in standard '
                       "deviations (default 3)"},
    }  # fmt: skip
    top = {
        "name": {"type": "string", "pattern": NAME_PATTERN, "maxLength": MAX_NAME_LENGTH,
                 "description": "names the report files (default: the file's name)"},
        "system": {
            "type": "object",
            "properties": _keys(system, TABLE_KEYS["system"], "[system]"),
            "required": ["A", "C"],
            "additionalProperties": False,
        },
        "attack": {
            "type": "object",
            "properties": _keys(attack, TABLE_KEYS["attack"], "[attack]"),
            "additionalProperties": False,
        },
        "noise": {
            "type": "object",
            "properties": _keys(noise, TABLE_KEYS["noise"], "[noise]"),
            "anyOf": [{"required": ["measurement"]}, {"required": ["process"]}],
            "dependentRequired": {"input": ["process"]},
            "additionalProperties": False,
        },
        "observer": {"oneOf": _observer_schemas()},
        "scenario": {"oneOf": [scenario_schema, {"type": "array", "items": scenario_schema}]},
    }  # fmt: skip
    return {
        "$schema": DRAFT,
        "$id": "https://ssecert.invalid/schemas/spec.schema.json",
        "title": "ssecert spec file",
        "description": "A plant x(k+1) = A x(k), y(k) = C x(k) + a(k), the number s of "
        "sensors an attacker may control, an optional observer and simulation scenarios.",
        "type": "object",
        "properties": _keys(top, TABLE_KEYS[""], "the spec"),
        "required": ["system"],
        "additionalProperties": False,
    }


# the fields scripts rely on, per check (docs/architecture.md, "JSON"); a check may have more
_CHECK_FIELDS: dict[str, dict[str, Any]] = {
    "observability": {"observability_index": {"type": ["integer", "null"]}},
    "sparse_observability": {
        "max_removable": {"type": ["integer", "null"], "minimum": -1},
        "max_removable_is_lower_bound": {"type": "boolean"},
        "max_correctable": {"type": ["integer", "null"], "minimum": -1},
        "breaking_set": {"oneOf": [_INDEX_LIST, {"type": "null"}]},
    },
    "irrepresentable": {
        "worst_support": {"oneOf": [_INDEX_LIST, {"type": "null"}]},
        "horizon": {"type": "integer", "minimum": 1},
        "mode": {"type": ["string", "null"]},
    },
    "observer_gain": {
        "L": {"type": ["array", "null"], "description": "null when no gain could be computed"},
        "spectral_radius": {"oneOf": [_REAL, {"type": "null"}]},
    },
    "decoder_error_bound": {
        "bound": {**_REAL, "description": "certified bound of ||x_hat - x||_2 (Infinity: none)"},
        "lower_bound": {**_REAL, "description": "no decoder guarantees an error below it"},
        "worst_kept_sensors": _INDEX_LIST,
        "hardened_bound": _REAL,
        "sigma_min": _REAL,
        "noise": {"type": "object", "required": ["measurement", "norm"]},
        "horizon": {"type": "integer", "minimum": 1},
        "decoder": {"enum": ["l0"]},
    },
    "observer_noise_bound": {
        "ultimate_bound": {
            **_REAL,
            "description": "certified: without attack the error eventually stays within it "
            "(2-norm; Infinity: none)",
        },
        "region_radius": {
            **_REAL,
            "description": "a local bound's: it holds from the initial errors within this "
            "radius (attack estimate 0)",
        },
        "worst_sensor": {
            "type": ["string", "null"],
            "description": "the sensor whose noise bound halved lowers the bound the most "
            "(null: several lower it alike)",
        },
        "hardened_bound": {**_REAL, "description": "the bound with that sensor's noise halved"},
        "noise": {"type": "object", "required": ["measurement", "norm"]},
    },
    "l1_error_bound": {
        "bound": {**_REAL, "description": "certified bound of ||x_hat - x||_2 (Infinity: none)"},
        "lower_bound": {
            **_REAL,
            "description": "the decoder's error on a window built for it (noise within the "
            "bounds, an attack on the others): its worst case is at least this (0: none built)",
        },
        "null_space_constant": {
            **_REAL,
            "description": "the largest max ||O_S e||_1 / "
            "||O_K e||_1 over the sets of s sensors (an upper bound)",
        },
        "null_space_support": _INDEX_LIST,
        "worst_support": _INDEX_LIST,
        "sigma_min": _REAL,
        "inverse_reach": {
            **_REAL,
            "description": "||O_K^+||_(1->2) there: the largest 2-norm "
            "of a column of the pseudo-inverse (an upper bound)",
        },
        "noise_l1": _REAL,
        "noise": {"type": "object", "required": ["measurement", "norm"]},
        "horizon": {"type": "integer", "minimum": 1},
        "decoder": {"enum": ["l1"]},
    },
    "lasso_error_bound": {
        "bound": {
            **_REAL,
            "description": "certified bound of ||x_hat - x||_2 as lambda comes "
            "down to lambda_min (Infinity: none)",
        },
        "lambda": {"oneOf": [_REAL, {"type": "null"}]},
        "lambda_min": {**_REAL, "description": "every weight above it is certified"},
        "lower_bound": {
            **_REAL,
            "description": "an error the decoder reaches on an explicit "
            "attack and noise (as lambda comes down to lambda_min)",
        },
        "noise_term": {**_REAL, "description": "the bound is noise_term + bias_per_lambda lambda"},
        "bias_per_lambda": _REAL,
        "irrepresentable_constant": _REAL,
        "irrepresentable_support": _INDEX_LIST,
        "lambda_support": _INDEX_LIST,
        "worst_support": _INDEX_LIST,
        "sigma_min": _REAL,
        "noise": {"type": "object", "required": ["measurement", "norm"]},
        "horizon": {"type": "integer", "minimum": 1},
        "decoder": {"enum": ["lasso"]},
    },
}
_REQUIRED_FIELDS: dict[str, list[str]] = {
    "observability": ["observability_index"],
    "sparse_observability": [
        "max_removable", "max_removable_is_lower_bound", "max_correctable", "breaking_set",
    ],
    "irrepresentable": ["horizon"],
    "observer_gain": ["L"],
    "decoder_error_bound": ["bound", "lower_bound", "noise", "horizon", "decoder"],
    "l1_error_bound": ["bound", "null_space_constant", "noise", "horizon", "decoder"],
    "lasso_error_bound": ["bound", "lambda_min", "noise_term", "bias_per_lambda", "noise",
                          "horizon", "decoder"],
}  # fmt: skip


def _check_schema(check_id: str | None) -> dict[str, Any]:
    common = {
        "verdict": {"enum": ["holds", "fails", "inconclusive"]},
        "title": {"type": "string"},
        "summary": {"type": "string"},
        "required": {"type": "boolean", "description": "counts towards the exit status"},
        "applies": {"type": "boolean"},
        "value": {
            "type": ["number", "string", "null"],
            "description": 'a number, "Infinity" or a word',
        },
        "value_name": {"type": ["string", "null"]},
        "margin": {"oneOf": [_REAL, {"type": "null"}]},
        "margin_name": {"type": ["string", "null"]},
        "method": {"type": ["string", "null"]},
        "witness": {"type": ["object", "null"]},
        "evidence": {"type": "object"},
        "tolerances": {"type": ["object", "null"]},
    }
    fields = _CHECK_FIELDS.get(check_id or "", {})
    return {
        "type": "object",
        "properties": {**common, **fields},
        "required": ["verdict", "title", "summary", "required", "applies", "evidence",
                     *_REQUIRED_FIELDS.get(check_id or "", [])],
    }  # fmt: skip


def certificate_schema() -> dict[str, Any]:
    """The JSON Schema of the certificate of ``ssecert analyze`` and ``ssecert certify``."""
    checks = {name: _check_schema(name) for name in _CHECK_FIELDS}
    return {
        "$schema": DRAFT,
        "$id": "https://ssecert.invalid/schemas/certificate.schema.json",
        "title": "ssecert certificate",
        "description": "Every check's verdict with its evidence; the top-level verdict follows "
        "the exit status (fails if a required check fails, else inconclusive if one is, else "
        "holds).",
        "type": "object",
        "properties": {
            "ssecert_version": {"type": "string"},
            "system": {
                "type": "object",
                "properties": {
                    "name": {"type": "string"},
                    "n": {"type": "integer", "minimum": 1},
                    "p": {"type": "integer", "minimum": 1},
                    "sensors": {"type": "array", "items": {"type": "string"}},
                },
                "required": ["name", "n", "p", "sensors"],
            },
            "verdict": {"enum": ["holds", "fails", "inconclusive"]},
            "checks": {
                "type": "object",
                "properties": checks,
                "required": ["observability", "sparse_observability"],
                "propertyNames": {"pattern": "^[a-z][a-z0-9_]*$"},
                "additionalProperties": _check_schema(None),
            },
            "meta": {"type": "object"},
            # ``ssecert certify`` adds these
            "spec": {"$ref": "https://ssecert.invalid/schemas/spec.schema.json"},
            "simulations": {"type": "object"},
            "reproduce": {"type": "string"},
            "seed": {"type": ["integer", "null"]},
            "notes": {"type": "array", "items": {"type": "string"}},
        },
        "required": ["ssecert_version", "system", "verdict", "checks"],
        "$defs": {"spec": spec_schema()},
    }


#: the schemas by the name ``ssecert schema NAME`` takes
SCHEMAS = {"spec": spec_schema, "certificate": certificate_schema}
