"""JSON rendering of certificates (strict JSON: no NaN or Infinity literals)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from ..base.atomic import atomic_write_text
from ..results import Certificate, to_jsonable
from ..spec.write import spec_document

__all__ = ["certificate_json", "write_json", "certify_json"]

#: keys holding measured wall-clock durations
TIMING_KEYS = ("seconds",)


def certificate_json(certificate: Certificate, *, indent: int | None = 2) -> str:
    """The certificate as a strict JSON document (non-finite floats as strings)."""
    return json.dumps(certificate.to_dict(), indent=indent, allow_nan=False) + "\n"


def write_json(certificate: Certificate, path: str | Path) -> Path:
    """Write the certificate's JSON atomically to ``path``."""
    return atomic_write_text(path, certificate_json(certificate))


def certify_json(result: Any, *, indent: int | None = 2) -> str:
    """The JSON certificate of ``ssecert certify`` (a ``CertifyResult``).

    It holds the validated spec under ``spec`` (``name``, ``system`` with ``A``, ``C`` and
    ``sensors``, ``attack``, ``observer``, ``scenario``): the matrices the report shows.
    Measured durations (``seconds`` of solver runs and simulations) are moved
    from where they were measured to ``meta.timings``, keyed by that place:
    with ``meta.date`` they are the only fields that change when a report is
    regenerated from the same spec, seed and version.
    """
    document = result.to_dict()
    # the spec as validated, so that A, C and the observer shown in the report are here in full
    document["spec"] = to_jsonable(spec_document(result.spec))
    # the analysis's own step times (``analyze``), then those measured in the checks
    timings: dict[str, Any] = dict(document.get("meta", {}).pop("timings", {}))
    _move_timings(document, "", timings)
    if timings:
        meta = document.setdefault("meta", {})
        meta["timings"] = timings
    return json.dumps(document, indent=indent, allow_nan=False) + "\n"


def _move_timings(node: Any, path: str, timings: dict[str, Any]) -> None:
    if isinstance(node, dict):
        for key in TIMING_KEYS:
            if key in node and isinstance(node[key], (int, float)):
                timings[f"{path}.{key}" if path else key] = node.pop(key)
        for key, value in node.items():
            _move_timings(value, f"{path}.{key}" if path else str(key), timings)
    elif isinstance(node, list):
        for i, value in enumerate(node):
            _move_timings(value, f"{path}[{i}]", timings)
