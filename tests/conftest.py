"""Shared test configuration: the hypothesis profiles of ssecert's pytest plugin.

The plugin (``ssecert.testing.plugin``, loaded once ssecert is installed)
registers ``ssecert-quick`` and ``ssecert-thorough``.  The suite runs with
``ssecert-quick`` (40 derandomized examples, no deadline: deterministic, for
CI).  For a thorough run on demand (1000 random examples per property)::

    python -m pytest --ssecert-profile thorough
    HYPOTHESIS_PROFILE=thorough python -m pytest      # the same

``pytester`` lets the plugin's own tests run small test files.
"""

import os

import pytest

pytest_plugins = ["pytester"]

_ENVIRONMENT_PROFILES = {"thorough": "thorough", "quick": "quick", "ci": "quick"}


def pytest_configure(config):
    # runs before the plugin's pytest_configure (trylast), which loads the profile
    name = os.environ.get("HYPOTHESIS_PROFILE")
    if (
        not name
        or config.getoption("ssecert_profile", default=None)
        or config.getoption("hypothesis_profile", default=None)
    ):
        return
    if name not in _ENVIRONMENT_PROFILES:
        raise pytest.UsageError(
            f"HYPOTHESIS_PROFILE must be one of {', '.join(_ENVIRONMENT_PROFILES)}; got {name!r}"
        )
    config.option.ssecert_profile = _ENVIRONMENT_PROFILES[name]
