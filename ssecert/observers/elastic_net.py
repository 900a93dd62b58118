"""The elastic-net observer of the thesis: shrink q in (0, 1) and a weighting L2.

Spec keys: ``gain`` (``"deadbeat"``, the default, ``"place"`` with
``poles``, ``"ogd"``, ``"pinv"``, or an n x p matrix), ``step`` and
``threshold`` (> 0), ``shrink`` (required, in (0, 1)), ``L2`` (p x p,
default identity).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

from .base import (
    GAIN_CHOICES,
    MATRIX_SCHEMA,
    POLES_SCHEMA,
    POSITIVE_SCHEMA,
    gain_schema,
    parse_gain,
)
from .dsso import SoftThresholdObserverKind
from .registry import register

if TYPE_CHECKING:  # annotations only: the spec package imports the observers
    from ..spec.table import SpecTable

__all__ = ["ElasticNet"]


@register
class ElasticNet(SoftThresholdObserverKind):
    name = "elastic_net"
    keys = ("kind", "gain", "poles", "step", "threshold", "shrink", "L2")
    key_schemas: ClassVar[Mapping[str, Any]] = {
        "gain": gain_schema(GAIN_CHOICES),
        "poles": POLES_SCHEMA,
        "step": POSITIVE_SCHEMA,
        "threshold": POSITIVE_SCHEMA,
        "shrink": {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 1},
        "L2": MATRIX_SCHEMA,
    }
    required_keys = ("step", "threshold", "shrink")

    def parse(self, table: SpecTable, n: int, p: int) -> dict[str, Any]:
        out = parse_gain(table, n, p, GAIN_CHOICES)
        out["step"] = table.positive("step")
        out["threshold"] = table.positive("threshold")
        out["shrink"] = table.real(
            "shrink",
            table.require("shrink"),
            min_value=0.0,
            max_value=1.0,
            min_inclusive=False,
            max_inclusive=False,
        )
        if "L2" in table:
            out["L2"] = table.matrix(
                "L2", table.get("L2"), shape=(p, p), shape_hint="p x p: sensors by sensors"
            )
        return out
