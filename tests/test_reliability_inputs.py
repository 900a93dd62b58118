"""Reliability matrix of the inputs: what every entry point does with bad data.

Entry points: ``System(...)``, ``spec_from_dict``, ``load_spec``, the
analyses' argument checks (``sparse_observability``, ``irrepresentable``,
``observability``) and the command line (``ssecert analyze``, ``certify``,
``simulate``).  Each row is one kind of bad input; the tests pin what it gets:

- Python API: ``TypeError`` for the wrong kind, ``ValueError`` for a wrong
  value, ``SpecError`` (a ``ValueError``) for anything in a spec, each with a
  one-line message naming the argument or the file and the key;
- command line: exit status 2 and one line on stderr, no traceback, and no
  file written; 3 for inconclusive; 4 only for bugs.

Also here: output paths, interrupted runs (no partial report, no temporary
file), warnings (none reach the terminal), how reports name the spec file,
and that regenerating a report changes only its date and measured timings.
docs/site/guide/refusals.md, "What ssecert refuses, and why", is this file as a table.
"""

from __future__ import annotations

import errno
import json
import math
import os
import re
import subprocess
import sys
import warnings
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import scipy.io

import ssecert.certify
import ssecert.simulation.engine
from ssecert import (
    SpecError,
    System,
    irrepresentable,
    load_spec,
    observability,
    sparse_observability,
    spec_from_dict,
)
from ssecert.cli import _WarningLog, main
from ssecert.examples import example_path, list_examples
from ssecert.spec import (
    MAX_BINARY_BYTES,
    MAX_HORIZON,
    MAX_MATRIX_DIM,
    MAX_MATRIX_ENTRIES,
    MAX_NAME_LENGTH,
    MAX_TEXT_BYTES,
)

# ---------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------

A2 = [[1.0, 0.1], [0.0, 0.9]]
C3 = [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]
GOOD: dict[str, Any] = {
    "name": "plant",
    "system": {"A": A2, "C": C3, "sensors": ["s0", "s1", "s2"]},
    "attack": {"max_attacked": 1, "horizon": 2},
}
COMMANDS = ["analyze", "certify", "simulate"]


DELETE = object()


def good(**sections: Any) -> dict[str, Any]:
    """A copy of GOOD with keys replaced: ``system__A=value`` (DELETE removes the key)."""
    data = json.loads(json.dumps(GOOD))
    for path, value in sections.items():
        table, _, key = path.rpartition("__")
        target = data[table] if table else data
        if value is DELETE:
            target.pop(key, None)
        else:
            target[key] = value
    return data


def toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return (
            "nan"
            if math.isnan(value)
            else ("inf" if value > 0 else "-inf")
            if math.isinf(value)
            else repr(value)
        )
    if isinstance(value, (int, str)):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(value)


