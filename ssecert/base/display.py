"""Notebook display of results: ``_repr_html_`` methods that render with the HTML report.

The renderer sits above the results it renders, so results hold only this hook; the package
(``ssecert/__init__.py``) sets ``html_renderer`` to one that imports ``ssecert.report.html``
when a result is first shown.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["html_display", "html_renderer"]

#: ``renderer(fragment_name, result)`` -> an HTML fragment; set by the package on import.
html_renderer: Callable[[str, Any], str] | None = None


def html_display(fragment: str) -> Callable[[Any], str]:
    """A ``_repr_html_`` that renders with ``html_renderer``'s ``fragment``."""

    def _repr_html_(self: Any) -> str:
        if html_renderer is None:  # pragma: no cover - the package sets it on import
            raise NotImplementedError("no HTML renderer is registered")
        return html_renderer(fragment, self)

    return _repr_html_
