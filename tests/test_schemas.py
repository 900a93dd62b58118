"""The JSON Schemas of the spec file and the certificate: valid schemas, built from the reader's
own key lists, agreeing with the reader on what it accepts and refuses, and validating every
packaged spec and the certificates made from them."""

import copy
import json
import tomllib

import jsonschema
import pytest

import ssecert
from ssecert.examples import example_path, list_examples
from ssecert.observers import get_kind
from ssecert.report.json import certificate_json, certify_json
from ssecert.schemas import SCHEMAS, certificate_schema, spec_schema
from ssecert.spec import SpecError, spec_from_dict

SPEC = spec_schema()
CERTIFICATE = certificate_schema()


def _valid(document, schema=SPEC) -> bool:
    return jsonschema.Draft202012Validator(schema).is_valid(document)


def _read(document) -> bool:
    try:
        spec_from_dict(document, default_name="x")
    except SpecError:
        return False
    return True


def test_the_schemas_are_valid_json_schemas():
    for build in SCHEMAS.values():
        jsonschema.Draft202012Validator.check_schema(build())
    assert json.loads(json.dumps(CERTIFICATE)) == CERTIFICATE  # plain JSON


@pytest.mark.parametrize("name", list_examples())
def test_every_packaged_spec_validates(name):
    document = tomllib.loads(example_path(name).read_text(encoding="utf-8"))
    assert _valid(document)


def _base(kind: dict | None = None) -> dict:
    document = {
        "name": "demo",
        "system": {"A": [[0.5, 1.0], [0.0, 0.9]], "C": [[1, 0], [0, 1], [1, 1]]},
        "attack": {"max_attacked": 1},
        "scenario": [{"name": "c", "attack": "constant", "sensors": [0]}],
    }
    if kind is not None:
        document["observer"] = kind
    return document


OBSERVERS = [
    {"kind": "luenberger"},
    {"kind": "luenberger", "gain": "place", "poles": [0.1, 0.2]},
    {"kind": "ogd", "step": 0.1},
    {"kind": "sso", "step": 0.2, "threshold": 0.1, "window": 2},
    {"kind": "dsso", "step": 0.7, "threshold": 0.1},
    {"kind": "elastic_net", "step": 0.7, "threshold": 0.1, "shrink": 0.5},
]


def _changes():
    """(what, document): valid documents and single changes the reader refuses."""
    yield "valid", _base()
    named = _base()
    named["system"]["sensors"] = ["a", "b", "c"]
    named["scenario"][0]["sensors"] = ["b", 0]
    yield "sensors by name", named
    for observer in OBSERVERS:
        yield f"valid {observer}", _base(observer)
        kind = observer["kind"]
        yield f"{kind}: an unknown key", _base({**observer, "speed": 1})
        for key in get_kind(kind).required_keys:
            rest = {k: v for k, v in observer.items() if k != key}
            yield f"{kind}: {key} missing", _base(rest)
        if "step" in observer:
            yield f"{kind}: a negative step", _base({**observer, "step": -1.0})
            yield f"{kind}: a step as text", _base({**observer, "step": "0.1"})
    yield "an unknown kind", _base({"kind": "kalman"})
    yield "an unknown table", {**_base(), "extra": {}}
    yield "no system", {k: v for k, v in _base().items() if k != "system"}
    bad = _base()
    bad["system"]["B"] = [[1.0]]
    yield "an unknown system key", bad
    bad = _base()
    bad["system"]["A"] = [[0.5, True], [0.0, 0.9]]
    yield "a boolean entry", bad
    bad = _base()
    bad["attack"]["max_attacked"] = -1
    yield "a negative max_attacked", bad
    bad = _base()
    bad["attack"]["max_attacked"] = 1.5
    yield "a fractional max_attacked", bad
    bad = _base()
    bad["scenario"][0]["colour"] = "red"
    yield "an unknown scenario key", bad
    bad = _base()
    bad["scenario"][0]["attack"] = "switching"
    yield "switching without its period", bad
    bad = _base()
    bad["scenario"][0]["period"] = 10
    yield "a period for a constant attack", bad
    bad = _base()
    bad["scenario"][0] = {"name": "s", "attack": "stealthy", "sensors": [0]}
    yield "sensors for the stealthy attack", bad
    bad = _base()
    bad["name"] = "has space"
    yield "a name that cannot name a file", bad


@pytest.mark.parametrize(("what", "document"), list(_changes()), ids=lambda x: str(x)[:40])
def test_the_schema_and_the_reader_agree(what, document):
    assert _valid(copy.deepcopy(document)) == _read(copy.deepcopy(document)), what


def test_a_key_the_reader_takes_without_a_schema_fails_the_build(monkeypatch):
    kind = get_kind("ogd")
    monkeypatch.setattr(type(kind), "keys", (*kind.keys, "speed"))
    with pytest.raises(
        RuntimeError, match=r"the schema of ogd is out of date: missing \['speed'\]"
    ):
        spec_schema()


def test_a_kind_without_schemas_is_described_by_its_kind(monkeypatch):
    kind = get_kind("ogd")
    monkeypatch.setattr(type(kind), "key_schemas", None)
    (branch,) = [b for b in spec_schema()["properties"]["observer"]["oneOf"]
                 if b["properties"]["kind"] == {"const": "ogd"}]  # fmt: skip
    assert branch["required"] == ["kind"] and "additionalProperties" not in branch


@pytest.mark.parametrize("name", ["notes-example-1", "notes-example-2", "lasso-example-1"])
def test_certificates_validate(name):
    document = json.loads(certificate_json(ssecert.analyze(name)))
    assert _valid(document, CERTIFICATE)
    broken = copy.deepcopy(document)
    broken["checks"]["sparse_observability"]["max_removable"] = "many"
    assert not _valid(broken, CERTIFICATE)
    broken = copy.deepcopy(document)
    del broken["checks"]["observability"]["verdict"]
    assert not _valid(broken, CERTIFICATE)


@pytest.mark.slow
@pytest.mark.parametrize("name", list_examples())
def test_certify_documents_validate_with_their_spec(name):
    result = ssecert.certify(name, runs=2, steps=20, region=False)
    document = json.loads(certify_json(result))
    assert _valid(document, CERTIFICATE)
    document["spec"]["observer"] = {"kind": "kalman"}  # the spec inside is checked too
    assert not _valid(document, CERTIFICATE)


@pytest.mark.parametrize("name", ["spec", "certificate"])
def test_the_command_line_prints_each_schema(name, capsys):
    from ssecert.cli import main

    assert main(["schema", name]) == 0
    assert json.loads(capsys.readouterr().out) == SCHEMAS[name]()
