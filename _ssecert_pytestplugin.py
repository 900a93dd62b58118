"""The pytest plugin of ssecert, loaded through the ``pytest11`` entry point ``ssecert``.

What it does is documented in ``ssecert.testing.plugin``, which re-exports its
public names.  It lives outside the ssecert package because pytest imports
every installed plugin when it starts: a module inside the package would
import ``ssecert/__init__.py`` (numpy, scipy, python-control and the
analyses) at every pytest start in an environment where ssecert is
installed.  This module imports only the standard library and pytest;
ssecert is imported when the ``ssecert_example`` fixture is used, and
hypothesis when a profile is chosen for every test or a test that uses
ssecert runs with hypothesis already imported.
"""

from __future__ import annotations

import inspect
import sys
from collections.abc import Generator, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from types import FunctionType, ModuleType
from typing import Any

import pytest

__all__ = [
    "PROFILES",
    "QUICK_EXAMPLES",
    "THOROUGH_EXAMPLES",
    "MARKER",
    "register_profiles",
    "ssecert_example",
]

PROFILES = {"quick": "ssecert-quick", "thorough": "ssecert-thorough"}
QUICK_EXAMPLES = 40
THOROUGH_EXAMPLES = 1000
MARKER = "ssecert"
FIXTURE = "ssecert_example"
STRATEGIES = "ssecert.testing.strategies"
_UNCHOSEN = ("default", "ci")  # hypothesis's own profiles: nobody chose them


@dataclass
class _Choice:
    """What the plugin does with the hypothesis profile in this pytest run."""

    key: str | None  # the PROFILES key to apply; None: leave hypothesis alone
    everywhere: bool  # for every test (--ssecert-profile, the ini option), or only ssecert's
    why: str
    previous: str | None = None  # the profile to restore when pytest finishes
    registered: set[str] = field(default_factory=set)  # profiles registered in this run


_CHOICE = pytest.StashKey[_Choice]()


def register_profiles() -> bool:
    """Register the ``ssecert-quick`` and ``ssecert-thorough`` hypothesis profiles.

    Idempotent; the plugin calls it before it first applies one.

    Returns
    -------
    bool
        False when hypothesis is not installed (nothing registered).

    Examples
    --------
    >>> from hypothesis import settings
    >>> register_profiles()
    True
    >>> settings.get_profile("ssecert-quick").max_examples
    40
    """
    try:
        from hypothesis import HealthCheck, settings
    except ImportError:
        return False
    suppress = [HealthCheck.too_slow, HealthCheck.data_too_large]
    settings.register_profile(
        PROFILES["quick"],
        max_examples=QUICK_EXAMPLES,
        derandomize=True,
        deadline=None,
        database=None,
        suppress_health_check=suppress,
    )
    settings.register_profile(
        PROFILES["thorough"],
        max_examples=THOROUGH_EXAMPLES,
        deadline=None,
        print_blob=True,
        suppress_health_check=suppress,
    )
    return True


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("ssecert", "ssecert property tests")
    group.addoption(
        "--ssecert-profile",
        action="store",
        choices=tuple(PROFILES),
        default=None,
        dest="ssecert_profile",
        help=(
            "hypothesis profile for every test: quick (40 derandomized examples) or thorough "
            "(1000 random examples), both without deadline.  Without it, ssecert-quick applies "
            "only to tests that use ssecert's fixtures, strategies or marker"
        ),
    )
    parser.addini(
        "ssecert_profile",
        default="",
        help="default of --ssecert-profile: quick or thorough, for every test",
    )


def _choose(config: pytest.Config) -> _Choice:
    """The profile to apply, to which tests, and why; imports nothing."""
    cli = config.getoption("ssecert_profile")
    hypothesis_cli = config.getoption("hypothesis_profile", default=None)
    if cli and hypothesis_cli:
        raise pytest.UsageError(
            f"--ssecert-profile {cli} and --hypothesis-profile {hypothesis_cli} both choose the "
            f"hypothesis profile; give only one"
        )
    if cli:
        return _Choice(cli, True, "--ssecert-profile")
    if hypothesis_cli:
        return _Choice(None, False, f"--hypothesis-profile {hypothesis_cli}")
    ini = str(config.getini("ssecert_profile") or "").strip()
    if ini:
        if ini not in PROFILES:
            raise pytest.UsageError(
                f"the ini option ssecert_profile must be one of {', '.join(PROFILES)}; got {ini!r}"
            )
        return _Choice(ini, True, "ini option ssecert_profile")
    return _Choice("quick", False, "for tests that use ssecert; hypothesis's own for the others")


