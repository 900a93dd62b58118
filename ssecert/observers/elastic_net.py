"""The elastic-net observer of the thesis: shrink q in (0, 1) and a weighting L2.

Spec keys: ``gain`` (``"deadbeat"``, the default, ``"place"`` with
``poles``, ``"ogd"``, ``"pinv"``, or an n x p matrix), ``step`` and
``threshold`` (> 0), ``shrink`` (required, in (0, 1)), ``L2`` (p x p,
default identity).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

from ..system import System
from .base import (
    DESIGN_SHRINKS,
    DESIGN_STEPS,
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
    from hypothesis.strategies import SearchStrategy

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
    aliases = ("elastic-net",)
    label = "the elastic-net observer"
    design_objectives = ("gain", "rate", "noise")
    design_default_for = ("gain", "rate", "noise")

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

    def design_axes(self, objective: str) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
        """The shrinks and the steps."""
        return DESIGN_SHRINKS, DESIGN_STEPS

    def design_section(
        self, system: System, row: Any, col: Any, *, threshold: float
    ) -> dict[str, Any]:
        section = super().design_section(system, row, col, threshold=threshold)
        section["shrink"] = row
        return section

    def parameter_strategy(self, system: System) -> SearchStrategy[dict[str, Any]]:
        """deadbeat, place, ogd, pinv or an explicit matrix (where it can be computed), step
        in [0.05, 1], threshold in [0.01, 0.5], shrink in [0.1, 0.95] and, half the draws,
        a diagonal L2 with entries in [0.5, 1]."""
        import numpy as np
        from hypothesis import strategies as st

        from .strategies import SHRINK, STEP, THRESHOLD, gain_drawer, real

        draw_gain = gain_drawer(system, ("deadbeat", "place", "ogd", "pinv", "matrix"))

        @st.composite
        def tables(draw: Any) -> dict[str, Any]:
            out = draw_gain(draw)
            out["step"] = real(draw, STEP)
            out["threshold"] = real(draw, THRESHOLD)
            out["shrink"] = real(draw, SHRINK)
            if draw(st.booleans()):
                weights = [real(draw, (0.5, 1.0)) for _ in range(system.p)]
                out["L2"] = np.diag(weights).tolist()
            return out

        return tables()
