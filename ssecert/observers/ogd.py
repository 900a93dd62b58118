"""The online-gradient observer (lecture notes Sec. 4.2): L = step * A C^T.

Spec keys: ``step`` (required, > 0); ``gain`` may only say ``"ogd"``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..budget import Budget
from ..design.gains import ogd_gain
from ..system import System
from ..tolerances import Tolerances
from .base import POSITIVE_SCHEMA, ObserverDesign, ObserverKind, check_finite
from .registry import register
from .simulators import LinearObserver

if TYPE_CHECKING:  # annotations only: the spec package imports the observers
    from hypothesis.strategies import SearchStrategy

    from ..spec.table import SpecTable

__all__ = ["OnlineGradient"]


@register
class OnlineGradient(ObserverKind):
    name = "ogd"
    keys = ("kind", "gain", "step")
    key_schemas: ClassVar[Mapping[str, Any]] = {
        "gain": {"const": "ogd", "default": "ogd"},
        "step": POSITIVE_SCHEMA,
    }
    required_keys = ("step",)

    def parse(self, table: SpecTable, n: int, p: int) -> dict[str, Any]:
        gain = table.get("gain", "ogd")
        if not isinstance(gain, str):
            raise table.error(
                "gain", "the ogd observer's gain is fixed (L = step * A C^T); remove this key"
            )
        if gain != "ogd":
            raise table.error(
                "gain", f"the ogd observer's gain is fixed (L = step * A C^T); got {gain!r}"
            )
        return {"gain": table.choice("gain", gain, ("ogd",)), "step": table.positive("step")}

    def build(
        self, system: System, params: Mapping[str, Any], budget: Budget, tolerances: Tolerances
    ) -> ObserverDesign:
        step = params["step"]
        gain = check_finite(ogd_gain(system, step))
        return ObserverDesign(
            kind=self.name, system=system, gain=gain, sensing=system.C, step=float(step)
        )

    def simulator(self, design: ObserverDesign) -> LinearObserver:
        return LinearObserver(design.system.A, design.system.C, design.gain.L)

    def parameter_strategy(self, system: System) -> SearchStrategy[dict[str, Any]]:
        """step f / ||C||^2, f in [0.05, 1]."""
        from hypothesis import strategies as st

        from .strategies import STEP, real

        norm_C = max(float(np.linalg.norm(system.C, 2)), 1e-300)
        return st.composite(lambda draw: {"step": real(draw, STEP) / norm_C**2})()