def _base(name: str) -> str:
    """The profile hypothesis's own options derived ``name`` from (``X-with-verbose-verbosity``)."""
    return name.split("-with-")[0]


def _ours(choice: _Choice, key: str) -> str:
    """Register (once per run) and name our profile, keeping the options hypothesis's plugin set.

    ``--hypothesis-verbosity`` and ``--hypothesis-explain`` derive a profile
    from the active one (``default-with-verbose-verbosity``); ours is derived
    the same way, with their verbosity and phases.
    """
    from hypothesis import settings

    ours = PROFILES[key]
    if ours not in choice.registered:
        register_profiles()
        choice.registered.update(PROFILES.values())
    current = settings.get_current_profile_name()
    suffix = current[len(_base(current)) :]
    if suffix and ours + suffix not in choice.registered:
        active = settings.default
        if active is None:  # pragma: no cover - a profile is loaded, so hypothesis has a default
            raise RuntimeError("hypothesis has no current settings to take the options from")
        settings.register_profile(
            ours + suffix,
            parent=settings.get_profile(ours),
            verbosity=active.verbosity,
            phases=active.phases,
        )
        choice.registered.add(ours + suffix)
    return ours + suffix


@pytest.hookimpl(trylast=True)
def pytest_configure(config: pytest.Config) -> None:
    # trylast: after hypothesis's plugin (--hypothesis-profile) and conftest hooks
    config.addinivalue_line(
        "markers",
        f"{MARKER}: run this test under ssecert's hypothesis profile (ssecert-quick unless "
        "--ssecert-profile or the ini option ssecert_profile chose one for every test)",
    )
    choice = _choose(config)
    if choice.everywhere:
        if not register_profiles():
            if config.getoption("ssecert_profile"):
                raise pytest.UsageError(
                    '--ssecert-profile needs hypothesis: pip install "ssecert[testing]"'
                )
            return
        from hypothesis import settings

        assert choice.key is not None
        choice.previous = settings.get_current_profile_name()
        settings.load_profile(_ours(choice, choice.key))
    config.stash[_CHOICE] = choice


def pytest_unconfigure(config: pytest.Config) -> None:
    choice = config.stash.get(_CHOICE, None)
    if choice is not None and choice.previous is not None:
        from hypothesis import settings

        settings.load_profile(choice.previous)


def pytest_report_header(config: pytest.Config) -> str | None:
    choice = config.stash.get(_CHOICE, None)
    if choice is None:
        return None
    if choice.everywhere or choice.key is None:
        # hypothesis is imported: we loaded a profile, or --hypothesis-profile did
        from hypothesis import settings

        return f"ssecert: hypothesis profile {settings.get_current_profile_name()!r} ({choice.why})"
    if "hypothesis" in sys.modules:  # a conftest imported it, and may have loaded a profile
        from hypothesis import settings

        current = settings.get_current_profile_name()
        if _base(current) not in _UNCHOSEN:
            return f"ssecert: hypothesis profile {current!r} (profile {current!r} loaded by the project)"
        name = PROFILES["quick"] + current[len(_base(current)) :]
    elif config.pluginmanager.has_plugin("hypothesispytest"):  # installed, not yet imported
        name = PROFILES["quick"]
    else:
        return None
    return f"ssecert: hypothesis profile {name!r} ({choice.why})"


def _from_strategies(value: object, strategies: ModuleType) -> bool:
    return value is strategies or (
        isinstance(value, FunctionType) and value.__module__ == STRATEGIES
    )


def _uses_ssecert(item: pytest.Item) -> bool:
    """Whether a test gets ssecert's profile when none is chosen for every test.

    It does when it is marked ``@pytest.mark.ssecert`` (itself, its class or
    its module), requests the ``ssecert_example`` fixture (directly or
    through another fixture), or sits in a module that imported
    ``ssecert.testing.strategies`` (``from`` it, or ``import
    ssecert.testing.strategies``) or one of its strategies: such a module's
    tests may draw them through ``st.data()`` or a composite strategy.
    """
    if item.get_closest_marker(MARKER) is not None:
        return True
    if FIXTURE in getattr(item, "fixturenames", ()):
        return True
    strategies = sys.modules.get(STRATEGIES)
    module = getattr(item, "module", None)
    if strategies is None or not isinstance(module, ModuleType):
        return False
    values = list(vars(module).values())
    if any(_from_strategies(value, strategies) for value in values):
        return True
    # ``import ssecert.testing.strategies`` binds only the package ``ssecert``: read the
    # module's own imports (once per module)
    package = sys.modules.get("ssecert")
    return any(value is package for value in values) and _imports_strategies(module)


