"""Fuzzing the spec loader: any document loads or raises SpecError, nothing else.

Hypothesis starts from the packaged examples' parsed TOML and mutates them
(deletes, renames and inserts keys, changes types and shapes, nests values
deeply, puts huge integers, non-finite floats, control characters and lone
surrogates anywhere), then hands the result to ``spec_from_dict`` and, written
as TOML and JSON (also with corrupted bytes), to ``load_spec``.  A TypeError,
KeyError, OverflowError, RecursionError, MemoryError or any other exception
escaping is a bug of the loader.

The CI profile of ``conftest.py`` (deterministic) keeps this to a few seconds;
``HYPOTHESIS_PROFILE=thorough`` runs many more examples, and more corrupted
.mat and .npz files.
"""

from __future__ import annotations

import copy
import json
import math
import os
import subprocess
import sys
import tomllib
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ssecert.examples import example_path, list_examples
from ssecert.spec import Spec, SpecError, load_spec, spec_from_dict

EXAMPLES = {name: tomllib.loads(example_path(name).read_text()) for name in list_examples()}
THOROUGH = os.environ.get("HYPOTHESIS_PROFILE") == "thorough"

# ---------------------------------------------------------------------------
# strategies
# ---------------------------------------------------------------------------

KEYS = [
    "name",
    "system",
    "A",
    "C",
    "sensors",
    "attack",
    "max_attacked",
    "horizon",
    "observer",
    "kind",
    "gain",
    "poles",
    "step",
    "threshold",
    "shrink",
    "L2",
    "window",
    "inner_steps",
    "scenario",
    "attack",
    "count",
    "magnitude",
    "period",
    "noise",
    "steps",
    "runs",
    "seed",
    "System",
    "max_attack",
    "horizn",
    "stpe",
    "sensor",
    "",
    " ",
    "a.b",
    "[x]",
]
WORDS = [
    "luenberger",
    "ogd",
    "sso",
    "dsso",
    "elastic_net",
    "deadbeat",
    "place",
    "pinv",
    "none",
    "constant",
    "switching",
    "sinusoidal",
    "random",
    "stealthy",
    "ugv",
]

integers = st.one_of(
    st.integers(-3, 40),
    st.integers(),
    st.sampled_from(
        [2**63 - 1, 2**63, -(2**63), -(2**63) - 1, 10**19, 10**300, -(10**400), 10**4299]
    ),
)
floats = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-300, 1e300, 1.5, 0.5, 1e308, 5e-324]),
)
texts = st.one_of(
    st.sampled_from(KEYS + WORDS),
    st.text(max_size=12),
    st.text(st.characters(codec=None, exclude_categories=()), max_size=6),  # surrogates too
    st.sampled_from(["\x00", "a\nb", "\x1b[31m", "\u202e", "\ud800", "y" * 300]),
)
scalars = st.one_of(st.none(), st.booleans(), integers, floats, texts)
values = st.recursive(
    scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=5),
        st.dictionaries(st.one_of(st.sampled_from(KEYS), st.text(max_size=6)), inner, max_size=4),
    ),
    max_leaves=12,
)


def _paths(node: Any, prefix: tuple = ()) -> list[tuple]:
    """Every path (sequence of keys / indices) into the document."""
    out = [prefix]
    if isinstance(node, dict):
        for key, value in node.items():
            out += _paths(value, prefix + (key,))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            out += _paths(value, prefix + (i,))
    return out


def _get(doc: Any, path: tuple) -> Any:
    for key in path:
        doc = doc[key]
    return doc


MUTATIONS = [
    "delete",
    "rename",
    "replace",
    "insert",
    "wrap",
    "unwrap",
    "nest_deep",
    "truncate",
    "append",
    "stringify",
    "to_dict",
    "huge_list",
    "duplicate_list",
]


