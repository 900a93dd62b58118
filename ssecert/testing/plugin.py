"""pytest plugin of ssecert: the ``ssecert_example`` fixture and hypothesis profiles.

Loaded automatically once ssecert is installed (``pytest11`` entry point
``ssecert``; disable with ``-p no:ssecert``).  It works without hypothesis:
then only the fixture is available.

Fixture
-------
``ssecert_example(name)``
    A packaged example (``ssecert examples`` lists them): its ``Spec`` when
    it has an ``[observer]`` section (a design), else its ``System``.
    Session-scoped, so it can be used in ``@given`` tests.

Hypothesis profiles
-------------------
The plugin registers two profiles, named so that they do not collide with
a project's own:

==================  ==========================================================
``ssecert-quick``   40 examples, ``derandomize=True`` (the same examples on
                    every run), no deadline, the ``too_slow`` and
                    ``data_too_large`` health checks suppressed: for CI
``ssecert-thorough``  1000 examples, random, no deadline, same health checks
                    suppressed: on demand
==================  ==========================================================

Which profile is active:

1. ``--ssecert-profile quick|thorough`` on the command line loads that
   profile (it cannot be combined with ``--hypothesis-profile``);
2. otherwise ``--hypothesis-profile NAME`` is respected: the plugin leaves
   the choice to hypothesis (``--hypothesis-profile default`` restores
   hypothesis's own defaults);
3. otherwise the ini option ``ssecert_profile = quick|thorough`` loads that
   profile;
4. otherwise, if nothing has chosen a profile (the active one is still
   hypothesis's ``default``, or the ``ci`` profile it loads on CI
   services, possibly with ``--hypothesis-verbosity`` or
   ``--hypothesis-explain`` applied), ``ssecert-quick`` is loaded, keeping
   those two options: plain ``pytest`` is
   deterministic and has no deadline, which ssecert's checks (tens of
   milliseconds each) would otherwise exceed now and then.  A profile your
   own ``conftest.py`` loaded at import is left alone.

The profile in force is shown in pytest's header, and the previous one is
restored when pytest finishes (in-process runs such as ``pytester`` do
not leak it).
"""

from __future__ import annotations

from typing import Any

import pytest

__all__ = ["PROFILES", "register_profiles", "ssecert_example"]

PROFILES = {"quick": "ssecert-quick", "thorough": "ssecert-thorough"}
QUICK_EXAMPLES = 40
THOROUGH_EXAMPLES = 1000
_UNCHOSEN = ("default", "ci")  # hypothesis's own profiles: nobody chose them
_STATE = pytest.StashKey[dict]()


def register_profiles() -> bool:
    """Register the ``ssecert-quick`` and ``ssecert-thorough`` hypothesis profiles.

    Idempotent; the plugin calls it when pytest starts.

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
            "hypothesis profile for property tests: quick (40 derandomized examples, the "
            "default) or thorough (1000 random examples); both without deadline"
        ),
    )
    parser.addini(
        "ssecert_profile", default="", help="default of --ssecert-profile: quick or thorough"
    )


def _choose(config: pytest.Config) -> tuple[str | None, str]:
    """The profile key to load (None: leave hypothesis alone) and why."""
    cli = config.getoption("ssecert_profile")
    hypothesis_cli = config.getoption("hypothesis_profile", default=None)
    if cli and hypothesis_cli:
        raise pytest.UsageError(
            f"--ssecert-profile {cli} and --hypothesis-profile {hypothesis_cli} both choose the "
            f"hypothesis profile; give only one"
        )
    if cli:
        return cli, "--ssecert-profile"
    if hypothesis_cli:
        return None, f"--hypothesis-profile {hypothesis_cli}"
    ini = str(config.getini("ssecert_profile") or "").strip()
    if ini:
        if ini not in PROFILES:
            raise pytest.UsageError(
                f"the ini option ssecert_profile must be one of {', '.join(PROFILES)}; got {ini!r}"
            )
        return ini, "ini option ssecert_profile"
    from hypothesis import settings

    current = settings.get_current_profile_name()
    if _base(current) in _UNCHOSEN:
        return "quick", "default"
    return None, f"profile {current!r} loaded by the project"


def _base(name: str) -> str:
    """The profile hypothesis's own options derived ``name`` from (``X-with-verbose-verbosity``)."""
    return name.split("-with-")[0]


def _load(key: str) -> None:
    """Load our profile, keeping the verbosity and phases that hypothesis's options set."""
    from hypothesis import settings

    ours = PROFILES[key]
    current = settings.get_current_profile_name()
    suffix = current[len(_base(current)) :]
    if suffix:  # --hypothesis-verbosity / --hypothesis-explain were given
        active = settings.default
        if active is None:  # pragma: no cover - a profile is loaded, so hypothesis has a default
            raise RuntimeError("hypothesis has no current settings to take the options from")
        settings.register_profile(
            ours + suffix,
            parent=settings.get_profile(ours),
            verbosity=active.verbosity,
            phases=active.phases,
        )
    settings.load_profile(ours + suffix)


@pytest.hookimpl(trylast=True)
def pytest_configure(config: pytest.Config) -> None:
    # trylast: after hypothesis's plugin (--hypothesis-profile) and conftest hooks
    if not register_profiles():
        if config.getoption("ssecert_profile"):
            raise pytest.UsageError(
                '--ssecert-profile needs hypothesis: pip install "ssecert[testing]"'
            )
        return
    from hypothesis import settings

    key, why = _choose(config)
    previous = settings.get_current_profile_name()
    if key is not None:
        _load(key)
    config.stash[_STATE] = {"previous": previous, "loaded": key is not None, "why": why}


def pytest_unconfigure(config: pytest.Config) -> None:
    state = config.stash.get(_STATE, None)
    if state and state["loaded"]:
        from hypothesis import settings

        settings.load_profile(state["previous"])


def pytest_report_header(config: pytest.Config) -> str | None:
    state = config.stash.get(_STATE, None)
    if not state:
        return None
    from hypothesis import settings

    return f"ssecert: hypothesis profile {settings.get_current_profile_name()!r} ({state['why']})"


@pytest.fixture(scope="session")
def ssecert_example() -> Any:
    """Factory of ssecert's packaged examples: ``ssecert_example(name)``.

    Returns the example's ``Spec`` when it has an ``[observer]`` section
    (a design), else its ``System``; unknown names raise ``ValueError``
    listing the available ones.

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