def to_toml(data: dict[str, Any]) -> str:
    """Spec dictionaries as TOML: top-level values, tables, arrays of tables."""
    lines = [
        f"{json.dumps(k)} = {toml_value(v)}"
        for k, v in data.items()
        if not isinstance(v, dict) and k != "scenario"
    ]
    for key, value in data.items():
        if isinstance(value, dict):
            lines.append(f"[{json.dumps(key)}]")
            lines += [f"{json.dumps(k)} = {toml_value(v)}" for k, v in value.items()]
    for table in data.get("scenario", []):
        lines.append("[[scenario]]")
        lines += [f"{json.dumps(k)} = {toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


def write(folder: Path, name: str, content: str | bytes | dict[str, Any]) -> Path:
    path = folder / name
    if isinstance(content, dict):
        content = to_toml(content) if name.endswith(".toml") else json.dumps(content)
    if isinstance(content, str):
        content = content.encode("utf-8")
    path.write_bytes(content)
    return path


def cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    """``ssecert ARGV`` in-process; (status, stdout, stderr)."""
    capsys.readouterr()
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def assert_refused(status: int, out: str, err: str, *fragments: str) -> str:
    """Exit 2 with one line on stderr, no traceback, nothing on stdout."""
    assert status == 2, (status, out, err)
    assert "Traceback" not in err, err
    assert err.startswith("ssecert: error: ") and err.count("\n") == 1, err
    assert out == "", out
    for fragment in fragments:
        assert fragment in err, err
    return err


def refused_everywhere(
    capsys: Any, tmp_path: Path, spec: Path, *fragments: str, extra: tuple[str, ...] = ()
) -> None:
    """analyze, certify and simulate all refuse SPEC, and certify writes nothing."""
    out_dir = tmp_path / "reports-out"
    for command in COMMANDS:
        argv = [command, str(spec), *extra]
        if command == "certify":
            argv += ["--out", str(out_dir)]
        if command == "simulate" and "--horizon" in argv:
            continue  # simulate has no --horizon
        assert_refused(*cli(capsys, *argv), *fragments)
    assert not out_dir.exists()


def spec_error(data: Any, *fragments: str, key: str | None = None, **kwargs: Any) -> str:
    with pytest.raises(SpecError) as info:
        spec_from_dict(data, **kwargs)
    message = str(info.value)
    assert "\n" not in message
    if key is not None:
        assert f"key '{key}'" in message, message
    for fragment in fragments:
        assert fragment in message, message
    return message


def deep_list(levels: int) -> Any:
    value: Any = 1.0
    for _ in range(levels):
        value = [value]
    return value


# ---------------------------------------------------------------------------
# matrices: System(...), spec_from_dict, spec files and the command line
# ---------------------------------------------------------------------------

# id, bad A, exception of System(A, C), fragment of its message, fragment of the
# spec_from_dict message (None: same as System's)
MATRIX_ROWS = [
    ("nan", [[float("nan"), 0.0], [0.0, 1.0]], ValueError, "finite", None),
    ("inf", [[float("inf"), 0.0], [0.0, 1.0]], ValueError, "finite", None),
    ("minus-inf", [[1.0, 0.0], [0.0, -float("inf")]], ValueError, "finite", None),
    ("complex", [[1 + 2j, 0.0], [0.0, 1.0]], TypeError, "complex", None),
    ("complex-array", np.eye(2) * (1 + 1j), TypeError, "complex", None),
    ("ragged", [[1.0, 0.0], [1.0]], ValueError, "ragged", None),
    ("ragged-number-row", [[1.0, 0.0], 1.0], ValueError, "ragged", None),
    ("empty", [], ValueError, "2-D", None),
    ("empty-row", [[]], ValueError, "empty", None),
    ("not-square", [[1.0, 0.0]], ValueError, "square", None),
    ("one-dimensional", [1.0, 0.0], ValueError, "2-D", None),
    ("three-dimensional", [[[1.0, 0.0], [0.0, 1.0]]], ValueError, "nested more than 2 deep", None),
    (
        "nested-too-deep",
        deep_list(5000),
        ValueError,
        "nested more than 2 deep",
        "nested more than 16 levels",
    ),
    ("string", "abc", TypeError, "numeric array", None),
    ("strings", [["1", "0"], ["0", "1"]], TypeError, "real numbers", None),
    ("boolean", True, TypeError, "boolean", None),
    ("booleans", [[True, False], [False, True]], TypeError, "real numbers", None),
    ("none", None, TypeError, "numeric array", None),
    ("none-entry", [[None, 0.0], [0.0, 1.0]], TypeError, "real numbers", None),
    ("dict", {"a": 1}, TypeError, "numeric array", None),
    ("dict-entry", [[{"a": 1}, 0.0], [0.0, 1.0]], TypeError, "real numbers", None),
    ("datetime64", np.zeros((2, 2), dtype="datetime64[s]"), TypeError, "datetime64", None),
    ("timedelta64", np.ones((2, 2), dtype="timedelta64[s]"), TypeError, "timedelta64", None),
    (
        "timedelta64-entries",
        [[np.timedelta64(1, "s"), 0.0], [0.0, 1.0]],
        TypeError,
        "real numbers",
        None,
    ),
    (
        "object-array",
        np.array([[1.0, 0.0], [0.0, 1.0]], dtype=object),
        TypeError,
        "numeric array",
        None,
    ),
    ("huge-integer", [[10**400, 0], [0, 1]], ValueError, "too large for a float64", "64 bits"),
]


@pytest.mark.parametrize("row", MATRIX_ROWS, ids=[r[0] for r in MATRIX_ROWS])
def test_system_refuses_bad_matrices(row):
    name, A, exc, fragment, _ = row
    with pytest.raises(exc, match=re.escape(fragment)) as info:
        System(A, C3)
    assert str(info.value).startswith("A ") and "\n" not in str(info.value)
    if name == "not-square":  # a valid C
        return
    with pytest.raises((TypeError, ValueError)) as info:
        System(A2, A)  # the same value as C: named C
    assert str(info.value).startswith("C ")


@pytest.mark.parametrize("row", MATRIX_ROWS, ids=[r[0] for r in MATRIX_ROWS])
def test_spec_from_dict_refuses_bad_matrices(row):
    _, A, _, fragment, spec_fragment = row
    message = spec_error(good(system__A=A), spec_fragment or fragment)
    assert message.startswith("<dict>: key 'system.A")


# rows a spec file can hold: id, TOML or JSON text of A, fragment
FILE_MATRIX_ROWS = [
    ("nan.toml", "[[nan, 0.0], [0.0, 1.0]]", "finite"),
    ("inf.toml", "[[inf, 0.0], [0.0, 1.0]]", "finite"),
    ("nan.json", "[[NaN, 0.0], [0.0, 1.0]]", "finite"),
    ("overflow.json", "[[1e999, 0.0], [0.0, 1.0]]", "finite"),
    ("ragged.toml", "[[1.0, 0.0], [1.0]]", "ragged"),
    ("empty.json", "[]", "2-D"),
    ("empty-row.toml", "[[]]", "empty"),
    ("not-square.json", "[[1.0, 0.0]]", "square"),
    ("three-d.toml", "[[[1.0, 0.0], [0.0, 1.0]]]", "nested more than 2 deep"),
    ("deep.json", "[" * 40 + "1" + "]" * 40, "nested more than 16 levels"),
    ("deeper-than-parser.json", "[" * 100_000 + "]" * 100_000, "nested too deeply"),
    ("deeper-than-parser.toml", "[" * 100_000 + "]" * 100_000, "nested too deeply"),
    ("strings.json", '[["1", "0"], ["0", "1"]]', "real numbers"),
    ("booleans.toml", "[[true, false], [false, true]]", "real numbers"),
    ("null.json", "null", "numeric array"),
    ("table.toml", "{a = 1}", "numeric array"),
    ("date.toml", "[[1979-05-27, 0.0], [0.0, 1.0]]", "real numbers"),
    ("300-digits.toml", "[[" + "9" * 300 + ", 0], [0, 1]]", "64 bits"),
    ("300-digits.json", "[[" + "9" * 300 + ", 0], [0, 1]]", "64 bits"),
    ("2-to-63.toml", "[[9223372036854775808, 0], [0, 1]]", "64 bits"),
    ("5000-digits.json", "[[" + "9" * 5000 + ", 0], [0, 1]]", "5,000 digits"),
]


def _spec_text(name: str, a_text: str) -> str:
    if name.endswith(".toml"):
        return to_toml(GOOD).replace(toml_value(A2), a_text, 1)
    return json.dumps(GOOD).replace(json.dumps(A2), a_text, 1)


@pytest.mark.parametrize("row", FILE_MATRIX_ROWS, ids=[r[0] for r in FILE_MATRIX_ROWS])
def test_spec_files_with_bad_matrices(tmp_path, capsys, row):
    name, a_text, fragment = row
    path = write(tmp_path, name, _spec_text(name, a_text))
    with pytest.raises(SpecError, match=re.escape(fragment)) as info:
        load_spec(path)
    message = str(info.value)
    assert message.startswith(str(path)) and "\n" not in message
    if "deeper-than-parser" not in name:
        assert "key 'system.A" in message
    assert_refused(*cli(capsys, "analyze", str(path)), fragment)


def test_5000_digit_integer_in_toml_names_the_line(tmp_path, capsys):
    # tomllib stops at Python's 4300-digit limit before it can say which key
    path = write(tmp_path, "big.toml", _spec_text(".toml", "[[" + "9" * 5000 + ", 0], [0, 1]]"))
    with pytest.raises(SpecError, match="line 3: an integer of 5,000 digits"):
        load_spec(path)
    refused_everywhere(capsys, tmp_path, path, "5,000 digits", "64 bits")


@pytest.mark.parametrize("fmt", ["toml", "json"])
def test_integer_beyond_64_bits_names_the_key(tmp_path, capsys, fmt):
    data = good(attack__max_attacked=int("9" * 300))
    path = write(tmp_path, f"s.{fmt}", data)
    with pytest.raises(SpecError) as info:
        load_spec(path)
    assert "key 'attack.max_attacked'" in str(info.value)
    assert "300 digits" in str(info.value) and "64 bits" in str(info.value)
    refused_everywhere(capsys, tmp_path, path, "attack.max_attacked", "64 bits")


def test_c_with_the_wrong_number_of_columns():
    with pytest.raises(ValueError, match="C has the wrong number of columns: expected 2"):
        System(A2, [[1.0, 0.0, 0.0]])
    spec_error(good(system__C=[[1.0, 0.0, 0.0]]), "columns", key="system.C")


# ---------------------------------------------------------------------------
# sensor names
# ---------------------------------------------------------------------------

SENSOR_ROWS = [
    ("duplicate", ["a", "b", "a"], ValueError, "unique"),
    ("integer", [1, 2, 3], TypeError, "non-empty string"),
    ("none-entry", ["a", None, "c"], TypeError, "non-empty string"),
    ("list-entry", ["a", ["b"], "c"], TypeError, "non-empty string"),
    ("empty-name", ["a", "", "c"], TypeError, "non-empty string"),
    ("blank-name", ["a", "  ", "c"], TypeError, "non-empty string"),
    ("too-few", ["a", "b"], ValueError, "wrong length"),
    ("too-many", ["a", "b", "c", "d"], ValueError, "wrong length"),
    ("a-string", "abc", TypeError, "list of names"),
    ("a-dict", {"a": 0}, TypeError, "list of names"),
]


@pytest.mark.parametrize("row", SENSOR_ROWS, ids=[r[0] for r in SENSOR_ROWS])
def test_bad_sensor_names(tmp_path, capsys, row):
    _, sensors, exc, fragment = row
    with pytest.raises(exc, match=fragment):
        System(A2, C3, sensors=sensors)
    spec_error(good(system__sensors=sensors), fragment, key="system.sensors")
    path = write(tmp_path, "names.json", good(system__sensors=sensors))
    refused_everywhere(capsys, tmp_path, path, "system.sensors", fragment)


@pytest.mark.parametrize(
    "sensors, fragment",
    [
        (["a" * (MAX_NAME_LENGTH + 1), "b", "c"], f"the limit is {MAX_NAME_LENGTH}"),
        (["a\nb", "b", "c"], "control character '\\n'"),
        (["\x1b[31mred", "b", "c"], "control character '\\x1b'"),
        (["a\u202eb", "b", "c"], "control character '\\u202e'"),
        (["\ud800", "b", "c"], "lone surrogate"),
    ],
    ids=["too-long", "newline", "terminal-escape", "bidi-override", "lone-surrogate"],
)
def test_sensor_names_that_would_break_the_output(tmp_path, capsys, sensors, fragment):
    message = spec_error(good(system__sensors=sensors), fragment)
    assert "\n" not in message and "\x1b" not in message and "\u202e" not in message
    path = write(tmp_path, "names.json", json.dumps(good(system__sensors=sensors)))
    refused_everywhere(capsys, tmp_path, path, fragment)


def test_names_of_specs_and_scenarios_are_limited_too():
    spec_error(good(name="a" * 200), "the limit is 128", key="name")
    scenario = {"name": "x" * 200, "attack": "none"}
    spec_error(good(scenario=[scenario]), "the limit is 128", key="scenario[0].name")


# ---------------------------------------------------------------------------
# s and the horizon: analyses, System, spec_from_dict, command line
# ---------------------------------------------------------------------------

PLANT = System(A2, C3)

S_ROWS = [
    ("negative", -1, ValueError, ">= 0"),
    ("non-integer", 1.5, TypeError, "integer"),
    ("string", "1", TypeError, "integer"),
    ("boolean", True, TypeError, "integer"),
    ("none", None, TypeError, "integer"),
    ("duration", np.timedelta64(1, "s"), TypeError, "integer"),
]


@pytest.mark.parametrize("row", S_ROWS, ids=[r[0] for r in S_ROWS])
def test_bad_s(row):
    _, s, exc, fragment = row
    with pytest.raises(exc, match=f"max_attacked must be .*{re.escape(fragment)}"):
        sparse_observability(PLANT, s)
    with pytest.raises(exc, match=f"support_size must be .*{re.escape(fragment)}"):
        irrepresentable(PLANT, s)
    spec_error(good(attack__max_attacked=s), fragment, key="attack.max_attacked")
    if s is not None:  # None: no override
        spec_error(GOOD, fragment, key="--max-attacked", max_attacked=s)


HORIZON_ROWS = [
    ("zero", 0, ValueError, ">= 1"),
    ("negative", -3, ValueError, ">= 1"),
    ("non-integer", 1.5, TypeError, "integer"),
    ("string", "2", TypeError, "integer"),
    ("boolean", True, TypeError, "integer"),
]


@pytest.mark.parametrize("row", HORIZON_ROWS, ids=[r[0] for r in HORIZON_ROWS])
def test_bad_horizon(row):
    _, horizon, exc, fragment = row
    for call in (
        lambda: sparse_observability(PLANT, 1, horizon=horizon),
        lambda: irrepresentable(PLANT, 1, horizon=horizon),
        lambda: PLANT.observability_matrix(horizon),
    ):
        with pytest.raises(exc, match=f"horizon must be .*{re.escape(fragment)}"):
            call()
    spec_error(good(attack__horizon=horizon), fragment, key="attack.horizon")
    spec_error(GOOD, fragment, key="--horizon", horizon=horizon)


def test_horizon_beyond_the_limit_in_specs():
    spec_error(good(attack__horizon=MAX_HORIZON + 1), f"<= {MAX_HORIZON:,}", key="attack.horizon")
    assert spec_from_dict(good(attack__horizon=MAX_HORIZON)).horizon == MAX_HORIZON


def test_s_beyond_64_bits_written_as_a_float():
    spec_error(
        good(attack__max_attacked=1e300), "9,223,372,036,854,775,807", key="attack.max_attacked"
    )


@pytest.mark.parametrize(
    "option, value, fragment",
    [
        ("--max-attacked", "-1", ">= 0"),
        ("--max-attacked", "1.5", "expected an integer"),
        ("--max-attacked", "one", "expected an integer"),
        ("--max-attacked", "9" * 30, "64 bits"),
        ("--horizon", "0", ">= 1"),
        ("--horizon", "-2", ">= 1"),
        ("--horizon", "2.5", "expected an integer"),
        ("--horizon", str(MAX_HORIZON + 1), f"<= {MAX_HORIZON:,}"),
        ("--max-sets", "inf", "expected an integer"),
        ("--max-sets", "1e400", "expected an integer"),
    ],
)
@pytest.mark.parametrize("command", ["analyze", "certify"])
def test_bad_numbers_on_the_command_line(tmp_path, capsys, command, option, value, fragment):
    argv = [command, "ugv", option, value]
    if command == "certify":
        argv += ["--out", str(tmp_path / "out"), "--no-sim"]
    assert_refused(*cli(capsys, *argv), option, fragment)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "option, value", [("--runs", "0"), ("--steps", "-1"), ("--seed", "-1"), ("--runs", "9" * 30)]
)
def test_bad_numbers_for_simulate(capsys, option, value):
    assert_refused(*cli(capsys, "simulate", "ugv", option, value), option)


