"""``ssecert design``'s search, importable from where it was first documented.

The code is ``ssecert.design.search``, beside the gains it synthesises; the names of its
``__all__`` (and the comparison and report helpers) stay importable from here.
"""

from .design.search import *  # noqa: F403
from .design.search import __all__ as _all
from .design.search import compare_designs, design_report, design_spec_text

__all__ = [*_all, "compare_designs", "design_report", "design_spec_text"]
