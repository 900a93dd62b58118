"""ssecert's pytest plugin touches only the tests that use ssecert, and imports nothing heavy.

Installing ssecert registers its plugin with every pytest run of the
environment: an unrelated suite must keep hypothesis's own settings (its
deadline still fails a slow test) and must not pay for importing ssecert.
"""

import json
import subprocess
import sys

import pytest

# imported here, not first in a pytester run: pytester forgets the modules a run imported, and
# numpy cannot be imported twice in one process
import ssecert.testing.strategies  # noqa: F401

HEAVY = ("numpy", "scipy", "control", "cvxpy", "sympy", "matplotlib", "ssecert")

# what a hypothesis test saw: the settings in force while its body ran
SEEN = """
import json
from hypothesis import settings

def record(name):
    current = settings.default
    deadline = current.deadline
    with open("seen.jsonl", "a") as out:
        out.write(json.dumps({
            "test": name,
            "max_examples": current.max_examples,
            "deadline": None if deadline is None else deadline.total_seconds(),
            "derandomize": current.derandomize,
        }) + "\\n")
"""

UNRELATED = """
from hypothesis import given, strategies as st
from seen import record

@given(st.integers())
def test_unrelated(x):
    record("unrelated")
"""

USES_SSECERT = """
import pytest
from hypothesis import given, settings, strategies as st
from seen import record

@pytest.mark.ssecert
@given(st.integers())
def test_marked(x):
    record("marked")

@given(st.integers())
def test_fixture(ssecert_example, x):
    record("fixture")

@pytest.mark.ssecert
class TestMarked:
    @given(st.integers())
    def test_method(self, x):
        record("method")

@pytest.mark.ssecert
@settings(max_examples=7)
@given(st.integers())
def test_own_settings(x):
    record("own")

@given(st.integers())
def test_same_module_unmarked(x):
    record("unmarked")
"""

STRATEGIES = """
from hypothesis import given, strategies as st
from ssecert.testing.strategies import sparse_attacks
from seen import record

@given(sparse_attacks(3, 1, 5))
def test_strategy(a):
    record("strategy")

@given(st.data())
def test_drawn(data):
    data.draw(sparse_attacks(3, 1, 5))
    record("drawn")
"""

DOTTED = """
import ssecert.testing.strategies
from hypothesis import given
from seen import record

@given(ssecert.testing.strategies.sparse_attacks(3, 1, 5))
def test_dotted(a):
    record("dotted")
"""

SLOW = """
import time
from hypothesis import given, strategies as st

@given(st.just(None))
def test_slow(x):
    time.sleep(0.3)  # beyond hypothesis's default deadline of 200 ms
"""

DEFAULTS = {"max_examples": 100, "deadline": 0.2, "derandomize": False}
QUICK = {"max_examples": 40, "deadline": None, "derandomize": True}


def _run(pytester, *args):
    """Run in-process as from a fresh process: the settings each test saw, the result, and the
    hypothesis profile in force after the run."""
    from hypothesis import settings

    seen = pytester.path / "seen.jsonl"
    if seen.exists():
        seen.unlink()
    outer = settings.get_current_profile_name()
    settings.load_profile("default")  # what a fresh process starts from
    try:
        result = pytester.runpytest("-p", "no:cacheprovider", *args)
        after = settings.get_current_profile_name()
    finally:
        settings.load_profile(outer)
    by_test: dict[str, dict] = {}
    lines = seen.read_text().splitlines() if seen.exists() else []
    for line in lines:
        record = json.loads(line)
        name = record.pop("test")
        entry = by_test.setdefault(name, {**record, "calls": 0})
        assert {k: entry[k] for k in record} == record, name  # the same settings every example
        entry["calls"] += 1
    return by_test, result, after


def _settings(entry):
    return {k: entry[k] for k in ("max_examples", "deadline", "derandomize")}


@pytest.fixture
def files(pytester):
    pytester.syspathinsert()
    pytester.makepyfile(seen=SEEN)
    return pytester


def test_an_unrelated_test_keeps_hypothesis_defaults(files):
    files.makepyfile(test_unrelated=UNRELATED)
    seen, result, after = _run(files)
    result.assert_outcomes(passed=1)
    assert _settings(seen["unrelated"]) == DEFAULTS
    assert seen["unrelated"]["calls"] == 100
    assert after == "default"
    result.stdout.fnmatch_lines(
        ["ssecert: hypothesis profile 'ssecert-quick' (for tests that use ssecert;*"]
    )


@pytest.mark.slow
def test_an_unrelated_deadline_still_fails(files):
    files.makepyfile(test_slow=SLOW)
    _, result, _ = _run(files)
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(["*DeadlineExceeded*"])
    # the same test, marked or run under an ssecert profile for every test, has no deadline
    _, result, _ = _run(files, "--ssecert-profile", "quick")
    result.assert_outcomes(passed=1)
    files.makepyfile(test_slow="import pytest\npytestmark = pytest.mark.ssecert\n" + SLOW)
    _, result, _ = _run(files)
    result.assert_outcomes(passed=1)


