"""The Luenberger observer: x_hat+ = A x_hat + L (y - C x_hat).

Spec keys: ``gain`` (``"deadbeat"``, the default, ``"place"`` with
``poles``, ``"pinv"``, or an n x p matrix).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

from ..budget import Budget
from ..system import System
from ..tolerances import Tolerances
from .base import (
    POLES_SCHEMA,
    ObserverDesign,
    ObserverKind,
    check_finite,
    gain_from_choice,
    gain_schema,
    parse_gain,
)
from .registry import register
from .simulators import LinearObserver

if TYPE_CHECKING:  # annotations only: the spec package imports the observers
    from hypothesis.strategies import SearchStrategy

    from ..spec.table import SpecTable

__all__ = ["Luenberger"]


@register
class Luenberger(ObserverKind):
    name = "luenberger"
    keys = ("kind", "gain", "poles")
    key_schemas: ClassVar[Mapping[str, Any]] = {
        "gain": gain_schema(("deadbeat", "place", "pinv")),
        "poles": POLES_SCHEMA,
    }
    label = "the Luenberger observer"
    design_objectives = ("gain", "rate", "noise")

    def parse(self, table: SpecTable, n: int, p: int) -> dict[str, Any]:
        return parse_gain(table, n, p, ("deadbeat", "place", "pinv"))

    def build(
        self, system: System, params: Mapping[str, Any], budget: Budget, tolerances: Tolerances
    ) -> ObserverDesign:
        gain = check_finite(gain_from_choice(system, params, tolerances))
        return ObserverDesign(kind=self.name, system=system, gain=gain, sensing=system.C)

    def simulator(self, design: ObserverDesign) -> LinearObserver:
        return LinearObserver(design.system.A, design.system.C, design.gain.L)

    def parameter_strategy(self, system: System) -> SearchStrategy[dict[str, Any]]:
        """deadbeat, place, pinv or an explicit matrix, where it can be computed."""
        from hypothesis import strategies as st

        from .strategies import gain_drawer

        draw_gain = gain_drawer(system, ("deadbeat", "place", "pinv", "matrix"))
        return st.composite(lambda draw: draw_gain(draw))()
