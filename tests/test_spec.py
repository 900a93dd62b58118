"""Spec files (TOML, JSON, .npz, .mat), spec dictionaries and the System class.

Every bad input must raise SpecError (a ValueError) whose one-line message
names the file and the key; see docs/architecture.md, "Spec files".
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import json
import math
from pathlib import Path
from typing import Any

import control
import numpy as np
import pytest
import scipy.io

from ssecert.examples import example_path, list_examples, load_example
from ssecert.spec import (
    ATTACK_KINDS,
    OBSERVER_KINDS,
    SCENARIO_DEFAULTS,
    Spec,
    SpecError,
    load_spec,
    spec_from_dict,
)
from ssecert.system import System

# ---------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------

A2 = [[1.0, 0.1], [0.0, 0.9]]
C3 = [[1, 0], [0, 1], [1, 1]]

#: a valid design with n = 2 states and p = 3 sensors
BASE: dict[str, Any] = {
    "name": "demo",
    "system": {"A": A2, "C": C3, "sensors": ["s0", "s1", "s2"]},
    "attack": {"max_attacked": 1, "horizon": 2},
}


def base(**top: Any) -> dict[str, Any]:
    """A deep copy of BASE with top-level keys replaced."""
    data = copy.deepcopy(BASE)
    data.update(copy.deepcopy(top))
    return data


def _toml_key(key: str) -> str:
    return key if key.replace("_", "").replace("-", "").isalnum() else json.dumps(key)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, (int, str)):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):  # inline table
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {value!r} as TOML")


def to_toml(data: dict[str, Any]) -> str:
    """A minimal TOML writer for spec dictionaries (tables, arrays of tables)."""
    lines: list[str] = []
    scalars = {
        k: v
        for k, v in data.items()
        if not isinstance(v, dict)
        and not (isinstance(v, list) and v and all(isinstance(x, dict) for x in v))
    }
    for key, value in scalars.items():
        lines.append(f"{_toml_key(key)} = {_toml_value(value)}")
    for key, value in data.items():
        if key in scalars:
            continue
        if isinstance(value, dict):
            lines.append(f"\n[{_toml_key(key)}]")
            for k, v in value.items():
                lines.append(f"{_toml_key(k)} = {_toml_value(v)}")
        else:
            for table in value:
                lines.append(f"\n[[{_toml_key(key)}]]")
                for k, v in table.items():
                    lines.append(f"{_toml_key(k)} = {_toml_value(v)}")
    return "\n".join(lines) + "\n"


def write_spec(folder: Path, data: dict[str, Any], fmt: str = "toml", stem: str = "spec") -> Path:
    path = folder / f"{stem}.{fmt}"
    if fmt == "toml":
        path.write_text(to_toml(data), encoding="utf-8")
    else:
        path.write_text(json.dumps(data), encoding="utf-8")
    return path


def expect_error(path: Path, *fragments: str, key: str | None = None, **kwargs: Any) -> str:
    """load_spec(path) must raise SpecError naming the file, the key and the fragments."""
    with pytest.raises(SpecError) as info:
        load_spec(path, **kwargs)
    message = str(info.value)
    assert isinstance(info.value, ValueError)
    assert str(path) in message, message
    if key is not None:
        assert f"'{key}'" in message, message
    for fragment in fragments:
        assert fragment in message, message
    assert "\n" not in message, "error messages must fit on one line"
    return message


def dict_error(data: Any, key: str | None, *fragments: str, **kwargs: Any) -> str:
    """spec_from_dict(data) must raise SpecError naming the key and the fragments."""
    with pytest.raises(SpecError) as info:
        spec_from_dict(data, **kwargs)
    message = str(info.value)
    assert message.startswith(kwargs.get("source", "<dict>")), message
    if key is not None:
        assert f"key '{key}'" in message, message
    for fragment in fragments:
        assert fragment in message, message
    return message


FORMATS = ["toml", "json"]

# ---------------------------------------------------------------------------
# packaged examples
# ---------------------------------------------------------------------------

EXPECTED_EXAMPLES = {
    # name: (n, p, max_attacked, horizon)
    "ugv": (2, 3, 1, 2),
    "notes-example-0": (3, 3, 1, 1),
    "notes-example-1": (3, 5, 1, 1),
    "notes-example-2": (3, 5, 1, 1),
    "notes-example-3": (3, 5, 1, 1),
    "lasso-example-1": (1, 3, 1, 1),
    "random-n15-p30": (15, 30, 3, 15),
    "ieee14": (10, 19, 6, 20),
}


def test_list_examples_names_every_packaged_example():
    names = list_examples()
    assert names == sorted(names)
    assert set(EXPECTED_EXAMPLES) <= set(names)


@pytest.mark.parametrize("name", list_examples())
def test_every_example_loads(name):
    path = example_path(name)
    spec = load_spec(path)
    assert isinstance(spec, Spec)
    assert spec.name == name
    assert spec.source == str(path)
    assert spec.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert spec.system.name == name
    assert spec.system.A.shape == (spec.system.n, spec.system.n)
    assert spec.system.C.shape == (spec.system.p, spec.system.n)
    assert 0 <= spec.max_attacked <= spec.system.p
    assert spec.horizon >= 1
    assert load_example(name).system == spec.system


@pytest.mark.parametrize("name", sorted(EXPECTED_EXAMPLES))
def test_example_dimensions(name):
    n, p, s, horizon = EXPECTED_EXAMPLES[name]
    spec = load_spec(example_path(name))
    assert (spec.system.n, spec.system.p, spec.max_attacked, spec.horizon) == (n, p, s, horizon)


def test_ugv_example_details():
    spec = load_spec(example_path("ugv"))
    np.testing.assert_array_equal(spec.system.A, [[1.0, 0.0099], [0.0, 0.9876]])
    np.testing.assert_array_equal(spec.system.C, [[1, 0], [0, 1], [0, 1]])
    assert spec.system.sensors == ("position", "velocity-a", "velocity-b")
    assert spec.observer is not None
    assert spec.observer["kind"] == "dsso"
    assert spec.observer["gain"] == "deadbeat"
    assert spec.observer["step"] == pytest.approx(0.7)
    assert spec.observer["threshold"] == pytest.approx(0.1)
    assert spec.observer["shrink"] == 1.0
    assert len(spec.scenarios) == 2
    first, second = spec.scenarios
    assert first["name"] == "constant-velocity-a"
    assert first["attack"] == "constant"
    assert first["sensors"] == [1]
    assert first["magnitude"] == (4.0, 5.0)
    assert (first["steps"], first["runs"], first["seed"]) == (300, 50, 0)
    assert second["name"] == "stealthy"
    assert second["attack"] == "stealthy"
    assert "sensors" not in second and "count" not in second


def test_lasso_example_system():
    spec = load_spec(example_path("lasso-example-1"))
    np.testing.assert_array_equal(spec.system.A, [[1.0]])
    np.testing.assert_array_equal(spec.system.C, [[2.0], [2.0], [2.0]])
    assert spec.system.sensors == ("y1", "y2", "y3")
    assert spec.observer is None
    assert spec.scenarios == ()


# ---------------------------------------------------------------------------
# valid files, TOML and JSON
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("fmt", FORMATS)
def test_valid_file_round_trip(tmp_path, fmt):
    path = write_spec(tmp_path, BASE, fmt)
    spec = load_spec(path)
    assert spec.name == "demo"
    assert spec.system == System(A2, C3, sensors=["s0", "s1", "s2"], name="demo")
    assert (spec.max_attacked, spec.horizon) == (1, 2)
    assert spec.source == str(path)
    assert spec.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert spec.observer is None and spec.scenarios == ()


def test_toml_and_json_give_the_same_spec(tmp_path):
    data = base(
        observer={"kind": "elastic_net", "step": 0.5, "threshold": 0.1, "shrink": 0.9},
        scenario=[
            {"name": "a", "attack": "constant", "sensors": [0, 2]},
            {"name": "b", "attack": "random", "count": 1, "noise": 0.01},
        ],
    )
    from_toml = load_spec(write_spec(tmp_path, data, "toml"))
    from_json = load_spec(write_spec(tmp_path, data, "json"))
    assert from_toml.system == from_json.system
    assert from_toml.observer == from_json.observer
    assert from_toml.scenarios == from_json.scenarios
    assert (from_toml.max_attacked, from_toml.horizon) == (
        from_json.max_attacked,
        from_json.horizon,
    )
    assert from_toml.sha256 != from_json.sha256


def test_name_defaults_to_the_file_stem(tmp_path):
    data = base()
    del data["name"]
    spec = load_spec(write_spec(tmp_path, data, "toml", stem="my_plant.v2"))
    assert spec.name == "my_plant.v2"
    spec = load_spec(write_spec(tmp_path, data, "json", stem="odd name"))
    assert spec.name == "odd-name"  # characters unfit for file names replaced


def test_integer_matrices_become_float(tmp_path):
    data = base(system={"A": [[1, 0], [0, 1]], "C": [[1, 0], [0, 1]]})
    spec = load_spec(write_spec(tmp_path, data))
    assert spec.system.A.dtype == np.float64 and spec.system.C.dtype == np.float64
    assert spec.system.sensors == ("y1", "y2")


def test_suffix_is_case_insensitive(tmp_path):
    path = tmp_path / "SPEC.TOML"
    path.write_text(to_toml(BASE))
    assert load_spec(path).system.p == 3
    assert load_spec(str(path)).name == "demo"


def test_spec_is_frozen(tmp_path):
    spec = load_spec(write_spec(tmp_path, BASE))
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.max_attacked = 5  # type: ignore[misc]


def test_system_matrices_of_a_loaded_spec_are_read_only(tmp_path):
    spec = load_spec(write_spec(tmp_path, BASE))
    with pytest.raises(ValueError):
        spec.system.A[0, 0] = 7.0
    with pytest.raises(ValueError):
        spec.system.C[0, 0] = 7.0


# ---------------------------------------------------------------------------
# overrides
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("fmt", FORMATS)
def test_overrides_replace_the_file_values(tmp_path, fmt):
    path = write_spec(tmp_path, BASE, fmt)
    spec = load_spec(path, max_attacked=2, horizon=3)
    assert (spec.max_attacked, spec.horizon) == (2, 3)
    spec = load_spec(path, max_attacked=0)
    assert (spec.max_attacked, spec.horizon) == (0, 2)
    spec = load_spec(path, horizon=5)
    assert (spec.max_attacked, spec.horizon) == (1, 5)


def test_horizon_defaults_to_n(tmp_path):
    data = base(attack={"max_attacked": 1})
    assert load_spec(write_spec(tmp_path, data)).horizon == 2
    data = base(
        system={"A": np.eye(4).tolist(), "C": np.eye(4).tolist()}, attack={"max_attacked": 0}
    )
    assert load_spec(write_spec(tmp_path, data, "json")).horizon == 4


def test_override_supplies_a_missing_max_attacked(tmp_path):
    data = base(attack={})
    path = write_spec(tmp_path, data)
    expect_error(path, "missing", key="attack.max_attacked")
    assert load_spec(path, max_attacked=1).max_attacked == 1


def test_attack_table_may_be_absent_with_an_override(tmp_path):
    data = base()
    del data["attack"]
    path = write_spec(tmp_path, data)
    expect_error(path, "--max-attacked", key="attack.max_attacked")
    spec = load_spec(path, max_attacked=1)
    assert (spec.max_attacked, spec.horizon) == (1, 2)


@pytest.mark.parametrize(
    "kwargs, key",
    [
        ({"max_attacked": -1}, "--max-attacked"),
        ({"max_attacked": 1.5}, "--max-attacked"),
        ({"max_attacked": True}, "--max-attacked"),
        ({"horizon": 0}, "--horizon"),
        ({"horizon": -2}, "--horizon"),
        ({"horizon": "3"}, "--horizon"),
    ],
)
def test_bad_overrides(tmp_path, kwargs, key):
    expect_error(write_spec(tmp_path, BASE), key=key, **kwargs)


# ---------------------------------------------------------------------------
# bad matrices
# ---------------------------------------------------------------------------


def test_nan_literal_in_toml(tmp_path):
    path = tmp_path / "nan.toml"
    path.write_text(
        'name = "x"\n[system]\nA = [[1.0, nan], [0.0, 1.0]]\nC = [[1, 0]]\n'
        "[attack]\nmax_attacked = 0\n"
    )
    expect_error(path, "finite", key="system.A")


@pytest.mark.parametrize("literal", ["inf", "-inf", "+inf"])
def test_inf_literal_in_toml(tmp_path, literal):
    path = tmp_path / "inf.toml"
    path.write_text(
        f'name = "x"\n[system]\nA = [[1.0, 0.0], [0.0, 1.0]]\nC = [[1, {literal}]]\n'
        "[attack]\nmax_attacked = 0\n"
    )
    expect_error(path, "finite", key="system.C")


def test_nan_in_json(tmp_path):
    path = tmp_path / "nan.json"
    path.write_text(
        '{"name": "x", "system": {"A": [[NaN]], "C": [[1.0]]}, "attack": {"max_attacked": 0}}'
    )
    expect_error(path, "finite", key="system.A")


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize(
    "system, key, fragments",
    [
        ({"A": [[1.0, 0.0], [0.0]], "C": C3}, "system.A", ("ragged",)),
        ({"A": A2, "C": [[1, 0], [0, 1, 2], [1, 1]]}, "system.C", ("ragged",)),
        ({"A": A2, "C": [[1, 0, 0], [0, 1, 0]]}, "system.C", ("columns", "expected 2", "got 3")),
        ({"A": A2, "C": [[1], [0]]}, "system.C", ("columns", "expected 2", "got 1")),
        ({"A": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], "C": C3}, "system.A", ("square", "(2, 3)")),
        ({"A": A2, "C": []}, "system.C", ()),
        ({"A": A2, "C": [[]]}, "system.C", ()),
        ({"A": [], "C": C3}, "system.A", ()),
        ({"A": [[]], "C": C3}, "system.A", ()),
        ({"A": [[1.0, "x"], [0.0, 1.0]], "C": C3}, "system.A", ("real numbers", "'x'")),
        ({"A": A2, "C": [[1, 0], [0, True], [1, 1]]}, "system.C", ("boolean",)),
        ({"A": "identity", "C": C3}, "system.A", ()),
        ({"A": 1.0, "C": C3}, "system.A", ("2-D",)),
        ({"A": [1.0, 2.0], "C": C3}, "system.A", ("2-D",)),
        ({"A": [[[1.0]]], "C": [[1.0]]}, "system.A", ("2-D",)),
        ({"A": A2, "C": [1, 0]}, "system.C", ("2-D",)),
        ({"A": {"a": 1}, "C": C3}, "system.A", ()),
    ],
)
def test_bad_matrices(tmp_path, fmt, system, key, fragments):
    expect_error(write_spec(tmp_path, base(system=system), fmt), *fragments, key=key)


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize(
    "sensors, fragments",
    [
        (["a", "b", "a"], ("unique", "'a'")),
        (["a", "b"], ("expected 3", "got 2")),
        (["a", "b", "c", "d"], ("expected 3", "got 4")),
        (["a", "", "c"], ("non-empty",)),
        (["a", 1, "c"], ("sensors[1]",)),
        ("abc", ("list of names",)),
    ],
)
def test_bad_sensor_names(tmp_path, fmt, sensors, fragments):
    data = base()
    data["system"]["sensors"] = sensors
    expect_error(write_spec(tmp_path, data, fmt), *fragments, key="system.sensors")


# ---------------------------------------------------------------------------
# bad attack section, names, missing keys
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize(
    "attack, key, fragments",
    [
        ({"max_attacked": -1}, "attack.max_attacked", (">= 0", "-1")),
        ({"max_attacked": 1.5}, "attack.max_attacked", ("integer",)),
        ({"max_attacked": True}, "attack.max_attacked", ("integer", "boolean")),
        ({"max_attacked": "1"}, "attack.max_attacked", ("integer",)),
        ({"max_attacked": 1, "horizon": 0}, "attack.horizon", (">= 1", "0")),
        ({"max_attacked": 1, "horizon": -3}, "attack.horizon", (">= 1",)),
        ({"max_attacked": 1, "horizon": 2.5}, "attack.horizon", ("integer",)),
    ],
)
def test_bad_attack_values(tmp_path, fmt, attack, key, fragments):
    expect_error(write_spec(tmp_path, base(attack=attack), fmt), *fragments, key=key)


def test_integral_float_counts_are_accepted(tmp_path):
    spec = load_spec(
        write_spec(tmp_path, base(attack={"max_attacked": 1.0, "horizon": 3.0}), "json")
    )
    assert (spec.max_attacked, spec.horizon) == (1, 3)
    assert isinstance(spec.max_attacked, int) and isinstance(spec.horizon, int)


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("name", ["my plant", "a/b", "../evil", "", "-lead", "tab\there", 5])
def test_bad_names(tmp_path, fmt, name):
    expect_error(write_spec(tmp_path, base(name=name), fmt), key="name")


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize(
    "mutate, key",
    [
        (lambda d: d["system"].pop("A"), "system.A"),
        (lambda d: d["system"].pop("C"), "system.C"),
        (lambda d: d["attack"].pop("max_attacked"), "attack.max_attacked"),
        (lambda d: d.pop("system"), "system"),
    ],
)
def test_missing_required_keys(tmp_path, fmt, mutate, key):
    data = base()
    mutate(data)
    expect_error(write_spec(tmp_path, data, fmt), "missing", key=key)


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize(
    "mutate, key, suggestion",
    [
        (lambda d: d.update(systme=1), "systme", "system"),
        (lambda d: d.update(scenarios=[]), "scenarios", "scenario"),
        (lambda d: d.update(obsever={"kind": "ogd"}), "obsever", "observer"),
        (lambda d: d["system"].update(sensor=["a", "b", "c"]), "system.sensor", "sensors"),
        (lambda d: d["system"].update(a=[[1.0]]), "system.a", "A"),
        (lambda d: d["attack"].update(max_atacked=1), "attack.max_atacked", "max_attacked"),
        (lambda d: d["attack"].update(horizn=2), "attack.horizn", "horizon"),
        (
            lambda d: d.update(
                observer={"kind": "dsso", "step": 0.5, "threshold": 0.1, "treshold": 0.1}
            ),
            "observer.treshold",
            "threshold",
        ),
        (
            lambda d: d.update(observer={"kind": "luenberger", "gains": "pinv"}),
            "observer.gains",
            "gain",
        ),
        (
            lambda d: d.update(scenario=[{"name": "a", "attack": "none", "stpes": 10}]),
            "scenario[0].stpes",
            "steps",
        ),
        (
            lambda d: d.update(
                scenario=[
                    {"name": "a", "attack": "none"},
                    {"name": "b", "attack": "none", "magnitdue": 1.0},
                ]
            ),
            "scenario[1].magnitdue",
            "magnitude",
        ),
    ],
)
def test_unknown_keys_are_refused_with_a_suggestion(tmp_path, fmt, mutate, key, suggestion):
    data = base()
    mutate(data)
    expect_error(
        write_spec(tmp_path, data, fmt), "unknown key", f"did you mean '{suggestion}'", key=key
    )


@pytest.mark.parametrize(
    "mutate, key",
    [
        (lambda d: d.update(zzzzzz=1), "zzzzzz"),
        (lambda d: d["system"].update(qqqq=1), "system.qqqq"),
        (lambda d: d["attack"].update(qqqq=1), "attack.qqqq"),
        (lambda d: d.update(observer={"kind": "ogd", "step": 0.1, "qqqq": 1}), "observer.qqqq"),
        (
            lambda d: d.update(scenario=[{"name": "a", "attack": "none", "qqqq": 1}]),
            "scenario[0].qqqq",
        ),
    ],
)
def test_unknown_keys_without_a_close_match(tmp_path, mutate, key):
    data = base()
    mutate(data)
    message = expect_error(
        write_spec(tmp_path, data, "json"), "unknown key", "allowed here", key=key
    )
    assert "did you mean" not in message


@pytest.mark.parametrize(
    "mutate, key",
    [
        (lambda d: d.update(system=[1, 2]), "system"),
        (lambda d: d.update(attack=3), "attack"),
        (lambda d: d.update(observer="dsso"), "observer"),
        (lambda d: d.update(scenario=5), "scenario"),
        (lambda d: d.update(scenario=["x"]), "scenario[0]"),
    ],
)
def test_sections_of_the_wrong_kind(tmp_path, mutate, key):
    data = base()
    mutate(data)
    expect_error(write_spec(tmp_path, data, "json"), key=key)


# ---------------------------------------------------------------------------
# files that cannot be read
# ---------------------------------------------------------------------------


def test_invalid_toml(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('name = "x"\n[system\nA = [[1.0]]\n')
    expect_error(path, "invalid TOML")


def test_toml_with_a_duplicate_key(tmp_path):
    path = tmp_path / "dup.toml"
    path.write_text('name = "x"\nname = "y"\n')
    expect_error(path, "invalid TOML")


def test_toml_not_utf8(tmp_path):
    path = tmp_path / "latin.toml"
    path.write_bytes('name = "caf\u00e9"\n'.encode("latin-1"))
    expect_error(path, "UTF-8")


def test_invalid_json(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"name": "x", "system": {"A": [[1.0]],}')
    expect_error(path, "invalid JSON")


@pytest.mark.parametrize("text", ["[1, 2]", '"spec"', "3", "null"])
def test_json_top_level_not_an_object(tmp_path, text):
    path = tmp_path / "top.json"
    path.write_text(text)
    expect_error(path, "object")


@pytest.mark.parametrize("filename", ["spec.yaml", "spec.txt", "spec"])
def test_unknown_suffix(tmp_path, filename):
    path = tmp_path / filename
    path.write_text(to_toml(BASE))
    expect_error(path, "unknown file type")


def test_missing_file(tmp_path):
    expect_error(tmp_path / "nowhere.toml", "no such file")
    expect_error(tmp_path / "no" / "such" / "dir.json", "no such file")


def test_directory_instead_of_a_file(tmp_path):
    folder = tmp_path / "folder.toml"
    folder.mkdir()
    expect_error(folder, "directory")


# ---------------------------------------------------------------------------
# .npz files
# ---------------------------------------------------------------------------


def test_npz_round_trip(tmp_path):
    path = tmp_path / "plant.npz"
    np.savez(path, A=np.array(A2), C=np.array(C3))
    spec = load_spec(path, max_attacked=1)
    assert spec.name == "plant"
    assert spec.system == System(A2, C3, name="plant")
    assert spec.system.sensors == ("y1", "y2", "y3")
    assert (spec.max_attacked, spec.horizon) == (1, 2)
    assert spec.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert spec.observer is None and spec.scenarios == ()
    assert load_spec(path, max_attacked=0, horizon=4).horizon == 4


def test_npz_with_sensor_names(tmp_path):
    path = tmp_path / "named.npz"
    np.savez(path, A=np.array(A2), C=np.array(C3), sensors=np.array(["p", "v1", "v2"]))
    assert load_spec(path, max_attacked=1).system.sensors == ("p", "v1", "v2")


def test_npz_file_name_with_spaces_gives_a_clean_name(tmp_path):
    path = tmp_path / "my plant (v2).npz"
    np.savez(path, A=np.array(A2), C=np.array(C3))
    spec = load_spec(path, max_attacked=0)
    assert spec.name.startswith("my-plant")
    assert " " not in spec.name and "(" not in spec.name


def test_npz_without_max_attacked(tmp_path):
    path = tmp_path / "plant.npz"
    np.savez(path, A=np.array(A2), C=np.array(C3))
    expect_error(path, "--max-attacked")


@pytest.mark.parametrize(
    "extra, key, fragments",
    [
        ({"Q": np.eye(2)}, "Q", ("unknown variable", "B, D and Ts are read and not used")),
        ({"sensor": np.array(["a", "b", "c"])}, "sensor", ("did you mean 'sensors'",)),
        ({"c": np.eye(2)}, "c", ("did you mean 'C'",)),
    ],
)
def test_npz_unknown_variable(tmp_path, extra, key, fragments):
    path = tmp_path / "plant.npz"
    np.savez(path, A=np.array(A2), C=np.array(C3), **extra)
    expect_error(path, "unknown variable", *fragments, key=key, max_attacked=1)


@pytest.mark.parametrize("missing", ["A", "C"])
def test_npz_missing_variable(tmp_path, missing):
    arrays = {"A": np.array(A2), "C": np.array(C3)}
    del arrays[missing]
    path = tmp_path / "plant.npz"
    np.savez(path, **arrays)
    expect_error(path, "missing", key=missing, max_attacked=1)


@pytest.mark.parametrize(
    "arrays, key, fragments",
    [
        ({"A": np.array(A2) + 1j, "C": np.array(C3)}, "system.A", ("complex",)),
        ({"A": np.array(A2), "C": np.array(C3, dtype=complex)}, "system.C", ("complex",)),
        ({"A": np.array([[1.0, np.nan], [0, 1]]), "C": np.array(C3)}, "system.A", ("finite",)),
        ({"A": np.array(A2), "C": np.array([[np.inf, 0.0]])}, "system.C", ("finite",)),
        ({"A": np.array(A2), "C": np.ones((3, 2), dtype=bool)}, "system.C", ("boolean",)),
        ({"A": np.array([["1", "0"], ["0", "1"]]), "C": np.array(C3)}, "system.A", ()),
        ({"A": np.ones((2, 3)), "C": np.array(C3)}, "system.A", ("square",)),
        ({"A": np.array(A2), "C": np.ones((3, 4))}, "system.C", ("columns", "expected 2")),
        ({"A": np.array(A2), "C": np.zeros((0, 2))}, "system.C", ("empty",)),
        ({"A": np.ones((2, 2, 2)), "C": np.array(C3)}, "system.A", ("2-D",)),
        (
            {"A": np.array(A2), "C": np.array(C3), "sensors": np.array([1, 2, 3])},
            "sensors",
            ("strings",),
        ),
    ],
)
def test_npz_bad_arrays(tmp_path, arrays, key, fragments):
    path = tmp_path / "plant.npz"
    np.savez(path, **arrays)
    expect_error(path, *fragments, key=key, max_attacked=1)


def test_npz_object_array_is_refused_without_unpickling(tmp_path):
    path = tmp_path / "plant.npz"
    np.savez(path, A=np.array([[1.0, None]], dtype=object), C=np.array(C3))
    expect_error(path, "cannot read", max_attacked=1)


@pytest.mark.parametrize(
    "content",
    [b"", b"PK\x03\x04 not really a zip archive", b"\x00\x01garbage" * 10],
)
def test_npz_corrupt(tmp_path, content):
    path = tmp_path / "broken.npz"
    path.write_bytes(content)
    expect_error(path, max_attacked=1)


def test_npy_file_with_npz_suffix(tmp_path):
    path = tmp_path / "single.npz"
    with open(path, "wb") as handle:
        np.save(handle, np.eye(2))
    expect_error(path, "cannot read", max_attacked=1)


# ---------------------------------------------------------------------------
# .mat files
# ---------------------------------------------------------------------------


def test_mat_round_trip(tmp_path):
    path = tmp_path / "plant.mat"
    scipy.io.savemat(path, {"A": np.array(A2), "C": np.array(C3)})
    spec = load_spec(path, max_attacked=1, horizon=3)
    assert spec.name == "plant"
    assert spec.system == System(A2, C3, name="plant")
    assert (spec.max_attacked, spec.horizon) == (1, 3)
    assert spec.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert load_spec(path, max_attacked=0).horizon == 2


def test_mat_sensors_as_cell_array(tmp_path):
    path = tmp_path / "cells.mat"
    cells = np.empty((1, 3), dtype=object)
    cells[0, :] = ["position", "velocity-a", "velocity-b"]
    scipy.io.savemat(path, {"A": np.array(A2), "C": np.array(C3), "sensors": cells})
    spec = load_spec(path, max_attacked=1)
    assert spec.system.sensors == ("position", "velocity-a", "velocity-b")
    np.testing.assert_array_equal(spec.system.C, C3)


def test_mat_sensors_as_string_array(tmp_path):
    path = tmp_path / "chars.mat"
    # a char matrix: MATLAB pads the shorter names with blanks
    scipy.io.savemat(
        path,
        {"A": np.array(A2), "C": np.array(C3), "sensors": np.array(["pos", "velocity-a", "v"])},
    )
    spec = load_spec(path, max_attacked=1)
    assert spec.system.sensors == ("pos", "velocity-a", "v")


def test_mat_duplicate_sensor_names(tmp_path):
    path = tmp_path / "dup.mat"
    cells = np.empty((1, 3), dtype=object)
    cells[0, :] = ["a", "b", "a"]
    scipy.io.savemat(path, {"A": np.array(A2), "C": np.array(C3), "sensors": cells})
    expect_error(path, "unique", key="system.sensors", max_attacked=1)


def test_mat_without_max_attacked(tmp_path):
    path = tmp_path / "plant.mat"
    scipy.io.savemat(path, {"A": np.array(A2), "C": np.array(C3)})
    expect_error(path, "--max-attacked")


def test_mat_unknown_variable(tmp_path):
    path = tmp_path / "plant.mat"
    scipy.io.savemat(path, {"A": np.array(A2), "C": np.array(C3), "Q": np.eye(2)})
    expect_error(path, "unknown variable", key="Q", max_attacked=1)


def test_mat_state_space_save_is_read_and_its_input_matrices_noted(tmp_path):
    # [A, B, C, D, Ts] = ssdata(sys); save(file, 'A', 'B', 'C', 'D', 'Ts')
    path = tmp_path / "ss.mat"
    B, D = np.array([[0.0], [0.01]]), np.zeros((3, 1))
    scipy.io.savemat(path, {"A": np.array(A2), "B": B, "C": np.array(C3), "D": D, "Ts": 0.01})
    with pytest.warns(UserWarning, match=r"ss\.mat: B, D and Ts read and not used"):
        spec = load_spec(path, max_attacked=1)
    assert spec.system == System(A2, C3, name="ss")
    npz = tmp_path / "ss.npz"
    # one input saved as a vector; Ts unspecified
    np.savez(npz, A=np.array(A2), B=B.ravel(), C=np.array(C3), Ts=np.array(-1.0))
    with pytest.warns(UserWarning, match="B and Ts read and not used"):
        assert load_spec(npz, max_attacked=1).system.C.shape == (3, 2)


@pytest.mark.parametrize(
    ("extra", "key", "fragment"),
    [
        ({"Ts": 0.0}, "Ts", "continuous-time model"),
        ({"Ts": -2.0}, "Ts", "expected a sampling time > 0"),
        ({"Ts": np.array([0.1, 0.2])}, "Ts", "expected a sampling time"),
        ({"B": np.zeros((3, 1))}, "B", "expected 2 rows (those of A)"),
        ({"D": np.zeros((2, 1))}, "D", "expected 3 rows (those of C)"),
        ({"B": np.zeros((2, 1)), "D": np.zeros((3, 2))}, "D", "expected the columns of B (1)"),
    ],
)
def test_mat_state_space_save_with_wrong_matrices(tmp_path, extra, key, fragment):
    path = tmp_path / "ss.mat"
    scipy.io.savemat(path, {"A": np.array(A2), "C": np.array(C3), **extra})
    expect_error(path, fragment, key=key, max_attacked=1)


def test_mat_state_space_object_is_refused_with_the_way_out(tmp_path):
    from scipy.io.matlab import MatlabObject

    model = MatlabObject(np.zeros((1, 1), dtype=[("a", object)]), classname="ss")
    model[0, 0]["a"] = np.eye(2)
    path = tmp_path / "sys.mat"
    scipy.io.savemat(path, {"sys": model})
    expect_error(path, "ssdata(sys)", max_attacked=1)


def test_mat_complex_matrix(tmp_path):
    path = tmp_path / "plant.mat"
    scipy.io.savemat(path, {"A": np.array(A2) * (1 + 1j), "C": np.array(C3)})
    expect_error(path, "complex", key="system.A", max_attacked=1)


@pytest.mark.parametrize("content", [b"", b"definitely not a MATLAB file " * 8])
def test_mat_corrupt(tmp_path, content):
    path = tmp_path / "broken.mat"
    path.write_bytes(content)
    expect_error(path, max_attacked=1)


# ---------------------------------------------------------------------------
# observer section
# ---------------------------------------------------------------------------


def observer_spec(observer: Any, **kwargs: Any) -> Spec:
    return spec_from_dict(base(observer=observer), **kwargs)


@pytest.mark.parametrize(
    "observer, expected",
    [
        ({"kind": "luenberger"}, {"kind": "luenberger", "gain": "deadbeat"}),
        ({"kind": "luenberger", "gain": "pinv"}, {"kind": "luenberger", "gain": "pinv"}),
        (
            {"kind": "luenberger", "gain": "place", "poles": [0.1, -0.2]},
            {"kind": "luenberger", "gain": "place", "poles": [0.1 + 0j, -0.2 + 0j]},
        ),
        (
            {"kind": "luenberger", "gain": "place", "poles": [[0.1, 0.2], [0.1, -0.2]]},
            {"kind": "luenberger", "gain": "place", "poles": [0.1 + 0.2j, 0.1 - 0.2j]},
        ),
        ({"kind": "ogd", "step": 0.1}, {"kind": "ogd", "gain": "ogd", "step": 0.1}),
        ({"kind": "ogd", "gain": "ogd", "step": 2}, {"kind": "ogd", "gain": "ogd", "step": 2.0}),
        (
            {"kind": "sso", "step": 0.5, "threshold": 0.1},
            {
                "kind": "sso",
                "step": 0.5,
                "threshold": 0.1,
                "shrink": 1.0,
                "window": 1,
                "inner_steps": 1,
            },
        ),
        (
            {
                "kind": "sso",
                "step": 0.5,
                "threshold": 0.1,
                "shrink": 1,
                "window": 3,
                "inner_steps": 4,
            },
            {
                "kind": "sso",
                "step": 0.5,
                "threshold": 0.1,
                "shrink": 1.0,
                "window": 3,
                "inner_steps": 4,
            },
        ),
        (
            {"kind": "dsso", "step": 0.7, "threshold": 0.1},
            {"kind": "dsso", "gain": "deadbeat", "step": 0.7, "threshold": 0.1, "shrink": 1.0},
        ),
        (
            {"kind": "dsso", "gain": "pinv", "step": 0.7, "threshold": 0.1, "shrink": 1.0},
            {"kind": "dsso", "gain": "pinv", "step": 0.7, "threshold": 0.1, "shrink": 1.0},
        ),
        (
            {"kind": "dsso", "gain": "place", "poles": [0.0, 0.5], "step": 0.7, "threshold": 0.1},
            {
                "kind": "dsso",
                "gain": "place",
                "poles": [0j, 0.5 + 0j],
                "step": 0.7,
                "threshold": 0.1,
                "shrink": 1.0,
            },
        ),
        (
            {"kind": "elastic_net", "step": 0.5, "threshold": 0.1, "shrink": 0.9},
            {
                "kind": "elastic_net",
                "gain": "deadbeat",
                "step": 0.5,
                "threshold": 0.1,
                "shrink": 0.9,
            },
        ),
        (
            {"kind": "elastic_net", "gain": "ogd", "step": 0.5, "threshold": 0.1, "shrink": 0.5},
            {"kind": "elastic_net", "gain": "ogd", "step": 0.5, "threshold": 0.1, "shrink": 0.5},
        ),
    ],
)
def test_valid_observers(observer, expected):
    spec = observer_spec(observer)
    assert dict(spec.observer) == expected


@pytest.mark.parametrize("kind", OBSERVER_KINDS)
def test_every_observer_kind_loads_from_toml(tmp_path, kind):
    observer: dict[str, Any] = {"kind": kind}
    if kind != "luenberger":
        observer["step"] = 0.25
    if kind in ("sso", "dsso", "elastic_net"):
        observer["threshold"] = 0.05
    if kind == "elastic_net":
        observer["shrink"] = 0.8
    spec = load_spec(write_spec(tmp_path, base(observer=observer)))
    assert spec.observer["kind"] == kind


def test_elastic_net_with_L2():
    L2 = np.diag([1.0, 2.0, 3.0]).tolist()
    spec = observer_spec(
        {"kind": "elastic_net", "step": 0.5, "threshold": 0.1, "shrink": 0.9, "L2": L2}
    )
    np.testing.assert_array_equal(spec.observer["L2"], L2)
    assert spec.observer["L2"].shape == (3, 3)


@pytest.mark.parametrize(
    "observer",
    [
        {"kind": "luenberger"},
        {"kind": "dsso", "step": 0.5, "threshold": 0.1},
        {"kind": "elastic_net", "step": 0.5, "threshold": 0.1, "shrink": 0.9},
    ],
)
def test_explicit_gain_matrix_is_accepted(observer):
    L = [[0.5, 0.0, 0.25], [0.0, 0.5, 0.25]]  # n x p = 2 x 3
    spec = observer_spec({**observer, "gain": L})
    gain = spec.observer["gain"]
    assert isinstance(gain, np.ndarray)
    assert gain.shape == (2, 3)
    np.testing.assert_array_equal(gain, L)
    assert "poles" not in spec.observer


def test_explicit_gain_matrix_from_toml(tmp_path):
    L = [[0.5, 0.0, 0.25], [0.0, 0.5, 0.25]]
    spec = load_spec(write_spec(tmp_path, base(observer={"kind": "luenberger", "gain": L})))
    np.testing.assert_array_equal(spec.observer["gain"], L)


@pytest.mark.parametrize(
    "observer, key, fragments",
    [
        ({"gain": "pinv"}, "observer.kind", ("missing",)),
        ({"kind": "kalman"}, "observer.kind", ("luenberger",)),
        ({"kind": "dso", "step": 1.0}, "observer.kind", ("did you mean",)),
        ({"kind": 3}, "observer.kind", ()),
        ({"kind": "luenberger", "gain": "bogus"}, "observer.gain", ("deadbeat",)),
        ({"kind": "luenberger", "gain": "ogd"}, "observer.gain", ()),
        ({"kind": "dsso", "gain": "ogd", "step": 0.5, "threshold": 0.1}, "observer.gain", ()),
        ({"kind": "ogd", "gain": "deadbeat", "step": 0.1}, "observer.gain", ("fixed",)),
        (
            {"kind": "ogd", "gain": [[1.0, 0, 0], [0, 1.0, 0]], "step": 0.1},
            "observer.gain",
            ("fixed",),
        ),
        (
            {"kind": "sso", "gain": "deadbeat", "step": 0.5, "threshold": 0.1},
            "observer.gain",
            ("unknown key",),
        ),
        # explicit gains must be n x p = 2 x 3
        (
            {"kind": "luenberger", "gain": [[1.0, 0.0], [0.0, 1.0]]},
            "observer.gain",
            ("columns", "expected 3"),
        ),
        (
            {"kind": "luenberger", "gain": [[1.0, 0.0, 0.0]]},
            "observer.gain",
            ("rows", "expected 2"),
        ),
        (
            {
                "kind": "dsso",
                "gain": [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]],
                "step": 0.5,
                "threshold": 0.1,
            },
            "observer.gain",
            ("expected 2",),
        ),
        (
            {"kind": "luenberger", "gain": [[1.0, 0.0, float("nan")], [0.0, 1.0, 0.0]]},
            "observer.gain",
            ("finite",),
        ),
        ({"kind": "luenberger", "gain": [1.0, 0.0]}, "observer.gain", ("2-D",)),
        # poles
        ({"kind": "luenberger", "gain": "place"}, "observer.poles", ("missing",)),
        (
            {"kind": "luenberger", "gain": "deadbeat", "poles": [0.1, 0.2]},
            "observer.poles",
            ("place",),
        ),
        ({"kind": "luenberger", "poles": [0.1, 0.2]}, "observer.poles", ("place",)),
        (
            {"kind": "luenberger", "gain": "place", "poles": [0.1]},
            "observer.poles",
            ("expected 2", "got 1"),
        ),
        (
            {"kind": "luenberger", "gain": "place", "poles": [0.1, 0.2, 0.3]},
            "observer.poles",
            ("expected 2", "got 3"),
        ),
        (
            {"kind": "luenberger", "gain": "place", "poles": [[0.1, 0.2], [0.1, 0.2]]},
            "observer.poles",
            ("conjugate",),
        ),
        (
            {"kind": "luenberger", "gain": "place", "poles": [[0.1, 0.2], 0.3]},
            "observer.poles",
            ("conjugate",),
        ),
        ({"kind": "luenberger", "gain": "place", "poles": ["a", 0.2]}, "observer.poles[0]", ()),
        (
            {"kind": "luenberger", "gain": "place", "poles": [0.1, [1, 2, 3]]},
            "observer.poles[1]",
            (),
        ),
        ({"kind": "luenberger", "gain": "place", "poles": [True, 0.2]}, "observer.poles[0]", ()),
        (
            {"kind": "luenberger", "gain": "place", "poles": [float("inf"), 0.2]},
            "observer.poles[0]",
            ("finite",),
        ),
        ({"kind": "luenberger", "gain": "place", "poles": 0.5}, "observer.poles", ()),
        (
            {"kind": "sso", "step": 0.5, "threshold": 0.1, "poles": [0.1, 0.2]},
            "observer.poles",
            ("unknown key",),
        ),
        ({"kind": "ogd", "step": 0.1, "poles": [0.1, 0.2]}, "observer.poles", ("unknown key",)),
        # step and threshold
        ({"kind": "ogd"}, "observer.step", ("missing",)),
        ({"kind": "sso", "threshold": 0.1}, "observer.step", ("missing",)),
        ({"kind": "dsso", "threshold": 0.1}, "observer.step", ("missing",)),
        ({"kind": "elastic_net", "threshold": 0.1, "shrink": 0.5}, "observer.step", ("missing",)),
        ({"kind": "ogd", "step": 0.0}, "observer.step", ("> 0",)),
        ({"kind": "ogd", "step": -1.0}, "observer.step", ("> 0",)),
        ({"kind": "ogd", "step": "big"}, "observer.step", ()),
        ({"kind": "ogd", "step": float("inf")}, "observer.step", ("finite",)),
        ({"kind": "luenberger", "step": 0.5}, "observer.step", ("unknown key",)),
        ({"kind": "sso", "step": 0.5}, "observer.threshold", ("missing",)),
        ({"kind": "dsso", "step": 0.5}, "observer.threshold", ("missing",)),
        ({"kind": "elastic_net", "step": 0.5, "shrink": 0.5}, "observer.threshold", ("missing",)),
        ({"kind": "dsso", "step": 0.5, "threshold": -0.1}, "observer.threshold", ("> 0",)),
        ({"kind": "ogd", "step": 0.5, "threshold": 0.1}, "observer.threshold", ("unknown key",)),
        # shrink
        (
            {"kind": "sso", "step": 0.5, "threshold": 0.1, "shrink": 0.5},
            "observer.shrink",
            ("elastic_net",),
        ),
        (
            {"kind": "dsso", "step": 0.5, "threshold": 0.1, "shrink": 0.99},
            "observer.shrink",
            ("elastic_net",),
        ),
        ({"kind": "dsso", "step": 0.5, "threshold": 0.1, "shrink": 2.0}, "observer.shrink", ()),
        ({"kind": "elastic_net", "step": 0.5, "threshold": 0.1}, "observer.shrink", ("missing",)),
        (
            {"kind": "elastic_net", "step": 0.5, "threshold": 0.1, "shrink": 1.0},
            "observer.shrink",
            ("< 1",),
        ),
        (
            {"kind": "elastic_net", "step": 0.5, "threshold": 0.1, "shrink": 0.0},
            "observer.shrink",
            ("> 0",),
        ),
        (
            {"kind": "elastic_net", "step": 0.5, "threshold": 0.1, "shrink": 1.5},
            "observer.shrink",
            (),
        ),
        (
            {"kind": "elastic_net", "step": 0.5, "threshold": 0.1, "shrink": -0.5},
            "observer.shrink",
            (),
        ),
        ({"kind": "luenberger", "shrink": 1.0}, "observer.shrink", ("unknown key",)),
        # L2
        (
            {
                "kind": "elastic_net",
                "step": 0.5,
                "threshold": 0.1,
                "shrink": 0.5,
                "L2": [[1.0, 0.0], [0.0, 1.0]],
            },
            "observer.L2",
            ("expected 3",),
        ),
        (
            {
                "kind": "elastic_net",
                "step": 0.5,
                "threshold": 0.1,
                "shrink": 0.5,
                "L2": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            },
            "observer.L2",
            ("rows", "expected 3"),
        ),
        (
            {"kind": "dsso", "step": 0.5, "threshold": 0.1, "L2": np.eye(3).tolist()},
            "observer.L2",
            ("unknown key",),
        ),
        # window and inner_steps: sso only
        (
            {"kind": "dsso", "step": 0.5, "threshold": 0.1, "window": 2},
            "observer.window",
            ("unknown key",),
        ),
        (
            {"kind": "elastic_net", "step": 0.5, "threshold": 0.1, "shrink": 0.5, "inner_steps": 2},
            "observer.inner_steps",
            ("unknown key",),
        ),
        ({"kind": "luenberger", "window": 2}, "observer.window", ("unknown key",)),
        ({"kind": "sso", "step": 0.5, "threshold": 0.1, "window": 0}, "observer.window", (">= 1",)),
        (
            {"kind": "sso", "step": 0.5, "threshold": 0.1, "window": 1.5},
            "observer.window",
            ("integer",),
        ),
        (
            {"kind": "sso", "step": 0.5, "threshold": 0.1, "inner_steps": 0},
            "observer.inner_steps",
            (">= 1",),
        ),
    ],
)
def test_bad_observers(observer, key, fragments):
    dict_error(base(observer=observer), key, *fragments)


@pytest.mark.parametrize(
    "observer, key",
    [
        ({"kind": "dsso", "step": 0.5, "threshold": 0.1, "shrink": 0.5}, "observer.shrink"),
        (
            {"kind": "luenberger", "gain": "place", "poles": [[0.5, 0.1], [0.5, 0.2]]},
            "observer.poles",
        ),
        ({"kind": "luenberger", "gain": [[1.0, 0.0], [0.0, 1.0]]}, "observer.gain"),
        ({"kind": "sso", "step": 0.5, "threshold": 0.1, "windw": 2}, "observer.windw"),
    ],
)
def test_bad_observers_in_files_name_the_file(tmp_path, observer, key):
    for fmt in FORMATS:
        expect_error(write_spec(tmp_path, base(observer=observer), fmt), key=key)


def test_every_kind_refuses_keys_of_other_kinds():
    # each kind's allowed keys (docs/architecture.md table); anything else is refused
    allowed = {
        "luenberger": {"kind", "gain", "poles"},
        "ogd": {"kind", "gain", "step"},
        "sso": {"kind", "step", "threshold", "shrink", "window", "inner_steps"},
        "dsso": {"kind", "gain", "poles", "step", "threshold", "shrink"},
        "elastic_net": {"kind", "gain", "poles", "step", "threshold", "shrink", "L2"},
    }
    every = set().union(*allowed.values())
    for kind, keys in allowed.items():
        for key in sorted(every - keys):
            observer = {"kind": kind, "step": 0.5, "threshold": 0.1, "shrink": 0.5, key: 1}
            observer = {k: v for k, v in observer.items() if k in keys or k == key}
            message = dict_error(base(observer=observer), f"observer.{key}")
            assert "unknown key" in message


# ---------------------------------------------------------------------------
# scenarios
# ---------------------------------------------------------------------------


def scenario_spec(*scenarios: dict[str, Any]) -> Spec:
    return spec_from_dict(base(scenario=list(scenarios)))


def test_scenario_defaults():
    spec = scenario_spec({"name": "c", "attack": "constant", "sensors": [0]})
    (scenario,) = spec.scenarios
    assert scenario["steps"] == 300
    assert scenario["runs"] == 50
    assert scenario["seed"] == 0
    assert scenario["noise"] == 0.0
    assert scenario["magnitude"] == (4.0, 5.0)
    assert SCENARIO_DEFAULTS == {
        "magnitude": (4.0, 5.0),
        "noise": 0.0,
        "steps": 300,
        "runs": 50,
        "seed": 0,
    }
    assert scenario == {
        "name": "c",
        "attack": "constant",
        "sensors": [0],
        "magnitude": (4.0, 5.0),
        "noise": 0.0,
        "steps": 300,
        "runs": 50,
        "seed": 0,
    }


def test_scenario_sensors_by_name_or_index():
    (scenario,) = scenario_spec({"name": "c", "attack": "constant", "sensors": ["s2", 0]}).scenarios
    assert scenario["sensors"] == [2, 0]  # kept as indices
    with pytest.raises(SpecError, match=r"scenario\[0\]\.sensors\[0\]'.*no sensor is named 'S1'"):
        scenario_spec({"name": "c", "attack": "constant", "sensors": ["S1"]})
    with pytest.raises(SpecError, match="did you mean 's1'"):
        scenario_spec({"name": "c", "attack": "constant", "sensors": ["s11"]})
    with pytest.raises(SpecError, match="repeated sensor indices"):
        scenario_spec({"name": "c", "attack": "constant", "sensors": ["s0", 0]})


def test_scenario_values_are_kept():
    spec = scenario_spec(
        {
            "name": "sw",
            "attack": "switching",
            "count": 2,
            "period": 40,
            "magnitude": [1, 2],
            "noise": 0.01,
            "steps": 100,
            "runs": 3,
            "seed": 7,
        }
    )
    (scenario,) = spec.scenarios
    assert scenario == {
        "name": "sw",
        "attack": "switching",
        "count": 2,
        "period": 40,
        "magnitude": (1.0, 2.0),
        "noise": 0.01,
        "steps": 100,
        "runs": 3,
        "seed": 7,
    }


@pytest.mark.parametrize(
    "scenario, expected",
    [
        ({"attack": "none"}, {}),
        ({"attack": "constant", "sensors": [2, 0]}, {"sensors": [2, 0]}),
        ({"attack": "constant", "count": 2}, {"count": 2}),
        ({"attack": "switching", "count": 1, "period": 10}, {"count": 1, "period": 10}),
        ({"attack": "sinusoidal", "sensors": [1], "period": 20}, {"sensors": [1], "period": 20}),
        ({"attack": "sinusoidal", "count": 3, "period": 20}, {"count": 3, "period": 20}),
        ({"attack": "random", "count": 1}, {"count": 1}),
        ({"attack": "stealthy"}, {}),
        ({"attack": "stealthy", "magnitude": 2.0}, {"magnitude": (2.0, 2.0)}),
    ],
)
def test_valid_scenarios(scenario, expected):
    (result,) = scenario_spec({"name": "s", **scenario}).scenarios
    assert result["attack"] == scenario["attack"]
    for key, value in expected.items():
        assert result[key] == value
    for key in ("sensors", "count", "period"):
        if key not in expected:
            assert key not in result


def test_every_attack_kind_is_covered():
    assert set(ATTACK_KINDS) == {
        "none",
        "constant",
        "switching",
        "sinusoidal",
        "random",
        "stealthy",
    }


@pytest.mark.parametrize(
    "magnitude, expected",
    [
        (3, (3.0, 3.0)),
        (0, (0.0, 0.0)),
        (2.5, (2.5, 2.5)),
        ([1, 2], (1.0, 2.0)),
        ([0.0, 0.0], (0.0, 0.0)),
        ([3, 3], (3.0, 3.0)),
    ],
)
def test_magnitude_forms(magnitude, expected):
    (result,) = scenario_spec(
        {"name": "s", "attack": "random", "count": 1, "magnitude": magnitude}
    ).scenarios
    assert result["magnitude"] == expected
    assert all(isinstance(x, float) for x in result["magnitude"])


def test_scenarios_keep_their_order_from_toml(tmp_path):
    data = base(
        scenario=[
            {"name": "one", "attack": "none"},
            {"name": "two", "attack": "random", "count": 1},
            {"name": "three", "attack": "stealthy"},
        ]
    )
    spec = load_spec(write_spec(tmp_path, data))
    assert [s["name"] for s in spec.scenarios] == ["one", "two", "three"]


def test_a_single_scenario_table_is_accepted(tmp_path):
    path = tmp_path / "single.toml"
    path.write_text(to_toml(BASE) + '\n[scenario]\nname = "only"\nattack = "none"\n')
    spec = load_spec(path)
    assert [s["name"] for s in spec.scenarios] == ["only"]


@pytest.mark.parametrize(
    "scenario, key, fragments",
    [
        ({"attack": "none"}, "scenario[0].name", ("missing",)),
        ({"name": "", "attack": "none"}, "scenario[0].name", ("non-empty",)),
        ({"name": 3, "attack": "none"}, "scenario[0].name", ()),
        ({"name": "s"}, "scenario[0].attack", ("missing",)),
        ({"name": "s", "attack": "bogus"}, "scenario[0].attack", ("stealthy",)),
        (
            {"name": "s", "attack": "constnat", "sensors": [0]},
            "scenario[0].attack",
            ("did you mean 'constant'",),
        ),
        # sensors XOR count for constant and sinusoidal
        ({"name": "s", "attack": "constant"}, "scenario[0].sensors", ("exactly one",)),
        (
            {"name": "s", "attack": "constant", "sensors": [0], "count": 1},
            "scenario[0].sensors",
            ("exactly one",),
        ),
        (
            {"name": "s", "attack": "sinusoidal", "period": 5},
            "scenario[0].sensors",
            ("exactly one",),
        ),
        (
            {"name": "s", "attack": "sinusoidal", "sensors": [0], "count": 1, "period": 5},
            "scenario[0].sensors",
            ("exactly one",),
        ),
        # count for switching and random
        ({"name": "s", "attack": "switching", "period": 5}, "scenario[0].count", ("missing",)),
        ({"name": "s", "attack": "random"}, "scenario[0].count", ("missing",)),
        (
            {"name": "s", "attack": "switching", "sensors": [0], "period": 5},
            "scenario[0].sensors",
            ("count",),
        ),
        ({"name": "s", "attack": "random", "sensors": [0]}, "scenario[0].sensors", ("count",)),
        ({"name": "s", "attack": "random", "count": 0}, "scenario[0].count", (">= 1",)),
        ({"name": "s", "attack": "random", "count": 4}, "scenario[0].count", ("<= 3",)),
        ({"name": "s", "attack": "constant", "count": 4}, "scenario[0].count", ("<= 3",)),
        ({"name": "s", "attack": "random", "count": 1.5}, "scenario[0].count", ("integer",)),
        # period
        ({"name": "s", "attack": "switching", "count": 1}, "scenario[0].period", ("missing",)),
        ({"name": "s", "attack": "sinusoidal", "sensors": [0]}, "scenario[0].period", ("missing",)),
        (
            {"name": "s", "attack": "switching", "count": 1, "period": 0},
            "scenario[0].period",
            (">= 1",),
        ),
        (
            {"name": "s", "attack": "constant", "sensors": [0], "period": 5},
            "scenario[0].period",
            ("only used",),
        ),
        (
            {"name": "s", "attack": "random", "count": 1, "period": 5},
            "scenario[0].period",
            ("only used",),
        ),
        ({"name": "s", "attack": "none", "period": 5}, "scenario[0].period", ("only used",)),
        ({"name": "s", "attack": "stealthy", "period": 5}, "scenario[0].period", ("only used",)),
        # sensors / count where they are not used
        ({"name": "s", "attack": "none", "sensors": [0]}, "scenario[0].sensors", ("not used",)),
        ({"name": "s", "attack": "none", "count": 1}, "scenario[0].count", ("not used",)),
        ({"name": "s", "attack": "stealthy", "sensors": [0]}, "scenario[0].sensors", ("witness",)),
        ({"name": "s", "attack": "stealthy", "count": 1}, "scenario[0].count", ("not used",)),
        # sensor indices
        (
            {"name": "s", "attack": "constant", "sensors": [3]},
            "scenario[0].sensors",
            ("out of range", "< 3"),
        ),
        (
            {"name": "s", "attack": "constant", "sensors": [0, 7]},
            "scenario[0].sensors",
            ("out of range",),
        ),
        ({"name": "s", "attack": "constant", "sensors": [-1]}, "scenario[0].sensors", (">= 0",)),
        (
            {"name": "s", "attack": "constant", "sensors": [1, 1]},
            "scenario[0].sensors",
            ("repeated",),
        ),
        (
            {"name": "s", "attack": "constant", "sensors": []},
            "scenario[0].sensors",
            ("at least one",),
        ),
        ({"name": "s", "attack": "constant", "sensors": 1}, "scenario[0].sensors", ()),
        ({"name": "s", "attack": "constant", "sensors": "0"}, "scenario[0].sensors", ()),
        (
            {"name": "s", "attack": "constant", "sensors": [0.5]},
            "scenario[0].sensors",
            ("integer",),
        ),
        (
            {"name": "s", "attack": "constant", "sensors": [True]},
            "scenario[0].sensors",
            ("integer",),
        ),
        # magnitude
        (
            {"name": "s", "attack": "random", "count": 1, "magnitude": [5.0, 4.0]},
            "scenario[0].magnitude",
            ("low <= high",),
        ),
        (
            {"name": "s", "attack": "random", "count": 1, "magnitude": [-1.0, 4.0]},
            "scenario[0].magnitude",
            ("0 <= low",),
        ),
        (
            {"name": "s", "attack": "random", "count": 1, "magnitude": -2.0},
            "scenario[0].magnitude",
            ("0 <= low",),
        ),
        (
            {"name": "s", "attack": "random", "count": 1, "magnitude": [1.0, 2.0, 3.0]},
            "scenario[0].magnitude",
            (),
        ),
        (
            {"name": "s", "attack": "random", "count": 1, "magnitude": [1.0]},
            "scenario[0].magnitude",
            (),
        ),
        (
            {"name": "s", "attack": "random", "count": 1, "magnitude": "big"},
            "scenario[0].magnitude",
            (),
        ),
        (
            {"name": "s", "attack": "random", "count": 1, "magnitude": True},
            "scenario[0].magnitude",
            (),
        ),
        (
            {"name": "s", "attack": "random", "count": 1, "magnitude": [1.0, float("inf")]},
            "scenario[0].magnitude",
            ("finite",),
        ),
        ({"name": "s", "attack": "none", "magnitude": 1.0}, "scenario[0].magnitude", ("not used",)),
        # noise, steps, runs, seed
        ({"name": "s", "attack": "none", "noise": -0.1}, "scenario[0].noise", (">= 0",)),
        ({"name": "s", "attack": "none", "noise": "x"}, "scenario[0].noise", ()),
        ({"name": "s", "attack": "none", "noise": float("nan")}, "scenario[0].noise", ("finite",)),
        ({"name": "s", "attack": "none", "steps": 0}, "scenario[0].steps", (">= 1",)),
        ({"name": "s", "attack": "none", "steps": 2.5}, "scenario[0].steps", ("integer",)),
        ({"name": "s", "attack": "none", "runs": 0}, "scenario[0].runs", (">= 1",)),
        ({"name": "s", "attack": "none", "runs": True}, "scenario[0].runs", ("integer",)),
        ({"name": "s", "attack": "none", "seed": -1}, "scenario[0].seed", (">= 0",)),
    ],
)
def test_bad_scenarios(scenario, key, fragments):
    dict_error(base(scenario=[scenario]), key, *fragments)


def test_error_names_the_index_of_the_bad_scenario():
    message = dict_error(
        base(
            scenario=[
                {"name": "ok", "attack": "none"},
                {"name": "bad", "attack": "constant", "sensors": [9]},
            ]
        ),
        "scenario[1].sensors",
    )
    assert "scenario[0]" not in message


def test_duplicate_scenario_names():
    dict_error(
        base(
            scenario=[
                {"name": "x", "attack": "none"},
                {"name": "y", "attack": "stealthy"},
                {"name": "x", "attack": "random", "count": 1},
            ]
        ),
        "scenario[2].name",
        "duplicate",
        "'x'",
    )


@pytest.mark.parametrize("fmt", FORMATS)
def test_bad_scenarios_in_files_name_the_file(tmp_path, fmt):
    data = base(scenario=[{"name": "a", "attack": "none"}, {"name": "a", "attack": "none"}])
    expect_error(write_spec(tmp_path, data, fmt), "duplicate", key="scenario[1].name")
    data = base(scenario=[{"name": "a", "attack": "switching", "count": 1}])
    expect_error(write_spec(tmp_path, data, fmt), "missing", key="scenario[0].period")
    data = base(scenario=[{"name": "a", "attack": "constant", "sensors": [0, 3]}])
    expect_error(write_spec(tmp_path, data, fmt), "out of range", key="scenario[0].sensors")


# ---------------------------------------------------------------------------
# spec_from_dict
# ---------------------------------------------------------------------------


def test_spec_from_dict_builds_the_system():
    spec = spec_from_dict(base())
    assert isinstance(spec, Spec)
    assert spec.system == System(A2, C3, sensors=["s0", "s1", "s2"], name="demo")
    assert spec.system == System(
        np.array(A2), np.array(C3, dtype=float), sensors=("s0", "s1", "s2"), name="demo"
    )
    assert spec.system != System(A2, C3, name="demo")  # different sensor names
    assert (spec.name, spec.max_attacked, spec.horizon) == ("demo", 1, 2)
    assert spec.source == "<dict>"
    assert spec.sha256 is None


def test_spec_from_dict_with_numpy_arrays():
    data = base(system={"A": np.array(A2), "C": np.array(C3)})
    spec = spec_from_dict(data)
    assert spec.system == System(A2, C3, name="demo")


def test_spec_from_dict_docstring_example():
    spec = spec_from_dict(
        {
            "name": "demo",
            "system": {"A": [[1.0]], "C": [[1.0], [2.0]]},
            "attack": {"max_attacked": 0},
        }
    )
    assert (spec.system.p, spec.horizon) == (2, 1)


def test_spec_from_dict_does_not_modify_its_input():
    data = base(
        observer={"kind": "dsso", "step": 0.5, "threshold": 0.1},
        scenario=[{"name": "a", "attack": "constant", "sensors": [0]}],
    )
    before = copy.deepcopy(data)
    spec_from_dict(data)
    assert data == before


def test_spec_from_dict_options():
    data = base()
    del data["name"]
    dict_error(data, "name", "missing")
    spec = spec_from_dict(
        data, default_name="fallback", max_attacked=0, horizon=4, source="somewhere", sha256="abc"
    )
    assert (spec.name, spec.max_attacked, spec.horizon) == ("fallback", 0, 4)
    assert (spec.source, spec.sha256) == ("somewhere", "abc")


def test_spec_from_dict_errors_use_the_source():
    dict_error(base(attack={"max_attacked": -1}), "attack.max_attacked", source="my/design.toml")


@pytest.mark.parametrize("data", [[1, 2], "spec", None, 3])
def test_spec_from_dict_refuses_non_mappings(data):
    with pytest.raises(SpecError):
        spec_from_dict(data)


def test_spec_from_dict_wrong_column_count_message():
    message = dict_error(base(system={"A": A2, "C": [[1.0, 0.0, 0.0]]}), "system.C")
    assert "wrong number of columns: expected 2" in message
    assert "got 3" in message


def test_spec_error_messages_keep_the_index_of_the_bad_entry():
    message = dict_error(
        base(scenario=[{"name": "s", "attack": "constant", "sensors": [0, 5]}]),
        "scenario[0].sensors",
    )
    assert "sensors[1] = 5" in message
    message = dict_error(base(system={"A": A2, "C": [[1.0, 0.0], [1.0]]}), "system.C")
    assert "row 1" in message


# ---------------------------------------------------------------------------
# System
# ---------------------------------------------------------------------------


def test_system_basic_attributes():
    system = System(A2, C3)
    assert (system.n, system.p) == (2, 3)
    assert system.sensors == ("y1", "y2", "y3")
    assert system.name == "system"
    assert system.A.dtype == np.float64 and system.C.dtype == np.float64
    assert system.A.flags.c_contiguous and system.C.flags.c_contiguous
    assert system.to_dict() == {"name": "system", "n": 2, "p": 3, "sensors": ["y1", "y2", "y3"]}
    assert "n=2" in repr(system) and "p=3" in repr(system)


def test_system_wrong_column_count_message():
    with pytest.raises(ValueError, match=r"C has the wrong number of columns: expected 2") as info:
        System(A2, [[1.0, 0.0, 0.0]])
    assert "got 3" in str(info.value)


def test_system_non_square_A_message():
    with pytest.raises(ValueError, match=r"A must be square") as info:
        System([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], C3)
    assert "(2, 3)" in str(info.value)


@pytest.mark.parametrize(
    "A, C, exc, pattern",
    [
        ([[1.0, np.nan], [0.0, 1.0]], C3, ValueError, r"A must be finite"),
        (A2, [[1.0, np.inf], [0, 1]], ValueError, r"C must be finite.*index \(0, 1\)"),
        (np.array(A2) + 1j, C3, TypeError, r"A must be real"),
        (A2, [[1.0, 1j]], TypeError, r"C must be real"),
        ([[1.0, "a"], [0.0, 1.0]], C3, TypeError, r"A must contain real numbers"),
        (A2, [[True, False]], TypeError, r"C must contain real numbers"),
        (A2, np.ones((2, 2), dtype=bool), TypeError, r"C .*boolean"),
        (np.array([["a", "b"], ["c", "d"]]), C3, TypeError, r"A must be a numeric array"),
        ([[1.0, 0.0], [0.0]], C3, ValueError, r"A is ragged"),
        (A2, [[1.0, 0.0], [1.0]], ValueError, r"C is ragged"),
        (A2, np.zeros((0, 2)), ValueError, r"C must not be empty"),
        (np.zeros((0, 0)), np.zeros((0, 0)), ValueError, r"A must not be empty"),
        ([1.0, 2.0], C3, ValueError, r"A must be a 2-D array.*\(2,\)"),
        (A2, [1.0, 0.0], ValueError, r"C must be a 2-D array"),
        (A2, [[1.0], [0.0]], ValueError, r"C has the wrong number of columns: expected 2.*got 1"),
        (None, C3, TypeError, r"A must be a numeric array"),
    ],
)
def test_system_bad_matrices(A, C, exc, pattern):
    with pytest.raises(exc, match=pattern):
        System(A, C)


@pytest.mark.parametrize(
    "sensors, exc, pattern",
    [
        (["a", "b"], ValueError, r"sensors has the wrong length: expected 3.*got 2"),
        (["a", "b", "a"], ValueError, r"sensors must be unique: 'a' names sensors 0 and 2"),
        ("abc", TypeError, r"sensors must be a list of names"),
        (["a", None, "c"], TypeError, r"sensors\[1\] must be a non-empty string"),
        (["a", "  ", "c"], TypeError, r"sensors\[1\] must be a non-empty string"),
        (3, TypeError, r"sensors must be a list"),
    ],
)
def test_system_bad_sensors(sensors, exc, pattern):
    with pytest.raises(exc, match=pattern):
        System(A2, C3, sensors=sensors)


@pytest.mark.parametrize("name", [3, "", "   ", None])
def test_system_bad_name(name):
    with pytest.raises(TypeError, match="name"):
        System(A2, C3, name=name)


def test_system_arrays_are_read_only_copies():
    A = np.array(A2)
    C = np.array(C3, dtype=float)
    system = System(A, C)
    for matrix in (system.A, system.C):
        assert not matrix.flags.writeable
        with pytest.raises(ValueError):
            matrix[0, 0] = 42.0
    A[0, 0] = 99.0  # the caller's arrays stay theirs
    C[0, 0] = 99.0
    assert system.A[0, 0] == 1.0
    assert system.C[0, 0] == 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        system.A = np.eye(2)  # type: ignore[misc]


def test_system_equality_and_hash():
    first = System(A2, C3, name="x")
    assert first == System(np.array(A2), np.array(C3), name="x")
    assert first != System(A2, C3, name="y")
    assert first != System(A2, [[1, 0], [0, 1], [1, 2]], name="x")
    assert first != System(A2, C3, sensors=["a", "b", "c"], name="x")
    assert first != "not a system"
    with pytest.raises(TypeError):
        hash(first)


def _reference_obsv(A: np.ndarray, C: np.ndarray, h: int) -> np.ndarray:
    return np.vstack([C @ np.linalg.matrix_power(A, k) for k in range(h)])


@pytest.mark.parametrize("seed", range(4))
def test_observability_matrix_matches_numpy_and_control(seed):
    rng = np.random.default_rng(seed)
    n, p = int(rng.integers(1, 6)), int(rng.integers(1, 7))
    A = rng.standard_normal((n, n))
    C = rng.standard_normal((p, n))
    system = System(A, C)
    for h in range(1, n + 3):
        O = system.observability_matrix(h)
        assert O.shape == (p * h, n)
        np.testing.assert_allclose(O, _reference_obsv(A, C, h), rtol=1e-12, atol=1e-12)
    expected = np.asarray(control.obsv(A, C))
    np.testing.assert_allclose(system.observability_matrix(n), expected, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(system.observability_matrix(), expected, rtol=1e-12, atol=1e-12)


def test_observability_matrix_of_the_ugv():
    spec = load_spec(example_path("ugv"))
    A, C = np.asarray(spec.system.A), np.asarray(spec.system.C)
    np.testing.assert_allclose(spec.system.observability_matrix(2), np.asarray(control.obsv(A, C)))
    np.testing.assert_allclose(spec.system.observability_matrix(5), _reference_obsv(A, C, 5))


@pytest.mark.parametrize("h", [1, 2, 3, 6])
def test_sensor_blocks(h):
    rng = np.random.default_rng(h)
    A = rng.standard_normal((3, 3))
    C = rng.standard_normal((4, 3))
    system = System(A, C)
    blocks = system.sensor_blocks(h)
    assert blocks.shape == (4, h, 3)
    for i in range(4):
        for k in range(h):
            np.testing.assert_allclose(
                blocks[i, k], C[i] @ np.linalg.matrix_power(A, k), rtol=1e-12, atol=1e-12
            )
    O = system.observability_matrix(h)
    for i in range(4):
        for k in range(h):
            np.testing.assert_array_equal(O[k * 4 + i], blocks[i, k])


def test_sensor_blocks_default_horizon_is_n():
    system = System(np.eye(3), np.ones((5, 3)))
    assert system.sensor_blocks().shape == (5, 3, 3)
    assert system.observability_matrix().shape == (15, 3)


@pytest.mark.parametrize(
    "horizon, exc",
    [(0, ValueError), (-1, ValueError), (True, TypeError), (1.5, TypeError), ("2", TypeError)],
)
def test_bad_horizon_for_system_methods(horizon, exc):
    system = System(A2, C3)
    with pytest.raises(exc, match="horizon"):
        system.observability_matrix(horizon)
    with pytest.raises(exc, match="horizon"):
        system.sensor_blocks(horizon)


def test_select_sensors():
    system = System(A2, C3, sensors=["a", "b", "c"], name="x")
    sub = system.select_sensors([2, 0])
    np.testing.assert_array_equal(sub.C, [[1, 1], [1, 0]])
    assert sub.sensors == ("c", "a")
    assert sub.name == "x"
    np.testing.assert_array_equal(sub.A, system.A)
    with pytest.raises(ValueError, match="out of range"):
        system.select_sensors([3])
    with pytest.raises(ValueError, match="repeated"):
        system.select_sensors([0, 0])
    with pytest.raises(ValueError, match="at least one"):
        system.select_sensors([])


def test_a_spec_written_back_reads_as_itself_with_every_attack_kind(tmp_path):
    """spec_document + dumps round-trip every scenario kind (no attack takes no magnitude:
    the reader fills in the default and refuses one written)."""
    from ssecert.spec.write import dumps, spec_document

    data = {
        "name": "round-trip",
        "system": {"A": [[0.5, 0.1], [0.0, 0.4]], "C": [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]},
        "attack": {"max_attacked": 1},
        "scenario": [{"name": kind, "attack": kind} for kind in ("none", "stealthy")]
        + [{"name": "constant", "attack": "constant", "sensors": [0], "magnitude": 2.0}],
    }
    spec = spec_from_dict(data)
    path = tmp_path / "spec.toml"
    path.write_text(dumps(spec_document(spec)))
    again = load_spec(path)
    assert again.scenarios == spec.scenarios
    assert np.array_equal(again.system.A, spec.system.A)
