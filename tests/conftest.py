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


def _follow_their_schema() -> None:
    """Every certificate the tests render (``certificate_json``, ``certify_json``) is checked
    against its JSON Schema (``ssecert.schemas``): patched before the test modules import
    them, so that a document that does not follow the schema fails the test that made it."""
    try:
        import jsonschema
    except ImportError:  # the test extra has it; a bare run checks nothing here
        return
    import json

    from ssecert.observers import observer_kinds
    from ssecert.report import json as rendering
    from ssecert.schemas import certificate_schema

    validators: dict[tuple[str, ...], jsonschema.Draft202012Validator] = {}

    def validator():  # the schema of the kinds registered now (a test may register its own)
        kinds = tuple(observer_kinds())
        if kinds not in validators:
            validators[kinds] = jsonschema.Draft202012Validator(certificate_schema())
        return validators[kinds]

    def checked(render):
        def wrapper(*args, **kwargs):
            text = render(*args, **kwargs)
            error = next(iter(validator().iter_errors(json.loads(text))), None)
            if error is not None:
                where = "/".join(str(p) for p in error.absolute_path)
                raise AssertionError(
                    f"the certificate breaks its schema at {where}: {error.message}"
                )
            return text

        return wrapper

    rendering.certificate_json = checked(rendering.certificate_json)
    rendering.certify_json = checked(rendering.certify_json)


def pytest_configure(config):
    _follow_their_schema()
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


@pytest.fixture
def sparse_problems(monkeypatch):
    """The problems of each ``sparse_observability`` call of a test as typed values, read where
    the check's evidence writes their words: per call, one list of ``Problem`` per method
    tried, in the order of ``evidence["methods_tried"]``."""
    from ssecert.structure import sparse

    calls = []
    evidence = sparse._evidence

    def recording(s, outcome, tried, *args, **kwargs):
        calls.append([list(o.problems) for o in tried])
        return evidence(s, outcome, tried, *args, **kwargs)

    monkeypatch.setattr(sparse, "_evidence", recording)
    return calls
