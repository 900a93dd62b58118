"""pytest plugin of ssecert: the ``ssecert_example`` fixture and hypothesis profiles.

Loaded automatically once ssecert is installed (``pytest11`` entry point
``ssecert``; disable it with ``-p no:ssecert``, load it by name with
``-p ssecert`` when ``PYTEST_DISABLE_PLUGIN_AUTOLOAD`` is set).  It works
without hypothesis: then only the fixture is available.

The plugin proper is the top-level module ``_ssecert_pytestplugin``, which
this module re-exports: pytest imports every installed plugin when it
starts, and importing a module of this package would import ssecert and its
numerical dependencies.  The plugin imports only pytest; ssecert is
imported when the fixture is used, hypothesis only when a test needs a
profile.  Installing ssecert thus costs nothing to a pytest run that does
not use it, and changes none of its hypothesis settings.

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
``ssecert-thorough``  1000 random examples, no deadline, same health checks
                    suppressed: on demand
==================  ==========================================================

Which tests run under which profile:

1. ``--ssecert-profile quick|thorough`` on the command line loads that
   profile for every test of the run (it cannot be combined with
   ``--hypothesis-profile``);
2. otherwise ``--hypothesis-profile NAME`` is respected: the plugin leaves
   every test to hypothesis;
3. otherwise the ini option ``ssecert_profile = quick|thorough`` loads that
   profile for every test (a project that tests with ssecert throughout
   sets it once);
4. otherwise ``ssecert-quick`` applies to the tests that use ssecert, while
   they run, and every other test keeps hypothesis's own settings.  A test
   uses ssecert when it is marked ``@pytest.mark.ssecert`` (itself, its
   class, or its module with ``pytestmark``), requests the
   ``ssecert_example`` fixture (directly or through another fixture), or
   sits in a module that imported ``ssecert.testing.strategies`` or one of
   its strategies (its tests may draw them through ``st.data()`` or a
   composite; mark tests that reach the strategies through a helper
   module).  What such a test's own ``@settings(...)`` changes stays; the
   rest comes from the profile.  Hypothesis's ``default`` profile, or the
   ``ci`` profile it loads on CI services, possibly with
   ``--hypothesis-verbosity`` or ``--hypothesis-explain`` applied (they are
   kept), counts as nobody's choice; a profile your own ``conftest.py`` or
   test module loaded is left alone.  Without a deadline and derandomized,
   ssecert's checks (tens of milliseconds each) neither trip hypothesis's
   200 ms deadline now and then nor change from run to run.

The choice is shown in pytest's header.  A profile loaded for every test is
replaced by the previous one when pytest finishes, and one applied to a
test when the test ends (in-process runs such as ``pytester`` leak
nothing).
"""

from __future__ import annotations

from _ssecert_pytestplugin import (
    MARKER,
    PROFILES,
    QUICK_EXAMPLES,
    THOROUGH_EXAMPLES,
    register_profiles,
    ssecert_example,
)

__all__ = [
    "PROFILES",
    "QUICK_EXAMPLES",
    "THOROUGH_EXAMPLES",
    "MARKER",
    "register_profiles",
    "ssecert_example",
]

# Naming this module as a plugin (``pytest_plugins``, ``-p``) loads the plugin proper.
pytest_plugins = ["_ssecert_pytestplugin"]
