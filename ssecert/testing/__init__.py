"""ssecert's checks in your own pytest suite: assertions, hypothesis strategies, a plugin.

* ``ssecert.testing`` (this package): assertions that pass only on a
  ``holds`` verdict and explain anything else, naming sensors by name and
  0-based index: ``assert_observable``, ``assert_sparse_observable``,
  ``assert_deadbeat``, ``assert_schur``, ``assert_certified`` and
  ``assert_recovers``.
* ``ssecert.testing.strategies`` (needs hypothesis): plants, sparse attacks
  and observer designs built to have the property they promise.
* ``ssecert.testing.plugin``: a pytest plugin, loaded automatically once
  ssecert is installed, with the ``ssecert_example`` fixture, the
  ``ssecert`` marker and the ``--ssecert-profile quick|thorough`` option.
  Its hypothesis profile applies to the tests that use ssecert (or to every
  test, when asked); pytest's start-up imports neither ssecert nor
  hypothesis for it.

Install the test dependencies with ``pip install "ssecert[testing]"``.

Examples
--------
>>> from ssecert.examples import load_example
>>> from ssecert.testing import assert_observable
>>> assert_observable(load_example("ugv").system).value
1
"""

from .assertions import (
    assert_certified,
    assert_deadbeat,
    assert_observable,
    assert_recovers,
    assert_schur,
    assert_sparse_observable,
)

__all__ = [
    "assert_observable",
    "assert_sparse_observable",
    "assert_deadbeat",
    "assert_schur",
    "assert_certified",
    "assert_recovers",
]
