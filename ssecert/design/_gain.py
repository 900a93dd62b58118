"""What every observer-gain construction returns, and the error it raises."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["Gain", "GainError", "GainMethod"]


class GainError(ValueError):
    """A gain could not be computed to specification (the message says why)."""


class GainMethod(enum.StrEnum):
    """How the package's observer gains are built: the value is the word shown and written."""

    DEADBEAT = "deadbeat"
    PLACE = "place"
    OGD = "ogd"
    PINV = "pinv"
    MATRIX = "matrix"  # given as a matrix


@dataclass(frozen=True)
class Gain:
    """An observer gain L with the evidence that it does what was asked.

    Attributes
    ----------
    L : ndarray, shape (n, p)
    method : GainMethod or str
        A ``GainMethod`` for the package's gains; the observer kind of a plugin may name
        its own gain with a string.
    error_matrix : ndarray, shape (n, n)
        F = A - L C.
    verified : bool
        Whether the construction's own check passed.
    details : mapping
        Method-specific evidence (nilpotency norms, pole mismatch, ...).
    """

    L: np.ndarray
    method: GainMethod | str
    error_matrix: np.ndarray
    verified: bool
    details: dict[str, Any] = field(default_factory=dict)