@pytest.mark.parametrize("value", ["-1", str(2**64)])
def test_design_refuses_a_seed_certify_could_not_replay(tmp_path, capsys, value):
    # (the search would run to its end first, then fail inside the certification)
    out = tmp_path / "out"
    assert_refused(*cli(capsys, "design", "ugv", "--seed", value, "--out", str(out)), "--seed")
    assert not out.exists()


def test_analyses_refuse_what_is_not_a_system():
    for call in (sparse_observability, irrepresentable):
        with pytest.raises(TypeError, match="system must be a System"):
            call([[1.0]], 1)


def test_observability_refuses_what_is_not_a_system():
    from ssecert import observability_index

    for call in (observability, observability_index):
        with pytest.raises(TypeError, match="system must be a System"):
            call([[1.0]])


@pytest.mark.parametrize("seed, error", [(-1, ValueError), ("a", TypeError), (1.5, TypeError)])
def test_sparse_observability_names_a_bad_seed(seed, error):
    with pytest.raises(error, match="seed"):
        sparse_observability(System([[1.0]], [[1.0]]), 0, seed=seed)


def test_analyses_name_bad_tolerances():
    with pytest.raises(TypeError, match="tolerances must be a Tolerances"):
        sparse_observability(System([[1.0]], [[1.0]]), 0, tolerances="x")
    with pytest.raises(TypeError, match="tolerances must be a Tolerances"):
        observability(System([[1.0]], [[1.0]]), tolerances="x")


# ---------------------------------------------------------------------------
# spec structure: unknown keys and typos, wrong kinds of sections
# ---------------------------------------------------------------------------

TYPO_ROWS = [
    ({"sytem": GOOD["system"]}, "sytem", "system"),
    ({"Name": "plant"}, "Name", "name"),
    ({"system__a": A2}, "system.a", "A"),
    ({"system__sensor": ["a", "b", "c"]}, "system.sensor", "sensors"),
    ({"attack__max_attack": 1}, "attack.max_attack", "max_attacked"),
    ({"attack__horizn": 2}, "attack.horizn", "horizon"),
    ({"observer": {"kind": "dsso", "stpe": 0.5, "threshold": 0.1}}, "observer.stpe", "step"),
    ({"scenario": [{"name": "x", "attack": "none", "seeds": 1}]}, "scenario[0].seeds", "seed"),
]


@pytest.mark.parametrize("row", TYPO_ROWS, ids=[r[1] for r in TYPO_ROWS])
@pytest.mark.parametrize("fmt", ["toml", "json"])
def test_unknown_keys_suggest_the_right_one(tmp_path, capsys, row, fmt):
    changes, key, right = row
    data = good()
    for path, value in changes.items():
        table, _, name = path.rpartition("__")
        (data[table] if table else data)[name] = value
    hint = f"did you mean '{right}'?"
    spec_error(data, "unknown key", hint, key=key)
    path = write(tmp_path, f"typo.{fmt}", data)
    refused_everywhere(capsys, tmp_path, path, f"'{key}'", hint)


@pytest.mark.parametrize(
    "data, key, fragment",
    [
        (good(system=[1, 2]), "system", "expected a table"),
        (good(attack=3), "attack", "expected a table"),
        (good(observer=["dsso"]), "observer", "expected a table"),
        (good(scenario="none"), "scenario", "list of tables"),
        (good(scenario=[["x"]]), "scenario[0]", "expected a table"),
        (good(name=None), "name", "missing"),
        (good(name=["plant"]), "name", "a list"),
        (good(system__A=DELETE), "system.A", "missing"),
    ],
    ids=[
        "system-list",
        "attack-number",
        "observer-list",
        "scenario-string",
        "scenario-entry-list",
        "name-none",
        "name-list",
        "missing-A",
    ],
)
def test_sections_of_the_wrong_kind(data, key, fragment):
    spec_error(data, fragment, key=key)