@st.composite
def mutated(draw: Any) -> dict[str, Any]:
    """A packaged example with 1-4 random mutations."""
    doc = copy.deepcopy(EXAMPLES[draw(st.sampled_from(sorted(EXAMPLES)))])
    for _ in range(draw(st.integers(1, 4))):
        paths = _paths(doc)
        path = draw(st.sampled_from(paths))
        kind = draw(st.sampled_from(MUTATIONS))
        if not path:  # the document itself: only add a key
            doc[draw(st.sampled_from(KEYS))] = draw(values)
            continue
        parent, key = _get(doc, path[:-1]), path[-1]
        value = parent[key]
        if kind == "delete":
            del parent[key]
        elif kind == "rename" and isinstance(parent, dict):
            parent[draw(st.one_of(st.sampled_from(KEYS), texts))] = parent.pop(key)
        elif kind == "replace":
            parent[key] = draw(values)
        elif kind == "insert" and isinstance(value, dict):
            value[draw(st.one_of(st.sampled_from(KEYS), texts))] = draw(values)
        elif kind == "insert" and isinstance(value, list):
            value.insert(draw(st.integers(0, len(value))), draw(values))
        elif kind == "wrap":
            parent[key] = [value]
        elif kind == "unwrap" and isinstance(value, list) and value:
            parent[key] = value[0]
        elif kind == "nest_deep":
            for _ in range(draw(st.integers(10, 200))):  # deeper: rows of the matrix test
                value = [value]
            parent[key] = value
        elif kind == "truncate" and isinstance(value, list):
            parent[key] = value[: draw(st.integers(0, max(len(value) - 1, 0)))]
        elif kind == "append" and isinstance(value, list):
            value.append(copy.deepcopy(value[-1]) if value else draw(values))
        elif kind == "stringify":
            parent[key] = str(value)[:50]
        elif kind == "to_dict" and isinstance(value, list):
            parent[key] = {str(i): v for i, v in enumerate(value)}
        elif kind == "huge_list":
            parent[key] = [draw(scalars)] * draw(st.sampled_from([10_001, 30_000]))
        elif kind == "duplicate_list" and isinstance(value, list):
            parent[key] = value * draw(st.integers(2, 4))
        else:
            parent[key] = draw(values)
    return doc


# ---------------------------------------------------------------------------
# writing documents as files
# ---------------------------------------------------------------------------


def _toml_key(key: Any) -> str:
    return json.dumps(str(key))


def _toml(value: Any) -> str:
    if value is None:
        return '"None"'  # TOML has no null
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, int):
        return str(value) if abs(value) < 10**4000 else "1" + "0" * 4400
    if isinstance(value, str):
        return json.dumps(value)  # \uXXXX escapes; a lone surrogate makes invalid TOML
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml(v)}" for k, v in value.items()) + "}"
    raise TypeError(value)


def to_toml(doc: dict[str, Any]) -> str:
    return "".join(f"{_toml_key(k)} = {_toml(v)}\n" for k, v in doc.items())


def to_json(doc: dict[str, Any]) -> str:
    def big(value: Any) -> Any:  # json.dumps refuses ints beyond the 4300-digit limit
        if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**4000:
            return float("inf")
        if isinstance(value, list):
            return [big(v) for v in value]
        if isinstance(value, dict):
            return {str(k): big(v) for k, v in value.items()}
        return value

    return json.dumps(big(doc))


def loads_or_spec_error(call: Any) -> None:
    """``call()`` returns a Spec or raises a one-line SpecError."""
    try:
        result = call()
    except SpecError as exc:
        message = str(exc)
        assert "\n" not in message and "\r" not in message, message
        assert len(message) < 2000, message[:200]
        message.encode("utf-8")  # printable
    else:
        assert isinstance(result, Spec)


# ---------------------------------------------------------------------------
# the properties
# ---------------------------------------------------------------------------

_LIMITED = settings(
    suppress_health_check=[
        HealthCheck.too_slow,
        HealthCheck.data_too_large,
        HealthCheck.large_base_example,
    ]
)


@_LIMITED
@given(doc=mutated())
def test_spec_from_dict_loads_or_refuses(doc):
    loads_or_spec_error(lambda: spec_from_dict(doc))


@_LIMITED
@given(doc=mutated(), override=st.one_of(st.none(), integers, floats, texts))
def test_overrides_load_or_refuse(doc, override):
    loads_or_spec_error(lambda: spec_from_dict(doc, max_attacked=override))
    loads_or_spec_error(lambda: spec_from_dict(doc, horizon=override))


@_LIMITED
@given(doc=mutated(), fmt=st.sampled_from(["toml", "json"]))
@pytest.mark.slow
def test_spec_files_load_or_refuse(tmp_path_factory, doc, fmt):
    path = tmp_path_factory.mktemp("fuzz") / f"spec.{fmt}"
    text = to_toml(doc) if fmt == "toml" else to_json(doc)
    path.write_bytes(text.encode("utf-8", "surrogatepass"))
    loads_or_spec_error(lambda: load_spec(path))


