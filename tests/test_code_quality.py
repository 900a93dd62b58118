"""The code passes its linter, its formatter and its type checker (configured in pyproject.toml)."""

import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _installed(module: str) -> bool:
    """Whether ``module`` (ruff, mypy: the ``dev`` extra) is installed for this Python."""
    import importlib.util

    return importlib.util.find_spec(module) is not None


def _run(*command: str) -> subprocess.CompletedProcess:
    return subprocess.run(command, cwd=ROOT, capture_output=True, text=True, check=False)


@pytest.mark.skipif(not (ROOT / "pyproject.toml").is_file(), reason="needs the source tree")
def test_ruff_lint_and_format():
    if not _installed("ruff"):
        pytest.skip('ruff is not installed: python -m pip install -e ".[dev]"')
    ruff = (sys.executable, "-m", "ruff")  # the one installed with this Python, PATH or not
    lint = _run(*ruff, "check", "--no-cache", ".")
    assert lint.returncode == 0, lint.stdout + lint.stderr
    fmt = _run(*ruff, "format", "--check", "--no-cache", ".")
    assert fmt.returncode == 0, fmt.stdout + fmt.stderr


@pytest.mark.slow
@pytest.mark.skipif(not (ROOT / "pyproject.toml").is_file(), reason="needs the source tree")
def test_mypy():
    if not _installed("mypy"):
        pytest.skip('mypy is not installed: python -m pip install -e ".[dev]"')
    run = _run(sys.executable, "-m", "mypy", "--cache-dir", "/dev/null")
    assert run.returncode == 0, run.stdout + run.stderr


def test_every_test_module_keeps_a_quick_test():
    # the default run deselects tests marked slow (pyproject's addopts); each module keeps one
    # test it runs, so the quick suite touches every module
    for path in [
        *sorted((ROOT / "tests").glob("test_*.py")),
        ROOT / "proofs_checks/test_claims.py",
    ]:
        text = path.read_text()
        tests = text.count("\ndef test_") + text.count("\n    def test_")
        whole = re.search(r"^pytestmark = pytest\.mark\.slow", text, re.MULTILINE)
        assert whole is None, f"{path.name}: mark its slow tests one by one"
        assert text.count("@pytest.mark.slow\n") < tests, path.name


_VERDICT_WORDS = {"holds", "fails", "inconclusive"}
_PROSE = ("reason", "summary", "problem", "note", "why")
# the renderers write the words: they may read them
_RENDERERS = ("report/", "cli/", "testing/assertions.py")


def _prose_name(node: object) -> bool:
    import ast

    name = node.id if isinstance(node, ast.Name) else getattr(node, "attr", None)
    return isinstance(name, str) and any(word in name.lower() for word in _PROSE)


# fields that carry a closed vocabulary (an observability or Schur decision, a method's status,
# how a certificate or gain was found): enums, compared by identity
_LABELS = ("state", "status", "method")


def _label_name(node: object) -> bool:
    """``x.state``, ``status``, ``pbh_state``, ``d["method"]``, ``d.get("state")``: a label
    (or a tuple, list or set holding one)."""
    import ast

    name: object = None
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return any(_label_name(e) for e in node.elts)
    if isinstance(node, ast.Name):
        name = node.id
    elif isinstance(node, ast.Attribute):
        name = node.attr
    elif isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant):
        name = node.slice.value
    elif (
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Attribute)
        and node.func.attr == "get"
        and node.args
        and isinstance(node.args[0], ast.Constant)
    ):
        name = node.args[0].value
    return isinstance(name, str) and (
        name in _LABELS or name.endswith(tuple(f"_{label}" for label in _LABELS[:2]))
    )


def _words(node: object) -> bool:
    """A string constant, or a tuple, list or set of them."""
    import ast

    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return bool(node.elts) and all(_words(e) for e in node.elts)
    return isinstance(node, ast.Constant) and isinstance(node.value, str)


def _reads_text(tree: object) -> list[tuple[int, str]]:
    """Where code decides from a sentence: a verdict compared with its name, a reason,
    summary or problem searched for a word, or a state, status or method compared with a
    string (or strings)."""
    import ast

    found = []
    for node in ast.walk(tree):  # type: ignore[arg-type]
        if isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            words = [s.value for s in sides if isinstance(s, ast.Constant)]
            if any(isinstance(op, (ast.Eq, ast.NotEq)) for op in node.ops) and (
                _VERDICT_WORDS & {w for w in words if isinstance(w, str)}
            ):
                found.append((node.lineno, ast.unparse(node)))
            if any(isinstance(op, (ast.In, ast.NotIn)) for op in node.ops) and any(
                _prose_name(s) for s in node.comparators
            ):
                found.append((node.lineno, ast.unparse(node)))
            if (
                any(isinstance(op, (ast.Eq, ast.NotEq, ast.In, ast.NotIn)) for op in node.ops)
                and any(_label_name(s) for s in sides)
                and any(_words(s) for s in sides)
            ):
                found.append((node.lineno, ast.unparse(node)))
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr in ("startswith", "endswith", "find", "index", "count")
            and _prose_name(node.func.value)
        ):
            found.append((node.lineno, ast.unparse(node)))
    return found


def _scan(paths: list[Path], skip: Any, finder: Any) -> list[str]:
    """``path:line: code`` of what ``finder`` (an AST scanner) finds in each file whose path
    from the repository root ``skip`` does not exclude."""
    import ast

    found = []
    for path in paths:
        where = path.relative_to(ROOT).as_posix()
        if not skip(where):
            tree = ast.parse(path.read_text(), str(path))
            found.extend(f"{where}:{line}: {code}" for line, code in finder(tree))
    return found