def test_duplicate_keys_in_json_are_refused(tmp_path, capsys):
    text = json.dumps(GOOD).replace('"max_attacked": 1', '"max_attacked": 0, "max_attacked": 5')
    path = write(tmp_path, "dup.json", text)
    with pytest.raises(SpecError, match="the key 'max_attacked' appears twice"):
        load_spec(path)
    refused_everywhere(capsys, tmp_path, path, "appears twice")


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("[1, 2]", "a list of length 2"),
        ('"spec"', "the string 'spec'"),
        ("3", "int 3"),
        ("null", "nothing (None)"),
    ],
)
def test_json_whose_top_level_is_not_an_object(tmp_path, capsys, text, fragment):
    path = write(tmp_path, "top.json", text)
    with pytest.raises(SpecError, match="expected a JSON object at the top level"):
        load_spec(path)
    refused_everywhere(capsys, tmp_path, path, "JSON object", fragment)


def test_spec_from_dict_refuses_what_is_not_a_mapping():
    for value in ([GOOD], "spec", None, 3):
        spec_error(value, "expected a table")


def test_self_containing_lists_do_not_hang():
    data = good()
    loop: list[Any] = []
    loop.append(loop)
    data["system"]["A"] = loop
    spec_error(data, "nested more than 16 levels")


# ---------------------------------------------------------------------------
# the spec file itself
# ---------------------------------------------------------------------------


def test_a_spec_that_is_a_directory(tmp_path, capsys):
    folder = tmp_path / "spec.toml"
    folder.mkdir()
    with pytest.raises(SpecError, match="is a directory"):
        load_spec(folder)
    refused_everywhere(capsys, tmp_path, folder, "is a directory")


def test_a_missing_spec_file(tmp_path, capsys):
    path = tmp_path / "nope.toml"
    with pytest.raises(SpecError, match="no such file"):
        load_spec(path)
    refused_everywhere(capsys, tmp_path, path, str(path), "no such file")
    assert_refused(*cli(capsys, "analyze", "no-such-example"), "no packaged example")


@pytest.mark.parametrize(
    "name, content",
    [
        ("empty.toml", b""),
        ("empty.json", b""),
        ("blank.toml", b"  \n\n"),
        ("empty.npz", b""),
        ("empty.mat", b""),
    ],
)
def test_an_empty_file(tmp_path, capsys, name, content):
    path = write(tmp_path, name, content)
    with pytest.raises(SpecError, match="the file is empty"):
        load_spec(path, max_attacked=1)
    refused_everywhere(capsys, tmp_path, path, "empty", extra=("--max-attacked", "1"))


@pytest.mark.parametrize("name", ["binary.toml", "binary.json"])
def test_a_binary_file_named_as_text(tmp_path, capsys, name):
    path = write(tmp_path, name, bytes(range(256)) * 8)
    with pytest.raises(SpecError, match="NUL bytes"):
        load_spec(path)
    refused_everywhere(capsys, tmp_path, path, "not a", "text file")


@pytest.mark.parametrize(
    "name, content, fragment",
    [
        ("latin1.toml", 'name = "caf\xe9"\n'.encode("latin-1"), "invalid byte 0xe9 at offset 11"),
        ("utf16.json", json.dumps(GOOD).encode("utf-16"), "it is UTF-16 text"),
        ("png.toml", b"\x89PNG\r\n\x1a\n" + b"x" * 50, "invalid byte 0x89"),
    ],
    ids=["latin1", "utf16", "png"],
)
def test_bytes_that_are_not_utf8(tmp_path, capsys, name, content, fragment):
    path = write(tmp_path, name, content)
    with pytest.raises(SpecError, match="not a UTF-8 text file"):
        load_spec(path)
    refused_everywhere(capsys, tmp_path, path, "UTF-8", fragment)


@pytest.mark.parametrize("fmt", ["toml", "json"])
def test_a_byte_order_mark_is_not_content(tmp_path, fmt):
    path = write(
        tmp_path,
        f"bom.{fmt}",
        b"\xef\xbb\xbf" + (to_toml(GOOD) if fmt == "toml" else json.dumps(GOOD)).encode(),
    )
    assert load_spec(path).system.p == 3


@pytest.mark.parametrize("name", ["plain", "spec.yaml", "spec.txt"])
def test_unknown_file_types(tmp_path, capsys, name):
    path = write(tmp_path, name, to_toml(GOOD))
    refused_everywhere(capsys, tmp_path, path, "unknown file type")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_a_named_pipe_is_refused_without_blocking(tmp_path, capsys):
    path = tmp_path / "pipe.toml"
    os.mkfifo(path)
    refused_everywhere(capsys, tmp_path, path, "not a regular file")


def test_load_spec_takes_a_path():
    with pytest.raises(TypeError, match="path must be a file path"):
        load_spec(3)  # type: ignore[arg-type]
    with pytest.raises(SpecError, match="not a valid file name"):
        load_spec("a\x00b.toml")


@pytest.mark.parametrize(
    "name, limit",
    [("huge.toml", MAX_TEXT_BYTES), ("huge.json", MAX_TEXT_BYTES), ("huge.npz", MAX_BINARY_BYTES)],
)
def test_a_file_above_the_size_limit_is_refused_before_reading(tmp_path, capsys, name, limit):
    path = tmp_path / name
    size = max(100 * 10**6, limit + 1)  # 100 MB, sparse: costs no disk
    with open(path, "wb") as handle:
        handle.truncate(size)
    with pytest.raises(SpecError) as info:
        load_spec(path, max_attacked=1)
    message = str(info.value)
    assert message.startswith(str(path))
    assert f"{size:,} bytes" in message and f"{limit // 2**20} MiB" in message
    refused_everywhere(
        capsys, tmp_path, path, f"{size:,} bytes", f"{limit:,} bytes", extra=("--max-attacked", "1")
    )


@pytest.mark.slow
@pytest.mark.parametrize("fmt", ["toml", "json"])
def test_a_million_row_matrix_is_refused_before_building_arrays(tmp_path, capsys, fmt):
    rows = "[1]," * 10**6
    if fmt == "toml":
        text = (
            f'name = "tall"\n[system]\nA = [[1.0]]\nC = [{rows[:-1]}]\n[attack]\nmax_attacked = 1\n'
        )
    else:
        text = (
            f'{{"system": {{"A": [[1.0]], "C": [{rows[:-1]}]}}, "attack": {{"max_attacked": 1}}}}'
        )
    path = write(tmp_path, f"tall.{fmt}", text)
    message = assert_refused(*cli(capsys, "analyze", str(path)), "1,000,000 entries")
    assert message.startswith(f"ssecert: error: {path}: key 'system.C'")
    assert f"limit of {MAX_MATRIX_DIM:,}" in message


def test_too_many_entries_is_refused_before_copying():
    square = np.zeros((3163, 3163))  # rows and columns within the limit, not the entries
    message = spec_error(
        good(system__A=square), "3,163 x 3,163 = 10,004,569 entries", key="system.A"
    )
    assert f"{MAX_MATRIX_ENTRIES:,} entries" in message


# ---------------------------------------------------------------------------
# .npz files
# ---------------------------------------------------------------------------


def npz(folder: Path, name: str = "plant.npz", **arrays: Any) -> Path:
    arrays.setdefault("A", np.array(A2))
    arrays.setdefault("C", np.array(C3))
    path = folder / name
    np.savez(path, **{k: v for k, v in arrays.items() if v is not None})
    return path


