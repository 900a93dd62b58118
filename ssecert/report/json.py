"""JSON rendering of certificates (strict JSON: no NaN or Infinity literals)."""

from __future__ import annotations

import json
from pathlib import Path

from .._io import atomic_write_text
from ..results import Certificate

__all__ = ["certificate_json", "write_json"]


def certificate_json(certificate: Certificate, *, indent: int | None = 2) -> str:
    """The certificate as a strict JSON document (non-finite floats as strings)."""
    return json.dumps(certificate.to_dict(), indent=indent, allow_nan=False) + "\n"


def write_json(certificate: Certificate, path: str | Path) -> Path:
    """Write the certificate's JSON atomically to ``path``."""
    return atomic_write_text(path, certificate_json(certificate))