@pytest.mark.slow
def test_tests_that_use_ssecert_get_its_profile(files):
    files.makepyfile(
        test_uses=USES_SSECERT, test_strategies=STRATEGIES, test_dotted=DOTTED, test_z=UNRELATED
    )
    seen, result, after = _run(files)
    result.assert_outcomes(passed=9)
    for name in ("marked", "fixture", "method", "strategy", "drawn", "dotted"):
        assert _settings(seen[name]) == QUICK, name
    for name in ("marked", "fixture", "method"):
        assert seen[name]["calls"] == QUICK["max_examples"], name
    # the test's own @settings stay; the rest comes from the profile
    assert _settings(seen["own"]) == {**QUICK, "max_examples": 7}
    assert seen["own"]["calls"] == 7
    # restored after each test: the next ones, unmarked or in another module, see the defaults
    assert _settings(seen["unmarked"]) == DEFAULTS
    assert _settings(seen["unrelated"]) == DEFAULTS
    assert after == "default"
    # derandomized: the same examples every run
    again, _, _ = _run(files)
    assert again["marked"] == seen["marked"]


@pytest.mark.slow
def test_a_profile_chosen_for_every_test(files):
    files.makepyfile(test_unrelated=UNRELATED)
    seen, result, after = _run(files, "--ssecert-profile", "thorough")
    result.assert_outcomes(passed=1)
    assert seen["unrelated"]["max_examples"] == 1000 and seen["unrelated"]["deadline"] is None
    assert seen["unrelated"]["calls"] == 1000
    result.stdout.fnmatch_lines(
        ["ssecert: hypothesis profile 'ssecert-thorough' (--ssecert-profile)"]
    )
    assert after == "default"
    files.makeini("[pytest]\nssecert_profile = quick\n")
    seen, result, _ = _run(files)
    assert _settings(seen["unrelated"]) == QUICK
    result.stdout.fnmatch_lines(
        ["ssecert: hypothesis profile 'ssecert-quick' (ini option ssecert_profile)"]
    )


def test_a_profile_the_project_loaded_is_left_alone(files):
    files.makepyfile(test_uses=USES_SSECERT)
    files.makeconftest("""
        from hypothesis import settings
        settings.register_profile("ours", max_examples=5, deadline=None)
        settings.load_profile("ours")
    """)
    seen, result, _ = _run(files)
    result.assert_outcomes(passed=5)
    assert seen["marked"]["max_examples"] == 5 and seen["marked"]["calls"] == 5
    result.stdout.fnmatch_lines(["*profile 'ours' (profile 'ours' loaded by the project)"])


def test_the_marker_is_registered(files):
    files.makepyfile(test_uses=USES_SSECERT)
    _, result, _ = _run(files, "--strict-markers")
    result.assert_outcomes(passed=5)
    result = files.runpytest("--markers")
    result.stdout.fnmatch_lines(["@pytest.mark.ssecert: run this test under ssecert's*"])


def test_the_entry_point_imports_nothing_heavy():
    code = (
        "import sys\n"
        "from importlib.metadata import entry_points\n"
        "(plugin,) = [e for e in entry_points(group='pytest11') if e.name == 'ssecert']\n"
        "plugin.load()\n"
        f"print(plugin.value, *[m for m in {HEAVY!r} if m in sys.modules])\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.split() == ["_ssecert_pytestplugin"]


@pytest.mark.slow
def test_a_pytest_run_that_does_not_use_ssecert_does_not_import_it(pytester):
    pytester.makepyfile(
        test_plain=f"""
        import sys

        def test_nothing_heavy_was_imported():
            assert [m for m in {HEAVY!r} if m in sys.modules] == []
        """
    )
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider")
    result.assert_outcomes(passed=1)
    result.stdout.fnmatch_lines(["ssecert: hypothesis profile 'ssecert-quick' (for tests*"])


@pytest.mark.slow
def test_the_plugin_loads_by_name_without_autoload(pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makepyfile(
        test_fixture="""
        def test_fixture(ssecert_example):
            assert ssecert_example("ugv").system.sensors[0] == "position"
        """
    )
    for name in ("ssecert", "ssecert.testing.plugin"):
        result = pytester.runpytest_subprocess(
            "-p", "no:cacheprovider", "-p", name, "--ssecert-profile", "quick"
        )
        result.assert_outcomes(passed=1)


def test_the_entry_point_module_examples_run():
    import doctest

    import _ssecert_pytestplugin

    assert doctest.testmod(_ssecert_pytestplugin).failed == 0