NPZ_ROWS = [
    ("datetime64", {"A": np.zeros((2, 2), dtype="datetime64[s]")}, "system.A", "datetime64"),
    ("timedelta64", {"C": np.ones((3, 2), dtype="timedelta64[ms]")}, "system.C", "timedelta64"),
    ("complex", {"A": np.eye(2) * (1 + 1j)}, "system.A", "complex"),
    (
        "object",
        {"A": np.array([[1.0, None], [0.0, 1.0]], dtype=object)},
        "A",
        "holds Python objects",
    ),
    ("string", {"A": np.array([["1", "0"], ["0", "1"]])}, "system.A", "numeric array"),
    ("bytes", {"A": np.array([[b"1", b"0"], [b"0", b"1"]])}, "system.A", "numeric array"),
    ("bool", {"C": np.ones((3, 2), dtype=bool)}, "system.C", "boolean"),
    ("structured", {"A": np.zeros((2, 2), dtype=[("x", "f8")])}, "system.A", "numeric array"),
    ("nan", {"A": np.array([[np.nan, 0.0], [0.0, 1.0]])}, "system.A", "finite"),
    ("three-d", {"A": np.ones((2, 2, 2))}, "system.A", "2-D"),
    ("sensors-numbers", {"sensors": np.arange(3)}, "sensors", "strings"),
    ("sensors-duplicate", {"sensors": np.array(["a", "a", "b"])}, "system.sensors", "unique"),
    ("unknown-variable", {"Q": np.eye(2)}, "Q", "unknown variable"),
    (
        "misspelt-variable",
        {"sensor": np.array(["a", "b", "c"])},
        "sensor",
        "did you mean 'sensors'",
    ),
    ("missing-C", {"C": None}, "C", "missing"),
]


@pytest.mark.parametrize("row", NPZ_ROWS, ids=[r[0] for r in NPZ_ROWS])
def test_npz_arrays(tmp_path, capsys, row):
    _, arrays, key, fragment = row
    path = npz(tmp_path, **arrays)
    with pytest.raises(SpecError) as info:
        load_spec(path, max_attacked=1)
    message = str(info.value)
    assert message.startswith(str(path)) and f"'{key}'" in message and fragment in message
    refused_everywhere(capsys, tmp_path, path, fragment, extra=("--max-attacked", "1"))


def _npz_with_header(path: Path, shape: tuple[int, ...]) -> Path:
    """An .npz whose A claims ``shape`` but holds a few bytes: a header-only bomb."""
    with zipfile.ZipFile(path, "w") as archive:
        with archive.open("A.npy", "w") as handle:
            np.lib.format.write_array_header_1_0(
                handle, {"descr": "<f8", "fortran_order": False, "shape": shape}
            )
            handle.write(b"\0" * 64)
        with archive.open("C.npy", "w") as handle:
            np.save(handle, np.ones((3, 1)))
    return path


@pytest.mark.parametrize(
    "shape, fragment",
    [
        ((10**6, 1), "1,000,000 rows"),
        ((4000, 4000), "16,000,000 entries"),
        ((10**5, 10**5), "100,000 rows"),
    ],
)
def test_npz_sizes_are_checked_on_the_header(tmp_path, capsys, monkeypatch, shape, fragment):
    path = _npz_with_header(tmp_path / "bomb.npz", shape)
    monkeypatch.setattr(
        np.lib.format,
        "read_array",
        lambda *a, **k: pytest.fail("array read before its size was checked"),
    )
    with pytest.raises(SpecError, match=fragment):
        load_spec(path, max_attacked=1)
    monkeypatch.undo()
    refused_everywhere(capsys, tmp_path, path, fragment, extra=("--max-attacked", "1"))


@pytest.mark.parametrize(
    "content", [b"PK\x03\x04 truncated", b"\x93NUMPY\x01\x00 one array", bytes(range(256))]
)
def test_corrupt_npz(tmp_path, capsys, content):
    path = write(tmp_path, "broken.npz", content)
    with pytest.raises(SpecError, match="cannot read the .npz file"):
        load_spec(path, max_attacked=1)
    refused_everywhere(capsys, tmp_path, path, "cannot read", extra=("--max-attacked", "1"))


# ---------------------------------------------------------------------------
# MATLAB .mat files
# ---------------------------------------------------------------------------


def mat(folder: Path, variables: dict[str, Any], name: str = "plant.mat", **kwargs: Any) -> Path:
    path = folder / name
    scipy.io.savemat(path, variables, **kwargs)
    return path


def _cells(*names: str) -> np.ndarray:
    cells = np.empty((1, len(names)), dtype=object)
    cells[0, :] = names
    return cells


MAT_ROWS = [
    ("no-expected-variables", {"B": np.eye(2), "D": np.zeros((3, 1))}, "A", "missing"),
    ("only-A", {"A": np.array(A2)}, "C", "missing"),
    ("lower-case", {"a": np.array(A2), "c": np.array(C3)}, "a", "did you mean 'A'"),
    (
        "extra-variables",
        {"A": np.array(A2), "C": np.array(C3), "Ts": 0.01, "Q": np.eye(2)},
        "Q",
        "unknown variable",
    ),
    ("complex", {"A": np.array(A2) * 1j, "C": np.array(C3)}, "system.A", "complex"),
    (
        "logical",
        {"A": np.eye(2, dtype=bool), "C": np.array(C3)},
        "system.A",
        "MATLAB logical array",
    ),
    ("char", {"A": "ab", "C": np.array(C3)}, "system.A", "MATLAB char array"),
    ("cell", {"A": _cells("x", "y"), "C": np.array(C3)}, "system.A", "MATLAB cell array"),
    ("struct", {"A": {"x": 1.0}, "C": np.array(C3)}, "A", "MATLAB struct"),
    (
        "sparse",
        {"A": scipy.sparse.csc_matrix(np.array(A2)), "C": np.array(C3)},
        "A",
        "MATLAB sparse matrix",
    ),
    (
        "sensors-numbers",
        {"A": np.array(A2), "C": np.array(C3), "sensors": np.arange(3.0)},
        "sensors",
        "strings",
    ),
    (
        "sensors-duplicate",
        {"A": np.array(A2), "C": np.array(C3), "sensors": _cells("a", "b", "a")},
        "system.sensors",
        "unique",
    ),
]


@pytest.mark.parametrize("compress", [False, True], ids=["plain", "compressed"])
@pytest.mark.parametrize("row", MAT_ROWS, ids=[r[0] for r in MAT_ROWS])
def test_mat_variables(tmp_path, capsys, row, compress):
    _, variables, key, fragment = row
    path = mat(tmp_path, variables, do_compression=compress)
    with pytest.raises(SpecError) as info:
        load_spec(path, max_attacked=1)
    message = str(info.value)
    assert message.startswith(str(path)) and f"'{key}'" in message and fragment in message
    refused_everywhere(capsys, tmp_path, path, fragment, extra=("--max-attacked", "1"))


def test_mat_files_that_load(tmp_path):
    for compress in (False, True):
        path = mat(
            tmp_path,
            {
                "A": np.array(A2),
                "C": np.array(C3).astype(np.int16),
                "sensors": _cells("p", "v", "w"),
            },
            do_compression=compress,
        )
        spec = load_spec(path, max_attacked=1)
        assert spec.system.sensors == ("p", "v", "w") and spec.system.p == 3
    path = mat(tmp_path, {"A": np.array(A2), "C": np.array(C3)}, format="4")
    assert load_spec(path, max_attacked=1).system.n == 2


def _v73_header() -> bytes:
    text = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5"
    return text.ljust(116, b" ") + b"\0" * 8 + b"\x00\x02IM"


@pytest.mark.parametrize(
    "content, fragment",
    [
        (_v73_header() + b"\x89HDF\r\n\x1a\n" + b"\0" * 400, "v7.3 (HDF5)"),
        (
            b"MATLAB 5.0 MAT-file".ljust(124, b" ") + b"\x00\x01IM" + b"\x0e\x00\x00\x00\xff\xff",
            "cannot read",
        ),
        (b"definitely not a MATLAB file " * 8, "cannot read"),
        (bytes(range(256)) * 4, "cannot read"),
    ],
)
def test_mat_files_that_cannot_be_read(tmp_path, capsys, content, fragment):
    path = write(tmp_path, "odd.mat", content)
    with pytest.raises(SpecError, match=re.escape(fragment)):
        load_spec(path, max_attacked=1)
    refused_everywhere(capsys, tmp_path, path, fragment, extra=("--max-attacked", "1"))


