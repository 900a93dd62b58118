"""What every observer-gain construction returns, and the error it raises."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["Gain", "GainError"]


class GainError(ValueError):
    """A gain could not be computed to specification (the message says why)."""


@dataclass(frozen=True)
class Gain:
    """An observer gain L with the evidence that it does what was asked.

    Attributes
    ----------
    L : ndarray, shape (n, p)
    method : str
        ``"deadbeat"``, ``"place"``, ``"ogd"``, ``"pinv"`` or ``"matrix"``.
    error_matrix : ndarray, shape (n, n)
        F = A - L C.
    verified : bool
        Whether the construction's own check passed.
    details : mapping
        Method-specific evidence (nilpotency norms, pole mismatch, ...).
    """

    L: np.ndarray
    method: str
    error_matrix: np.ndarray
    verified: bool
    details: dict[str, Any] = field(default_factory=dict)
