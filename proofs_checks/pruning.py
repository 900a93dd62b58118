"""Claims of the document pruning: see ``proofs_checks._core.DOCUMENTS``."""

from __future__ import annotations

from ._core import Finding, claim  # noqa: F401

__all__: list[str] = []