@_LIMITED
@given(
    name=st.sampled_from(sorted(EXAMPLES)),
    fmt=st.sampled_from(["toml", "json"]),
    edits=st.lists(
        st.tuples(st.integers(0, 10**6), st.binary(min_size=0, max_size=4)), min_size=1, max_size=6
    ),
)
def test_corrupted_spec_files_load_or_refuse(tmp_path_factory, name, fmt, edits):
    text = example_path(name).read_bytes() if fmt == "toml" else json.dumps(EXAMPLES[name]).encode()
    data = bytearray(text)
    for position, replacement in edits:
        at = position % (len(data) + 1)
        data[at : at + len(replacement)] = replacement
    path = tmp_path_factory.mktemp("corrupt") / f"spec.{fmt}"
    path.write_bytes(bytes(data))
    loads_or_spec_error(lambda: load_spec(path))


# ---------------------------------------------------------------------------
# corrupted .mat and .npz files, in a child process: a crash of a compiled
# reader would otherwise take the test session down with it
# ---------------------------------------------------------------------------

_CHILD = r"""
import io, sys, traceback
import numpy as np, scipy.io
from pathlib import Path
from ssecert.spec import Spec, SpecError, load_spec

folder, count = Path(sys.argv[1]), int(sys.argv[2])
outcomes = {"loaded": 0, "refused": 0}
for seed in range(count):
    rng = np.random.default_rng(seed)
    n, p = int(rng.integers(1, 5)), int(rng.integers(1, 5))
    cells = np.empty((1, p), dtype=object)
    cells[0, :] = [f"s{i}" for i in range(p)]
    arrays = {"A": rng.random((n, n)), "C": rng.random((p, n)), "sensors": cells}
    buffer = io.BytesIO()
    suffix = ".mat" if seed % 3 else ".npz"
    if suffix == ".mat":
        scipy.io.savemat(buffer, arrays, do_compression=bool(seed % 2))
    else:
        np.savez(buffer, A=arrays["A"], C=arrays["C"], sensors=np.array(cells[0].tolist()))
    raw = bytearray(buffer.getvalue())
    low = 0 if seed % 5 == 0 else min(128, len(raw) - 1)
    for at in rng.integers(low, len(raw), int(rng.integers(1, 10))):
        raw[at] = int(rng.integers(0, 256))
    if seed % 7 == 0:
        raw = raw[: int(rng.integers(0, len(raw)))]
    path = folder / f"plant{suffix}"
    path.write_bytes(bytes(raw))
    try:
        result = load_spec(path, max_attacked=1)
        assert isinstance(result, Spec)
        outcomes["loaded"] += 1
    except SpecError as exc:
        assert "\n" not in str(exc)
        outcomes["refused"] += 1
    except BaseException:
        print(f"seed {seed}: escaped", file=sys.stderr)
        traceback.print_exc()
        sys.exit(3)
print(outcomes)
"""


@pytest.mark.slow
def test_corrupted_mat_and_npz_files_never_crash(tmp_path):
    count = 5000 if THOROUGH else 400
    done = subprocess.run(
        [sys.executable, "-c", _CHILD, str(tmp_path), str(count)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, (
        f"exit status {done.returncode} (negative: killed by a signal, such as a segmentation "
        f"fault in a file reader)\n{done.stderr[-3000:]}"
    )
    assert "refused" in done.stdout


@pytest.mark.parametrize(
    "case", ["complex flag without an imaginary part", "unknown data type code", "data type code 8"]
)
def test_mat_files_that_crashed_scipy(tmp_path, case):
    """Files scipy.io.loadmat (1.17) crashed on with a segmentation fault."""
    script = r"""
import io, struct, sys
import numpy as np, scipy.io
from ssecert.spec import SpecError, load_spec
buffer = io.BytesIO()
scipy.io.savemat(buffer, {"A": np.eye(2), "C": np.ones((3, 2))})
raw = bytearray(buffer.getvalue())
case = sys.argv[2]
# A's record: tag at 128, flags tag at 136 and flags at 144, dims 152, name 168, data tag 176
if case.startswith("complex"):
    raw[145] |= 0x08  # the complex flag: SciPy then reads the next variable's tag as data
elif case.startswith("unknown"):
    raw[176] = 0x59  # a data type code past SciPy's table
else:
    raw[176] = 8  # a code with no entry in SciPy's table
open(sys.argv[1], "wb").write(bytes(raw))
try:
    load_spec(sys.argv[1], max_attacked=1)
except SpecError as exc:
    print(exc)
"""
    path = tmp_path / "crash.mat"
    done = subprocess.run(
        [sys.executable, "-c", script, str(path), case], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    assert "cannot read the .mat file" in done.stdout, done.stdout