@pytest.mark.slow
def test_no_decision_is_read_from_a_sentence():
    """Verdicts and decisions travel as enums, flags and numbers; no code outside the renderers
    compares a verdict with its name, searches a reason, summary or problem for a word, or
    compares a state, status or method with a string."""
    offenders = _scan(
        sorted((ROOT / "ssecert").rglob("*.py")),
        lambda where: where.startswith(tuple(f"ssecert/{r}" for r in _RENDERERS)),
        _reads_text,
    )
    assert not offenders, "\n".join(offenders)


def test_the_sentence_reader_finds_what_it_names():
    import ast

    code = (
        "a = cert.verdict == 'inconclusive'\n"
        "b = 'is not stable' in found.reason\n"
        "c = problem.startswith('budget')\n"
        "d = check.verdict is Verdict.HOLDS\n"
        "e = 'radius' in evidence\n"
        # a label compared with its word(s)
        "f = x.state == 'observable'\n"
        "g = outcome.status != 'exact'\n"
        "h = cert.method in ('lyapunov', 'exact powers')\n"
        "i = 'unknown' not in [pbh_state, 'x']\n"
        "j = stair_state == 'unobservable'\n"
        "k = proof.get('state') not in {'stable', 'unstable'}\n"
        "l = proof['method'] == 'exact powers'\n"
        "m = problem.solver_status == 'optimal'\n"
        # members, other names and other comparisons are not
        "n = x.state is Observability.OBSERVABLE\n"
        "o = x.state in (SchurState.STABLE, SchurState.UNSTABLE)\n"
        "p = kind == 'iss'\n"
        "q = x.state == other.state\n"
        "r = statement == 'x'\n"
        "s = proof.get('radius') == 'x'\n"
        "t = x.state < 'b'\n"
        "u = x.method in ('a', b)\n"
    )
    assert [line for line, _ in _reads_text(ast.parse(code))] == [1, 2, 3, *range(6, 14)]


# tests of the words themselves: a family's message templates (called with codes and facts),
# how values are written (``base.format``), and the pytest toolkit's assertion messages
_WORDING_TESTS = ("_messages.py", "test_format.py", "test_testing.py")


def _searched_words(tree: object) -> list[tuple[int, str]]:
    """Asserts that search a summary, reason, note or problem for words (``"x" in
    check.summary``), unless the text searched is a message template's, called there."""
    import ast

    def prose(node: object) -> bool:
        if isinstance(node, ast.Subscript):
            key = node.slice
            if isinstance(key, ast.Constant) and isinstance(key.value, str):
                return any(word in key.value.lower() for word in _PROSE)
            return prose(node.value)
        if isinstance(node, ast.BinOp):
            return prose(node.left) or prose(node.right)
        if isinstance(node, ast.Call):
            return any(prose(a) for a in node.args)
        return _prose_name(node)

    def template(node: object) -> bool:
        return any(
            isinstance(n, ast.Call) and "_messages." in ast.unparse(n.func)
            for n in ast.walk(node)  # type: ignore[arg-type]
        )

    # words written once at the top of a module (CLAIM = "...") and searched for later
    named = {
        target.id
        for node in getattr(tree, "body", [])
        if isinstance(node, ast.Assign) and _words(node.value)
        for target in node.targets
        if isinstance(target, ast.Name)
    }

    def words(node: object) -> bool:
        if isinstance(node, ast.Name):
            return node.id in named
        return isinstance(node, (ast.Constant, ast.JoinedStr))

    found = []
    for node in ast.walk(tree):  # type: ignore[arg-type]
        if not isinstance(node, ast.Assert):
            continue
        for test in ast.walk(node.test):
            if (
                isinstance(test, ast.Compare)
                and any(isinstance(op, (ast.In, ast.NotIn)) for op in test.ops)
                and words(test.left)
                and any(prose(side) and not template(side) for side in test.comparators)
            ) or (
                isinstance(test, ast.Call)
                and isinstance(test.func, ast.Attribute)
                and test.func.attr in ("startswith", "endswith", "count", "find", "index")
                and prose(test.func.value)
                and bool(test.args)
                and words(test.args[0])
            ):
                found.append((test.lineno, ast.unparse(test)))
    return found


@pytest.mark.slow
def test_tests_read_codes_not_sentences():
    """Verdict tests compare reason codes and numbers; the words are tested where they are
    written (the message templates, the formatting of values, the toolkit's messages), so
    that a better sentence breaks no test that meant to check a verdict."""
    offenders = _scan(
        sorted((ROOT / "tests").glob("test_*.py")),
        lambda where: where.endswith(_WORDING_TESTS),
        _searched_words,
    )
    assert not offenders, "\n".join(offenders)


def test_the_words_searcher_finds_what_it_names():
    import ast

    code = (
        "CLAIM = 'within precision'\n"
        "assert 'x' in check.summary\n"
        "assert f'{v:.3g}' in cert['a'].reason\n"
        "assert 'y' not in notes[0]\n"
        "assert 'z' in out['summary']\n"
        "assert 'w' in ' '.join(found['problems'])\n"
        "assert CLAIM not in check.summary\n"
        # a template called with its code and facts, a code, a number: not
        "assert 'x' in region_messages.reason(code, facts)\n"
        "assert check.code is Code.X\n"
        "assert 'x' in fields\n"
        "assert 0.5 in values\n"
        "assert name in check.summary\n"
        "assert check.summary.endswith('done.')\n"
        "assert found.reason.startswith(region_messages.reason(code, facts))\n"
    )
    assert [line for line, _ in _searched_words(ast.parse(code))] == [2, 3, 4, 5, 6, 7, 13]