_IMPORTS: dict[str, bool] = {}


def _imports_strategies(module: ModuleType) -> bool:
    """Whether the module's source has ``import ssecert.testing.strategies`` (any alias)."""
    import ast

    path = getattr(module, "__file__", None)
    if path is None:
        return False
    if path not in _IMPORTS:
        try:
            with open(path, encoding="utf-8") as handle:
                tree = ast.parse(handle.read())
        except (OSError, SyntaxError, ValueError):
            tree = None
        _IMPORTS[path] = tree is not None and any(
            isinstance(node, ast.Import) and any(a.name == STRATEGIES for a in node.names)
            for node in ast.walk(tree)
        )
    return _IMPORTS[path]


def _rebased(given: Any, base: Any, profile: Any) -> Any:
    """The settings of a ``@given`` test with ``profile`` in place of the profile they came from.

    ``@given`` keeps the settings in force when the test was decorated: the
    active profile (``base``), or a ``@settings(...)`` made from it.  What
    the test's own ``@settings`` changed stays; the rest comes from
    ``profile``.
    """
    from hypothesis import settings

    if given is base:
        return profile
    names = [
        name
        for name, parameter in inspect.signature(settings).parameters.items()
        if parameter.kind is inspect.Parameter.KEYWORD_ONLY
    ]
    changed = {
        name: getattr(given, name) for name in names if getattr(given, name) != getattr(base, name)
    }
    return settings(profile, **changed)


@contextmanager
def _applied(item: pytest.Item, choice: _Choice, key: str) -> Iterator[None]:
    """Our profile in force while ``item`` runs, then the previous one again.

    Loading the profile covers ``@given`` tests decorated inside the test and
    ``hypothesis.find``; the settings that the test's own ``@given`` stored
    when its module was imported are swapped for the test's run.
    """
    from hypothesis import settings

    previous = settings.get_current_profile_name()
    if _base(previous) not in _UNCHOSEN:  # the project loaded a profile of its own: keep it
        yield
        return
    base = settings.default
    name = _ours(choice, key)
    obj = getattr(item, "obj", None)
    test: Any = getattr(obj, "__func__", obj)  # a method's settings live on its function
    given = getattr(test, "_hypothesis_internal_use_settings", None)
    settings.load_profile(name)
    try:
        if given is not None:
            test._hypothesis_internal_use_settings = _rebased(
                given, base, settings.get_profile(name)
            )
        yield
    finally:
        if given is not None:
            test._hypothesis_internal_use_settings = given
        settings.load_profile(previous)


@pytest.hookimpl(hookwrapper=True, tryfirst=True)
def pytest_runtest_call(item: pytest.Item) -> Generator[None, Any, None]:
    # tryfirst: outside hypothesis's own wrapper, which reads the test's settings
    choice = item.config.stash.get(_CHOICE, None)
    if (
        choice is None
        or choice.everywhere
        or choice.key is None
        or "hypothesis" not in sys.modules
        or not _uses_ssecert(item)
    ):
        yield
        return
    with _applied(item, choice, choice.key):
        yield


@pytest.fixture(scope="session")
def ssecert_example() -> Any:
    """Factory of ssecert's packaged examples: ``ssecert_example(name)``.

    Returns the example's ``Spec`` when it has an ``[observer]`` section
    (a design), else its ``System``; unknown names raise ``ValueError``
    listing the available ones.  Tests that use it run under ssecert's
    hypothesis profile.

    Examples
    --------
    .. code-block:: python

        def test_ugv_position_sensor(ssecert_example):
            ugv = ssecert_example("ugv")            # a Spec: it has an [observer]
            assert ugv.system.sensors[0] == "position"
    """
    cache: dict[str, Any] = {}

    def load(name: str) -> Any:
        from ssecert.examples import list_examples, load_example

        if not isinstance(name, str):
            raise TypeError(
                f"name must be the name of a packaged example, got {type(name).__name__} {name!r}"
            )
        if name not in cache:
            names = list_examples()
            if name not in names:
                raise ValueError(
                    f"no packaged ssecert example named {name!r}; available: {', '.join(names)}"
                )
            spec = load_example(name)
            cache[name] = spec if spec.observer is not None else spec.system
        return cache[name]

    return load
