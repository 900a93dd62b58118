"""The ``ssecert`` command: exit statuses, table and JSON output, bad input.

docs/architecture.md, "Command line and JSON": 0 every required check holds, 1 one
fails, 2 bad input or usage (a one-line message on stderr, no traceback);
with ``--json -`` the JSON is the only thing on stdout.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import ssecert
from ssecert.cli import main
from ssecert.examples import example_path, list_examples

# ---------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """Run ``ssecert ARGV`` in-process; return (status, stdout, stderr)."""
    capsys.readouterr()  # drop anything printed before
    try:
        status = main(argv)
    except SystemExit as exc:  # argparse's --version / --help
        status = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    out, err = capsys.readouterr()
    return status, out, err


def run_process(args: list[str], cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    """Run ``python -m ssecert ARGS`` in a fresh interpreter."""
    env = dict(os.environ)
    env.pop("PYTHONWARNINGS", None)
    return subprocess.run(
        [sys.executable, "-m", "ssecert", *args],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=cwd,
        env=env,
    )


def assert_usage_error(status: int, out: str, err: str, *fragments: str) -> str:
    """Exit 2, one line on stderr starting 'ssecert: error:', nothing on stdout."""
    assert status == 2, (status, out, err)
    assert "Traceback" not in err
    assert err.startswith("ssecert: error: "), err
    assert err.endswith("\n")
    assert err.count("\n") == 1, f"expected a single line, got {err!r}"
    assert out == "", out
    for fragment in fragments:
        assert fragment in err, err
    return err


def strict_json(text: str) -> Any:
    """Parse strict JSON: NaN / Infinity literals are refused."""

    def refuse(token: str) -> Any:
        raise AssertionError(f"non-standard JSON literal {token!r}")

    return json.loads(text, parse_constant=refuse)


@pytest.fixture(scope="module")
def ugv_json() -> dict[str, Any]:
    """The ugv certificate via ``--json -`` (computed once)."""
    import io
    from contextlib import redirect_stderr, redirect_stdout

    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        status = main(["analyze", "ugv", "--json", "-"])
    assert status == 1, err.getvalue()
    return strict_json(out.getvalue())


def write_plant_npz(folder: Path, name: str = "plant.npz") -> Path:
    """An observable plant with n = 2 and p = 4 sensors."""
    path = folder / name
    np.savez(
        path,
        A=np.array([[1.0, 0.1], [0.0, 0.9]]),
        C=np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, -1.0]]),
    )
    return path


# ---------------------------------------------------------------------------
# analyze: exit statuses and the table
# ---------------------------------------------------------------------------


def test_analyze_ugv_fails(capsys):
    status, out, err = run(["analyze", "ugv"], capsys)
    assert status == 1
    assert "sparse_observability" in out
    assert "FAILS" in out
    assert "position" in out
    assert "observability" in out and "irrepresentable" in out
    assert "Traceback" not in err


@pytest.mark.parametrize(
    "name, status",
    [
        ("notes-example-3", 0),
        ("lasso-example-1", 0),
        ("notes-example-0", 1),
        ("notes-example-1", 1),
        ("notes-example-2", 1),
    ],
)
def test_analyze_examples_exit_status(capsys, name, status):
    got, out, err = run(["analyze", name], capsys)
    assert got == status, out + err
    assert name in out
    assert "sparse_observability" in out
    if status == 0:
        assert "FAILS" not in out.split("irrepresentable")[0]
    assert "Traceback" not in err


def test_analyze_by_file_path_equals_by_name(capsys):
    status_name, out_name, _ = run(["analyze", "ugv", "--json", "-"], capsys)
    status_path, out_path, _ = run(["analyze", str(example_path("ugv")), "--json", "-"], capsys)
    assert status_name == status_path == 1
    by_name, by_path = strict_json(out_name), strict_json(out_path)
    assert by_name["checks"]["sparse_observability"] == by_path["checks"]["sparse_observability"]
    assert by_name["system"] == by_path["system"]


def test_analyze_a_user_toml_file(tmp_path, capsys):
    path = tmp_path / "mine.toml"
    path.write_text(
        'name = "mine"\n[system]\nA = [[1.0, 0.0], [0.0, 0.5]]\n'
        "C = [[1, 0], [0, 1], [1, 1], [1, -1], [2, 1]]\n"
        "[attack]\nmax_attacked = 1\n"
    )
    status, out, err = run(["analyze", str(path), "--json", "-"], capsys)
    assert status == 0, err
    doc = strict_json(out)
    assert doc["system"] == {
        "name": "mine",
        "n": 2,
        "p": 5,
        "sensors": ["y1", "y2", "y3", "y4", "y5"],
    }
    assert doc["verdict"] == "holds"
    assert doc["checks"]["sparse_observability"]["max_removable"] >= 2


def test_max_attacked_override(capsys):
    # every triple of rows of notes-example-3 is independent: max_removable = 2,
    # so s = 1 is correctable and s = 2 is not
    status, out, _ = run(
        ["analyze", "notes-example-3", "--max-attacked", "2", "--json", "-"], capsys
    )
    assert status == 1
    doc = strict_json(out)
    sparse = doc["checks"]["sparse_observability"]
    assert sparse["max_attacked"] == 2
    assert sparse["max_removable"] == 2
    assert sparse["verdict"] == "fails"
    assert doc["meta"]["max_attacked"] == 2
    status, _, _ = run(["analyze", "notes-example-3", "--max-attacked", "0"], capsys)
    assert status == 0


def test_horizon_override(capsys):
    status, out, _ = run(["analyze", "ugv", "--horizon", "3", "--json", "-"], capsys)
    assert status == 1
    doc = strict_json(out)
    assert doc["meta"]["horizon"] == 3
    assert doc["checks"]["irrepresentable"]["horizon"] == 3
    witness = doc["checks"]["sparse_observability"]["witness"]
    assert np.asarray(witness["attack_a"]).shape == (3, 3)


@pytest.mark.parametrize("method", ["enumeration", "eigenspace", "auto"])
def test_methods_agree_on_ugv(capsys, method):
    status, out, _ = run(["analyze", "ugv", "--method", method, "--json", "-"], capsys)
    assert status == 1
    sparse = strict_json(out)["checks"]["sparse_observability"]
    assert sparse["max_removable"] == 0
    assert sparse["breaking_set"] == [0]
    if method != "auto":
        assert sparse["method"] == method


def test_max_sets_accepts_scientific_notation(capsys):
    status, out, err = run(["analyze", "notes-example-3", "--max-sets", "1e6"], capsys)
    assert status == 0, err


# ---------------------------------------------------------------------------
# --json -
# ---------------------------------------------------------------------------


def test_json_to_stdout_is_the_only_stdout(capsys):
    status, out, err = run(["analyze", "ugv", "--json", "-"], capsys)
    assert status == 1
    doc = strict_json(out)  # the whole of stdout is one JSON document
    assert isinstance(doc, dict)
    assert "sparse_observability" in err and "FAILS" in err  # the table went to stderr
    assert "check" in err
    assert "Traceback" not in err


def test_json_top_level(ugv_json):
    assert {"ssecert_version", "system", "verdict", "checks"} <= set(ugv_json)
    assert ugv_json["ssecert_version"] == ssecert.__version__
    assert ugv_json["system"] == {
        "name": "ugv",
        "n": 2,
        "p": 3,
        "sensors": ["position", "velocity-a", "velocity-b"],
    }
    assert ugv_json["verdict"] == "fails"
    assert {"observability", "sparse_observability", "irrepresentable"} <= set(ugv_json["checks"])
    for check_id, check in ugv_json["checks"].items():
        assert check_id == check_id.lower() and " " not in check_id
        assert check["verdict"] in ("holds", "fails", "inconclusive")


def test_json_observability(ugv_json):
    observability = ugv_json["checks"]["observability"]
    assert observability["verdict"] == "holds"
    assert observability["observability_index"] == 1
    assert observability["margin"] > 0


def test_json_sparse_observability_of_ugv(ugv_json):
    sparse = ugv_json["checks"]["sparse_observability"]
    assert sparse["verdict"] == "fails"
    assert sparse["max_removable"] == 0
    assert sparse["breaking_set"] == [0]
    assert sparse["max_correctable"] == 0
    assert sparse["max_removable_is_lower_bound"] is False
    assert isinstance(sparse["method"], str) and sparse["method"]


def test_json_witness_of_ugv(ugv_json):
    sparse = ugv_json["checks"]["sparse_observability"]
    witness = sparse["witness"]
    assert {"z", "sensors_a", "sensors_b", "attack_a", "attack_b"} <= set(witness)
    z = np.asarray(witness["z"], dtype=float)
    attack_a = np.asarray(witness["attack_a"], dtype=float)
    attack_b = np.asarray(witness["attack_b"], dtype=float)
    assert z.shape == (2,) and np.linalg.norm(z) > 0
    assert attack_a.shape == (2, 3)  # horizon x p
    assert attack_b.shape == (2, 3)
    # the breaking set has one sensor <= s: an undetectable attack, sensors_b empty
    assert sorted(witness["sensors_a"] + witness["sensors_b"]) == sparse["breaking_set"]
    assert witness["sensors_a"] == [0] and witness["sensors_b"] == []
    # the attacks live on their sensor sets ...
    others_a = [i for i in range(3) if i not in witness["sensors_a"]]
    others_b = [i for i in range(3) if i not in witness["sensors_b"]]
    assert np.all(attack_a[:, others_a] == 0)
    assert np.all(attack_b[:, others_b] == 0)
    # ... and make x0 and x0 + z indistinguishable:
    # C A^k x0 + attack_a(k) == C A^k (x0 + z) + attack_b(k)
    A = np.array([[1.0, 0.0099], [0.0, 0.9876]])
    C = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 1.0]])
    for k in range(2):
        np.testing.assert_allclose(
            attack_a[k] - attack_b[k], C @ np.linalg.matrix_power(A, k) @ z, atol=1e-12
        )


def test_json_irrepresentable_of_ugv_is_infinity(ugv_json):
    irrepresentable = ugv_json["checks"]["irrepresentable"]
    assert irrepresentable["value"] == "Infinity"
    assert irrepresentable["verdict"] == "fails"
    assert irrepresentable["horizon"] == 2


def test_json_irrepresentable_of_lasso_example(capsys):
    status, out, _ = run(["analyze", "lasso-example-1", "--json", "-"], capsys)
    assert status == 0
    doc = strict_json(out)
    assert doc["verdict"] == "holds"
    irrepresentable = doc["checks"]["irrepresentable"]
    assert irrepresentable["value"] == pytest.approx(0.5, abs=1e-9)
    assert irrepresentable["verdict"] == "holds"
    assert doc["system"]["n"] == 1 and doc["system"]["p"] == 3


def test_json_verdict_follows_the_exit_status(capsys):
    for name, status in (("notes-example-3", 0), ("notes-example-0", 1)):
        got, out, _ = run(["analyze", name, "--json", "-"], capsys)
        assert got == status
        assert strict_json(out)["verdict"] == {0: "holds", 1: "fails"}[status]


# ---------------------------------------------------------------------------
# --json PATH
# ---------------------------------------------------------------------------


def test_json_to_a_file(tmp_path, capsys):
    target = tmp_path / "ugv.json"
    status, out, err = run(["analyze", "ugv", "--json", str(target)], capsys)
    assert status == 1
    assert target.is_file()
    doc = strict_json(target.read_text())
    assert doc["system"]["name"] == "ugv"
    assert doc["checks"]["sparse_observability"]["breaking_set"] == [0]
    assert "sparse_observability" in out  # the table stays on stdout
    assert str(target) in out
    leftovers = [name for name in os.listdir(tmp_path) if name.endswith(".tmp")]
    assert leftovers == []
    assert os.listdir(tmp_path) == ["ugv.json"]


def test_json_file_is_replaced(tmp_path, capsys):
    target = tmp_path / "out.json"
    target.write_text("old content")
    status, _, _ = run(["analyze", "lasso-example-1", "--json", str(target)], capsys)
    assert status == 0
    assert strict_json(target.read_text())["system"]["name"] == "lasso-example-1"
    assert sorted(os.listdir(tmp_path)) == ["out.json"]


def test_json_into_a_missing_folder(tmp_path, capsys):
    target = tmp_path / "no" / "such" / "folder" / "out.json"
    status, out, err = run(["analyze", "ugv", "--json", str(target)], capsys)
    assert_usage_error(status, out, err, "does not exist")
    assert not (tmp_path / "no").exists()


def test_json_onto_a_folder(tmp_path, capsys):
    status, out, err = run(["analyze", "ugv", "--json", str(tmp_path)], capsys)
    assert_usage_error(status, out, err, str(tmp_path))
    assert os.listdir(tmp_path) == []


def test_no_output_replaces_the_spec_or_another_output(tmp_path, capsys, monkeypatch):
    """The certificate written over the spec it certifies (``certify plant.json --out .``,
    ``analyze g.json --json g.json``), or the .mat over the JSON: refused before any work,
    every file as it was."""
    monkeypatch.chdir(tmp_path)
    spec = tmp_path / "plant.json"
    text = json.dumps(
        {"system": {"A": [[0.5]], "C": [[1.0], [1.0], [1.0]]}, "attack": {"max_attacked": 1}}
    )
    spec.write_text(text)
    for argv, option in (
        (["certify", "plant.json", "--out", ".", "--no-sim"], "--out ."),
        (["analyze", "plant.json", "--json", "plant.json"], "--json"),
        (["analyze", "plant.json", "--json", "./plant.json"], "--json"),
        (["simulate", "plant.json", "--json", "plant.json"], "--json"),
        (["analyze", "plant.json", "--json", "same.x", "--mat", "same.x"], "--mat"),
    ):
        status, out, err = run(argv, capsys)
        assert_usage_error(status, out, err, option)
        assert spec.read_text() == text and sorted(os.listdir(tmp_path)) == ["plant.json"]


# ---------------------------------------------------------------------------
# bad input: exit 2, one line on stderr, no traceback
# ---------------------------------------------------------------------------


def test_unknown_example_name(capsys):
    status, out, err = run(["analyze", "no-such-example"], capsys)
    assert_usage_error(status, out, err, "no-such-example", "ugv")


def test_missing_spec_file(tmp_path, capsys):
    missing = tmp_path / "missing.toml"
    status, out, err = run(["analyze", str(missing)], capsys)
    assert_usage_error(status, out, err, str(missing), "no such file")


def test_bad_toml_file(tmp_path, capsys):
    path = tmp_path / "broken.toml"
    path.write_text('name = "x"\n[system\nA = [[1.0]]\n')
    status, out, err = run(["analyze", str(path)], capsys)
    assert_usage_error(status, out, err, str(path), "invalid TOML")


def test_spec_with_an_unknown_key(tmp_path, capsys):
    path = tmp_path / "typo.toml"
    path.write_text(
        'name = "x"\n[system]\nA = [[1.0]]\nC = [[1.0], [2.0]]\n[attack]\nmax_atacked = 1\n'
    )
    status, out, err = run(["analyze", str(path)], capsys)
    assert_usage_error(
        status, out, err, str(path), "attack.max_atacked", "did you mean 'max_attacked'"
    )


def test_spec_with_nan(tmp_path, capsys):
    path = tmp_path / "nan.json"
    path.write_text(
        '{"name": "x", "system": {"A": [[NaN]], "C": [[1.0]]}, "attack": {"max_attacked": 0}}'
    )
    status, out, err = run(["analyze", str(path), "--json", "-"], capsys)
    assert_usage_error(status, out, err, str(path), "system.A", "finite")


def test_spec_that_is_a_folder(tmp_path, capsys):
    folder = tmp_path / "specs.toml"
    folder.mkdir()
    status, out, err = run(["analyze", str(folder)], capsys)
    assert_usage_error(status, out, err, str(folder))


@pytest.mark.parametrize(
    "argv, fragments",
    [
        (["analyze", "ugv", "--max-attacked", "-1"], ("--max-attacked",)),
        (["analyze", "ugv", "--max-attacked", "one"], ("--max-attacked",)),
        (["analyze", "ugv", "--max-attacked", "1.5"], ("--max-attacked",)),
        (["analyze", "ugv", "--horizon", "0"], ("--horizon",)),
        (["analyze", "ugv", "--horizon", "-2"], ("--horizon",)),
        (["analyze", "ugv", "--horizon", "1.5e0"], ("--horizon",)),
        (["analyze", "ugv", "--horizon", "two"], ("--horizon",)),
        (["analyze", "ugv", "--max-sets", "0"], ("--max-sets",)),
        (["analyze", "ugv", "--max-sets", "1e400"], ("--max-sets",)),
        (["analyze", "ugv", "--max-sets", "5.5e0"], ("--max-sets",)),
        (["analyze", "ugv", "--max-sets", "nan"], ("--max-sets",)),
        (["analyze", "ugv", "--seed", "-3"], ("--seed",)),
        (["analyze", "ugv", "--method", "bogus"], ("--method", "bogus")),
        ([], ()),
        (["--bogus"], ("--bogus",)),
        (["analyze", "ugv", "--bogus"], ("--bogus",)),
        (["analyze"], ()),
        (["analyze", "ugv", "--json"], ("--json",)),
        (["frobnicate"], ("frobnicate",)),
        (["examples", "no-such-example"], ("no-such-example",)),
    ],
)
def test_bad_command_lines(capsys, argv, fragments):
    status, out, err = run(argv, capsys)
    assert_usage_error(status, out, err, *fragments)


def test_no_command_mentions_the_commands(capsys):
    status, out, err = run([], capsys)
    assert_usage_error(status, out, err)
    assert "analyze" in err


# ---------------------------------------------------------------------------
# .npz and .mat systems
# ---------------------------------------------------------------------------


def test_npz_needs_max_attacked(tmp_path, capsys):
    path = write_plant_npz(tmp_path)
    status, out, err = run(["analyze", str(path)], capsys)
    assert_usage_error(status, out, err, str(path), "--max-attacked")


def test_npz_with_max_attacked_runs(tmp_path, capsys):
    path = write_plant_npz(tmp_path)
    status, out, err = run(["analyze", str(path), "--max-attacked", "1"], capsys)
    assert status in (0, 1), err
    assert "sparse_observability" in out
    assert "Traceback" not in err
    status, out, err = run(
        ["analyze", str(path), "--max-attacked", "1", "--horizon", "3", "--json", "-"], capsys
    )
    assert status in (0, 1)
    doc = strict_json(out)
    assert doc["system"] == {"name": "plant", "n": 2, "p": 4, "sensors": ["y1", "y2", "y3", "y4"]}
    assert doc["meta"]["horizon"] == 3
    assert doc["meta"]["max_attacked"] == 1
    assert doc["verdict"] == {0: "holds", 1: "fails"}[status]


def test_mat_with_max_attacked_runs(tmp_path, capsys):
    import scipy.io

    path = tmp_path / "ugv-copy.mat"
    cells = np.empty((1, 3), dtype=object)
    cells[0, :] = ["position", "velocity-a", "velocity-b"]
    scipy.io.savemat(
        path,
        {
            "A": np.array([[1.0, 0.0099], [0.0, 0.9876]]),
            "C": np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 1.0]]),
            "sensors": cells,
        },
    )
    status, out, err = run(["analyze", str(path), "--max-attacked", "1", "--json", "-"], capsys)
    assert status == 1, err
    doc = strict_json(out)
    assert doc["system"]["sensors"] == ["position", "velocity-a", "velocity-b"]
    assert doc["checks"]["sparse_observability"]["breaking_set"] == [0]
    status, out, err = run(["analyze", str(path)], capsys)
    assert_usage_error(status, out, err, "--max-attacked")


def test_corrupt_npz(tmp_path, capsys):
    path = tmp_path / "broken.npz"
    path.write_bytes(b"PK\x03\x04 this is not a zip archive")
    status, out, err = run(["analyze", str(path), "--max-attacked", "1"], capsys)
    assert_usage_error(status, out, err, str(path))


# ---------------------------------------------------------------------------
# examples and --version
# ---------------------------------------------------------------------------


def test_examples_lists_every_name(capsys):
    status, out, err = run(["examples"], capsys)
    assert status == 0
    names = out.split()
    assert names == list_examples()
    for name in ("ugv", "notes-example-0", "notes-example-3", "lasso-example-1", "random-n15-p30"):
        assert name in names


def test_examples_prints_one_spec(capsys):
    status, out, err = run(["examples", "ugv"], capsys)
    assert status == 0
    assert out == example_path("ugv").read_text()
    document = tomllib.loads(out)
    assert document["name"] == "ugv"
    assert document["system"]["sensors"] == ["position", "velocity-a", "velocity-b"]


@pytest.mark.parametrize("name", list_examples())
def test_every_example_prints_as_valid_toml(capsys, name):
    status, out, _ = run(["examples", name], capsys)
    assert status == 0
    assert tomllib.loads(out)["name"] == name


def test_printed_example_round_trips_through_analyze(tmp_path, capsys):
    status, out, _ = run(["examples", "notes-example-3"], capsys)
    assert status == 0
    path = tmp_path / "copy.toml"
    path.write_text(out)
    status, out, err = run(["analyze", str(path)], capsys)
    assert status == 0, err


def test_version(capsys):
    status, out, err = run(["--version"], capsys)
    assert status == 0
    assert out.strip() == f"ssecert {ssecert.__version__}"


# ---------------------------------------------------------------------------
# real processes: exit codes and streams
# ---------------------------------------------------------------------------


@pytest.mark.slow
def test_process_analyze_ugv_json():
    proc = run_process(["analyze", "ugv", "--json", "-"])
    assert proc.returncode == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    doc = strict_json(proc.stdout)
    assert doc["checks"]["sparse_observability"]["breaking_set"] == [0]
    assert "sparse_observability" in proc.stderr


@pytest.mark.slow
@pytest.mark.parametrize(
    "args, fragment",
    [
        (["analyze", "no-such-example"], "no-such-example"),
        (["analyze", "ugv", "--max-sets", "1e400"], "--max-sets"),
        ([], "analyze"),
    ],
)
def test_process_bad_input(args, fragment):
    proc = run_process(args)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.startswith("ssecert: error: ")
    assert proc.stderr.count("\n") == 1
    assert fragment in proc.stderr
    assert proc.stdout == ""


@pytest.mark.slow
def test_process_npz_without_max_attacked(tmp_path):
    path = write_plant_npz(tmp_path)
    proc = run_process(["analyze", path.name], cwd=tmp_path)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert "--max-attacked" in proc.stderr


def test_process_version():
    proc = run_process(["--version"])
    assert proc.returncode == 0
    assert proc.stdout.strip() == f"ssecert {ssecert.__version__}"
    assert "Traceback" not in proc.stderr


def test_quiet_prints_nothing_and_still_writes_the_json(tmp_path, capsys):
    target = tmp_path / "c.json"
    assert main(["analyze", "notes-example-2", "--quiet", "--json", str(target)]) == 1
    out, err = capsys.readouterr()
    assert out == "" and err == ""
    assert json.loads(target.read_text())["verdict"] == "fails"
    assert main(["analyze", "notes-example-2", "--quiet", "--json", "-"]) == 1
    out, err = capsys.readouterr()
    assert json.loads(out)["verdict"] == "fails" and err == ""


def test_verbose_says_each_step_as_it_ends(capsys):
    assert main(["analyze", "notes-example-2", "--verbose"]) == 1
    err = capsys.readouterr().err.splitlines()
    steps = [line.split(":")[1].strip() for line in err if line.startswith("ssecert: ")]
    assert steps[:4] == ["eigenvalues", "observability", "sparse observability", "irrepresentable"]
    assert all(line.endswith(" s") for line in err if line.startswith("ssecert: "))


def test_quiet_and_verbose_exclude_each_other(capsys):
    assert main(["analyze", "notes-example-2", "--quiet", "--verbose"]) == 2
    assert "not allowed with argument" in capsys.readouterr().err
