"""Claims of 001 (Cilia's thesis), Chapter 5: the elastic-net observer, Assumptions 1-3, Lemma 1
and Theorems 6-8 (registered with the rest of the thesis's claims by ``proofs_checks.thesis``)."""

from __future__ import annotations

from ._core import Finding, claim  # noqa: F401

__all__: list[str] = []