def test_truncated_mat_file(tmp_path, capsys):
    whole = mat(
        tmp_path, {"A": np.random.default_rng(0).random((6, 6)), "C": np.ones((3, 6))}
    ).read_bytes()
    for cut in (130, 200, len(whole) // 2, len(whole) - 3):
        path = write(tmp_path, "cut.mat", whole[:cut])
        with pytest.raises(SpecError, match="cannot read the .mat file"):
            load_spec(path, max_attacked=1)
    assert_refused(*cli(capsys, "analyze", str(path), "--max-attacked", "1"), "cannot read")


def test_mat_sizes_are_checked_before_loading(tmp_path, monkeypatch):
    path = mat(tmp_path, {"A": np.zeros((1, 1)), "C": np.zeros((12_000, 1))}, do_compression=True)
    monkeypatch.setattr(
        scipy.io, "loadmat", lambda *a, **k: pytest.fail("loaded before the size was checked")
    )
    with pytest.raises(SpecError, match="12,000 rows"):
        load_spec(path, max_attacked=1)


# ---------------------------------------------------------------------------
# output paths: checked before the run, errors name the path, nothing written
# ---------------------------------------------------------------------------


def listing(folder: Path) -> list[str]:
    """Every file and folder under ``folder``, hidden temporary files included."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def test_out_under_a_regular_file(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    before = listing(tmp_path)
    assert_refused(
        *cli(capsys, "certify", "ugv", "--no-sim", "--out", f"{tmp_path}/file/sub"),
        f"{tmp_path}/file/sub",
        "is a file",
    )
    assert listing(tmp_path) == before


def test_out_that_is_a_file(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    assert_refused(
        *cli(capsys, "certify", "ugv", "--no-sim", "--out", str(tmp_path / "file")),
        "exists and is not a folder",
    )


@pytest.mark.slow
@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="no /proc here")
@pytest.mark.parametrize("option", ["--out", "--json"])
def test_an_impossible_output_path(tmp_path, capsys, option):
    argv = ["certify", "ugv", "--no-sim", "--out", str(tmp_path / "out")]
    argv += [option, "/proc/ssecert-test/x"] if option == "--out" else [option, "/proc/x.json"]
    err = assert_refused(*cli(capsys, *argv))
    assert ("/proc/ssecert-test" if option == "--out" else "/proc/x.json") in err
    assert not (tmp_path / "out").exists()
    assert not os.path.exists("/proc/ssecert-test")


@pytest.mark.skipif(
    hasattr(os, "geteuid") and os.geteuid() == 0, reason="root writes into read-only folders"
)
def test_a_read_only_folder(tmp_path, capsys):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        err = assert_refused(*cli(capsys, "certify", "ugv", "--no-sim", "--out", str(folder)))
        assert str(folder) in err and "permission denied" in err
        err = assert_refused(*cli(capsys, "analyze", "ugv", "--json", str(folder / "a.json")))
        assert str(folder) in err
    finally:
        folder.chmod(0o755)
    assert listing(folder) == []


@pytest.mark.slow
def test_a_folder_that_refuses_files(tmp_path, capsys, monkeypatch):
    # what a read-only folder does when the check before the run cannot see it
    # (root, network file systems): the write fails, the message names the file
    import tempfile

    def refuse(*args, **kwargs):
        raise PermissionError(errno.EACCES, "Permission denied", kwargs.get("dir"))

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    out = tmp_path / "out"
    err = assert_refused(
        *cli(capsys, "certify", "ugv", "--no-sim", "--out", str(out)), "Permission denied"
    )
    assert f"{out}/ugv.html" in err and ".tmp" not in err
    assert not out.exists()  # the folder made for the report is removed again
    err = assert_refused(*cli(capsys, "analyze", "ugv", "--json", str(tmp_path / "a.json")))
    assert f"{tmp_path}/a.json" in err and listing(tmp_path) == []


@pytest.mark.parametrize(
    "argv, fragment",
    [
        (["analyze", "ugv", "--json", "{tmp}"], "is a folder"),
        (["analyze", "ugv", "--json", "{tmp}/no/such/a.json"], "does not exist"),
        (["analyze", "ugv", "--json", ""], "empty path"),
        (["certify", "ugv", "--out", ""], "empty path"),
        (["simulate", "ugv", "--json", "{tmp}"], "is a folder"),
        (["certify", "ugv", "--out", "{tmp}/out", "--json", "{tmp}"], "is a folder"),
    ],
)
def test_bad_output_paths_are_refused_before_the_run(tmp_path, capsys, monkeypatch, argv, fragment):
    def too_early(*args, **kwargs):
        pytest.fail("the run started before the paths were checked")

    for module, name in (
        ("ssecert.analyze", "analyze"),
        ("ssecert.certify", "analyze"),
        ("ssecert.simulation.engine", "simulate_spec"),
    ):
        monkeypatch.setattr(sys.modules[module], name, too_early)
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert_refused(*cli(capsys, *argv), fragment)
    assert listing(tmp_path) == []


def test_an_existing_report_folder_name(tmp_path, capsys):
    (tmp_path / "ugv.html").mkdir()
    assert_refused(
        *cli(capsys, "certify", "ugv", "--no-sim", "--out", str(tmp_path)), "ugv.html is a folder"
    )


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_json_into_a_named_pipe_is_written_in_place(tmp_path, capsys):
    import threading

    pipe = tmp_path / "pipe"
    os.mkfifo(pipe)
    received: list[str] = []
    reader = threading.Thread(target=lambda: received.append(pipe.read_text()))
    reader.start()
    status, out, err = cli(capsys, "analyze", "ugv", "--json", str(pipe))
    reader.join(timeout=60)
    assert status == 1, err
    assert json.loads(received[0])["system"]["name"] == "ugv"
    assert pipe.is_fifo() and listing(tmp_path) == ["pipe"]


def test_json_through_a_symbolic_link_keeps_the_link(tmp_path, capsys):
    real = tmp_path / "real.json"
    real.write_text("{}")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    assert cli(capsys, "analyze", "ugv", "--json", str(link))[0] == 1
    assert link.is_symlink() and json.loads(real.read_text())["system"]["name"] == "ugv"


# ---------------------------------------------------------------------------
# interrupted runs: no partial report, no temporary file, no new folder
# ---------------------------------------------------------------------------


@pytest.fixture()
def old_reports(tmp_path):
    """An --out folder that already holds a report: it must survive a failed run."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "ugv.html").write_text("old html")
    (out / "ugv.json").write_text("old json")
    return out


def assert_old_reports_intact(out: Path) -> None:
    assert listing(out) == ["ugv.html", "ugv.json"]
    assert (out / "ugv.html").read_text() == "old html"
    assert (out / "ugv.json").read_text() == "old json"


@pytest.mark.slow
def test_interrupt_while_rendering(tmp_path, capsys, monkeypatch, old_reports):
    import ssecert.report.html as html

    def interrupted(result):
        raise KeyboardInterrupt

    monkeypatch.setattr(html, "render_report", interrupted)
    status, out, err = cli(capsys, "certify", "ugv", "--no-sim", "--out", str(old_reports))
    assert status == 130 and "interrupted" in err
    assert_old_reports_intact(old_reports)
    status, _, _ = cli(capsys, "certify", "ugv", "--no-sim", "--out", str(tmp_path / "new"))
    assert status == 130 and not (tmp_path / "new").exists()


@pytest.mark.slow
def test_renderer_failing_half_way(tmp_path, capsys, monkeypatch, old_reports):
    import ssecert.report.json as json_report

    def broken(result):
        raise RuntimeError("renderer broke")

    monkeypatch.setattr(json_report, "certify_json", broken)
    status, out, err = cli(
        capsys,
        "certify",
        "ugv",
        "--no-sim",
        "--out",
        str(old_reports),
        "--json",
        str(tmp_path / "copy.json"),
    )
    assert status == 4 and "internal error" in err  # a bug: reported as one
    assert_old_reports_intact(old_reports)
    assert not (tmp_path / "copy.json").exists()


@pytest.mark.slow
@pytest.mark.parametrize("fail_at", [1, 2, 3])
def test_disk_full_while_writing(tmp_path, capsys, monkeypatch, old_reports, fail_at):
    calls = []
    real_fsync = os.fsync

    def fsync(fd):
        calls.append(fd)
        if len(calls) == fail_at:
            raise OSError(errno.ENOSPC, "No space left on device")
        real_fsync(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    status, out, err = cli(
        capsys,
        "certify",
        "ugv",
        "--no-sim",
        "--out",
        str(old_reports),
        "--json",
        str(tmp_path / "copy.json"),
    )
    assert_refused(status, out, err, "No space left on device")
    assert_old_reports_intact(old_reports)
    assert not (tmp_path / "copy.json").exists()


@pytest.mark.slow
@pytest.mark.parametrize("failure", [KeyboardInterrupt, OSError])
def test_failure_between_renames_restores_the_old_files(
    tmp_path, capsys, monkeypatch, old_reports, failure
):
    calls = []
    real_replace = os.replace

    def replace(src, dst):
        calls.append(dst)
        if len(calls) == 2:
            raise failure(errno.EIO, "I/O error") if failure is OSError else failure()
        real_replace(src, dst)

    import ssecert.base.atomic as io_module

    monkeypatch.setattr(io_module.os, "replace", replace)
    status, out, err = cli(capsys, "certify", "ugv", "--no-sim", "--out", str(old_reports))
    assert status == (130 if failure is KeyboardInterrupt else 2), err
    monkeypatch.undo()
    assert_old_reports_intact(old_reports)


def test_interrupted_analyze_leaves_no_json(tmp_path, capsys, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(sys.modules["ssecert.analyze"], "analyze", interrupted)
    status, _, err = cli(capsys, "analyze", "ugv", "--json", str(tmp_path / "a.json"))
    assert status == 130 and listing(tmp_path) == []


# ---------------------------------------------------------------------------
# warnings: none reaches the terminal; what they say is kept as notes
# ---------------------------------------------------------------------------

_DEGENERATE = {
    "singular": ([[1.0, 1.0], [1.0, 1.0]], [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
    "zero-sensor-row": ([[0.9, 0.1], [0.0, 0.8]], [[1.0, 0.0], [0.0, 0.0], [1.0, 1.0]]),
    "a-zero": ([[0.0, 0.0], [0.0, 0.0]], [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
    "tiny": ([[1e-300, 0.0], [0.0, 1e-300]], [[1e-300, 0.0], [0.0, 1e-300], [1e-300, 1e-300]]),
    "huge": ([[1e300, 1.0], [0.0, 1e300]], [[1e300, 0.0], [0.0, 1e300], [1e300, 1e300]]),
    "mixed-scales": ([[1e300, 1e-300], [0.0, 1e-300]], [[1.0, 0.0], [0.0, 1e300], [1.0, 1.0]]),
}
_OBSERVERS = [
    {"kind": "luenberger", "gain": "pinv"},
    {"kind": "dsso", "step": 0.5, "threshold": 0.1},
    {"kind": "elastic_net", "step": 0.5, "threshold": 0.1, "shrink": 0.5},
]


def degenerate_spec(folder: Path, name: str, observer: int) -> Path:
    A, C = _DEGENERATE[name]
    data = {
        "name": name,
        "system": {"A": A, "C": C},
        "attack": {"max_attacked": 1},
        "observer": _OBSERVERS[observer],
        "scenario": [
            {"name": "constant", "attack": "constant", "sensors": [1], "steps": 40, "runs": 4}
        ],
    }
    return write(folder, f"{name}.toml", data)


def run_quietly(capsys: Any, *argv: str) -> tuple[int, str, str]:
    """main(argv) with every warning recorded: none may escape the command."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        status, out, err = cli(capsys, *argv)
    assert [str(w.message) for w in caught] == []
    for stream in (out, err):
        assert not re.search(r"\w+Warning\b", stream), stream
        assert "Traceback" not in stream
    return status, out, err


@pytest.mark.slow
@pytest.mark.parametrize("name", list_examples())
def test_packaged_examples_raise_no_warning(tmp_path, capsys, name):
    status, out, _ = run_quietly(capsys, "analyze", name)
    assert status in (0, 1, 3) and "note:" not in out
    status, out, _ = run_quietly(capsys, "certify", name, "--out", str(tmp_path))
    assert status in (0, 1, 3) and "note:" not in out


@pytest.mark.slow
@pytest.mark.parametrize(
    "name, observer",
    [
        pytest.param(name, k, id=f"{name}-{o['kind']}")
        for name in _DEGENERATE
        for k, o in enumerate(_OBSERVERS)
    ],
)
def test_degenerate_plants_raise_no_warning(tmp_path, capsys, name, observer):
    path = degenerate_spec(tmp_path, name, observer)
    # certify runs every check of analyze, the simulations and the report
    for argv in (
        ["certify", str(path), "--out", str(tmp_path / "out"), "--json", "-"],
        ["simulate", str(path), "--json", "-"],
    ):
        status, out, err = run_quietly(capsys, *argv)
        if status == 2:  # simulate without a gain: a refusal, on one line
            assert_refused(status, out, err, "observer.gain = ")
        else:
            assert status in (0, 1, 3), err


@pytest.mark.slow
def test_what_the_warnings_said_is_kept(tmp_path, capsys, monkeypatch):
    # the runtime warnings numpy raised, as the command saw them
    raised: list[tuple[type[Warning], str]] = []
    show = _WarningLog.show

    def recording(self, message, category, *args, **kwargs):
        raised.append((category, str(message)))
        return show(self, message, category, *args, **kwargs)

    monkeypatch.setattr(_WarningLog, "show", recording)
    # the package's own computations no longer warn on this spec: its observability check is
    # made to overflow as numpy does, from a module of the package
    module = sys.modules["ssecert.analyze"]
    where = Path(ssecert.__file__).parent / "structure" / "observability.py"
    scope = {"np": np, "check": module.observability}
    source = "def overflowing(*args, **kwargs):\n    np.array([1e308]) * 10.0\n    return check(*args, **kwargs)\n"
    exec(compile(source, str(where), "exec"), scope)
    monkeypatch.setattr(module, "observability", scope["overflowing"])
    path = degenerate_spec(tmp_path, "huge", 0)
    status, out, _ = run_quietly(capsys, "analyze", str(path), "--json", str(tmp_path / "a.json"))
    # decided (sensors 0 and 2 are the only ones that see the Jordan block's eigenvector e1,
    # so max_removable = 1 < 2s) or inconclusive, never exit 4
    assert status in (1, 3)
    assert re.search(r"note: overflow encountered in \w+ \(in ssecert\.\w+", out), out
    said = {text for category, text in raised if category is RuntimeWarning}
    assert said
    notes = json.loads((tmp_path / "a.json").read_text())["meta"]["notes"]
    # every warning's own words are kept, each in a note of its own
    assert all(any(n == text or n.startswith(f"{text} (") for n in notes) for text in said)
    raised.clear()
    status, out, _ = run_quietly(capsys, "certify", str(path), "--out", str(tmp_path))
    assert "note: overflow encountered" in out
    said = {text for category, text in raised if category is RuntimeWarning}
    assert said
    kept = json.loads((tmp_path / "huge.json").read_text())["notes"]
    assert all(any(n == text or n.startswith(f"{text} (") for n in kept) for text in said)
    assert "overflow encountered" in (tmp_path / "huge.html").read_text()


def test_a_note_names_the_module_of_the_package_that_warned():
    # the innermost module of ssecert on the stack, wherever in the package the CLI lives
    from ssecert.cli import _warnings_as_notes

    where = Path(ssecert.__file__).parent / "structure" / "sparse.py"
    with _warnings_as_notes() as log:
        exec(compile("import warnings; warnings.warn('overflow in x')", str(where), "exec"))
    assert log.notes() == ["overflow in x (in ssecert.structure.sparse)"]


@pytest.mark.slow
def test_no_warning_reaches_stderr_of_a_fresh_interpreter(tmp_path):
    path = degenerate_spec(tmp_path, "huge", 2)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONWARNINGS"}
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "ssecert",
            "certify",
            str(path),
            "--out",
            str(tmp_path / "out"),
            "--json",
            "-",
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert done.returncode in (1, 3), done.stderr
    assert "Warning" not in done.stderr and "Traceback" not in done.stderr, done.stderr
    json.loads(done.stdout)


# ---------------------------------------------------------------------------
# reports name the spec as typed; regenerating changes only the date
# ---------------------------------------------------------------------------


def _outputs(folder: Path, name: str) -> tuple[str, dict[str, Any]]:
    return (folder / f"{name}.html").read_text(), json.loads((folder / f"{name}.json").read_text())


@pytest.mark.parametrize(
    "typed", ["specs/plant.toml", "../specs/plant.toml", "./specs/../specs/plant.toml"]
)
def test_reports_name_the_spec_as_typed(tmp_path, capsys, monkeypatch, typed):
    (tmp_path / "specs").mkdir()
    write(tmp_path / "specs", "plant.toml", GOOD)
    work = tmp_path / "work"
    (work / "specs").mkdir(parents=True)
    write(work / "specs", "plant.toml", GOOD)
    monkeypatch.chdir(work)
    status, _, err = cli(capsys, "certify", typed, "--out", "reports", "--no-sim")
    assert status == 1, err
    html, document = _outputs(work / "reports", "plant")
    assert document["meta"]["spec"]["source"] == typed
    assert document["reproduce"] == f"ssecert certify {typed} --out reports --no-sim"
    assert f"<th>spec file</th><td>{typed}</td>" in html
    assert f"ssecert certify {typed} --out reports --no-sim" in html
    for text in (html, json.dumps(document)):
        assert str(tmp_path) not in text and os.getcwd() not in text
    status, out, _ = cli(capsys, "analyze", typed, "--json", "-")
    assert json.loads(out)["meta"]["spec"]["source"] == typed


@pytest.mark.slow
def test_packaged_examples_are_named_by_name(tmp_path, capsys):
    package = str(Path(ssecert.__file__).parent)
    assert cli(capsys, "certify", "ugv", "--out", str(tmp_path), "--no-sim")[0] == 1
    html, document = _outputs(tmp_path, "ugv")
    assert document["meta"]["spec"]["source"] == "ugv"
    assert "<th>spec file</th><td>ugv</td>" in html
    assert package not in html and package not in json.dumps(document)
    assert str(example_path("ugv")) not in html


def _masked(html: str, document: dict[str, Any]) -> tuple[str, str]:
    html = re.sub(r"<th>date</th><td>[^<]*</td>", "<th>date</th><td>DATE</td>", html)
    document["meta"]["date"] = "DATE"
    document["meta"]["timings"] = dict.fromkeys(document["meta"].get("timings", {}), "SECONDS")
    return html, json.dumps(document, indent=1)  # keeps the order of the keys


@pytest.mark.slow
@pytest.mark.parametrize("simulate", [False, True], ids=["no-sim", "with-simulations"])
def test_regenerating_a_report_changes_only_its_date(tmp_path, capsys, monkeypatch, simulate):
    monkeypatch.chdir(tmp_path)
    argv = ["certify", "ugv", "--out", "reports", "--seed", "3"] + (
        [] if simulate else ["--no-sim"]
    )
    runs = []
    for _ in range(2):
        assert cli(capsys, *argv)[0] == 1
        runs.append(_outputs(tmp_path / "reports", "ugv"))
        assert listing(tmp_path / "reports") == ["ugv.html", "ugv.json"]  # no temporary file
    (html_1, doc_1), (html_2, doc_2) = runs
    if simulate:
        assert doc_1["simulations"] and set(doc_1["meta"]["timings"]) == set(
            doc_2["meta"]["timings"]
        )
    first, second = _masked(html_1, doc_1), _masked(html_2, doc_2)
    assert first[0] == second[0], "the HTML changed beyond its date"
    assert first[1] == second[1], "the JSON changed beyond its date and timings"
    for text in first:
        assert not re.search(r"0x[0-9a-f]{6,}", text)  # no object ids
        assert ".tmp" not in text and str(tmp_path) not in text


@pytest.mark.parametrize(
    "observer, error, words",
    [
        ({"kind": "luenberger", "gian": "deadbeat"}, ValueError, "did you mean 'gain'"),
        ({"kind": "dsso", "gain": "deadbeat"}, ValueError, "key 'step' is required"),
        ({"kind": "luenberger", "gain": [[1, 0], [0, 1]]}, ValueError, "2 x 3 matrix"),
        ({"kind": "luenberger", "gain": "place"}, ValueError, "needs key 'poles'"),
        ({"kind": "luenberger", "poles": [0.5, 0.6]}, ValueError, "only used with gain 'place'"),
        ({"kind": "luenberger", "gain": None}, ValueError, "'gain' is None"),
        ({"gain": "deadbeat"}, ValueError, "key 'kind' is required"),
        ([("kind", "luenberger")], TypeError, "observer must be a mapping"),
    ],
)
def test_build_observer_checks_the_keys_of_a_section_given_in_python(observer, error, words):
    # the guide passes a plain dict: a misspelt key was ignored (the default gain built), a
    # wrong gain failed inside numpy's matmul, a missing key raised a bare KeyError
    from ssecert.observers import build_observer

    system = System([[1.0, 0.0099], [0.0, 0.9876]], [[1, 0], [0, 1], [0, 1]])
    with pytest.raises(error, match=words):
        build_observer(system, observer)


def test_an_entry_that_is_not_a_float64_is_refused_not_rounded(tmp_path):
    # C = [[2^53 + 1, 2^53], [2^53, 2^53]] is invertible; rounded to float64 it is singular,
    # and the plant was called "not observable (confirmed in exact arithmetic)"
    from ssecert import load_spec
    from ssecert.spec import SpecError

    big = 2**53
    path = tmp_path / "big.toml"
    path.write_text(
        f'name = "big"\n[system]\nA = [[1, 0], [0, 1]]\nC = [[{big + 1}, {big}], [{big}, {big}]]\n'
        "[attack]\nmax_attacked = 0\n"
    )
    with pytest.raises(SpecError, match="'system.C': has an entry that is not a float64"):
        load_spec(path)
    archive = tmp_path / "big.npz"
    np.savez(archive, A=np.eye(2, dtype=np.int64), C=np.array([[big + 1, big], [big, big]]))
    with pytest.raises(SpecError, match="9007199254740993"):
        load_spec(archive, max_attacked=0)
    wide = np.array([[1, 1], [1, 1 + np.longdouble(2) ** -60]], dtype=np.longdouble)
    if wide[1, 1] != 1:  # (a platform whose long double is wider than a float64)
        with pytest.raises(ValueError, match="not a float64"):
            System(np.eye(2), wide)
    # integers a float64 holds exactly are taken, however large; a Fraction only if exact
    assert System(np.eye(2), [[2**60, 3], [0, 1]]).C[0, 0] == 2.0**60
    from fractions import Fraction

    assert System(np.eye(1), [[Fraction(1, 2)]]).C[0, 0] == 0.5
    with pytest.raises(ValueError, match="Fraction"):
        System(np.eye(1), [[Fraction(1, 3)]])


def test_a_horizon_beyond_the_limit_is_refused_as_the_argument_it_is(capsys):
    # (it was refused as a key of the spec file, "ugv.toml: key '--horizon'")
    assert_refused(*cli(capsys, "analyze", "ugv", "--horizon", "10001"), "--horizon", "10,000")
