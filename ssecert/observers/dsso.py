"""The decoupled sparse soft observer (D-SSO) of the thesis, shrink 1.

Spec keys: ``gain`` (``"deadbeat"``, the default, ``"pinv"``, ``"place"``
with ``poles``, or an n x p matrix), ``step`` and ``threshold`` (> 0),
``shrink`` (1 if given).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..budget import Budget
from ..system import System
from ..tolerances import Tolerances
from .base import (
    DESIGN_STEPS,
    POLES_SCHEMA,
    POSITIVE_SCHEMA,
    UNIT_SHRINK_SCHEMA,
    ObserverDesign,
    ObserverKind,
    check_finite,
    gain_from_choice,
    gain_schema,
    parse_gain,
    parse_unit_shrink,
    soft_lure_model,
)
from .dynamic import DynamicObserver
from .lure import LureModel
from .registry import register
from .simulators import SparseSoftObserver

if TYPE_CHECKING:  # annotations only: the spec package imports the observers
    from hypothesis.strategies import SearchStrategy

    from ..spec.table import SpecTable

__all__ = ["DecoupledSSO", "SoftThresholdObserverKind"]


class SoftThresholdObserverKind(ObserverKind):
    """A Luenberger-type observer with a soft-thresholded attack estimate (D-SSO, elastic net)."""

    estimates_attack = True

    def build(
        self, system: System, params: Mapping[str, Any], budget: Budget, tolerances: Tolerances
    ) -> ObserverDesign:
        gain = check_finite(gain_from_choice(system, params, tolerances))
        m = system.p
        L2 = params.get("L2")
        return ObserverDesign(
            kind=self.name,
            system=system,
            gain=gain,
            sensing=system.C,
            step=float(params["step"]),
            threshold=float(params["threshold"]),
            shrink=float(params.get("shrink", 1.0)),
            L2=np.eye(m) if L2 is None else np.asarray(L2, dtype=float),
        )

    def simulator(self, design: ObserverDesign) -> DynamicObserver:
        return SparseSoftObserver(
            design.system.A,
            design.sensing,
            design.gain.L,
            step=design.parameter("step"),
            threshold=design.parameter("threshold"),
            shrink=design.shrink,
            L2=design.L2,
        )

    def lure_form(self, design: ObserverDesign) -> LureModel:
        return soft_lure_model(design)

    def region_family(self, design: ObserverDesign) -> ObserverDesign | None:
        return replace(design, kind="elastic_net")

    def design_section(
        self, system: System, row: Any, col: Any, *, threshold: float
    ) -> dict[str, Any]:
        """The gain to synthesise, the step ``col`` and the threshold."""
        section = super().design_section(system, row, col, threshold=threshold)
        section.update(step=col, threshold=threshold)
        return section


@register
class DecoupledSSO(SoftThresholdObserverKind):
    name = "dsso"
    keys = ("kind", "gain", "poles", "step", "threshold", "shrink")
    key_schemas: ClassVar[Mapping[str, Any]] = {
        "gain": gain_schema(("deadbeat", "pinv", "place")),
        "poles": POLES_SCHEMA,
        "step": POSITIVE_SCHEMA,
        "threshold": POSITIVE_SCHEMA,
        "shrink": UNIT_SHRINK_SCHEMA,
    }
    required_keys = ("step", "threshold")
    label = "the D-SSO"
    design_note = "shrink 1"
    design_objectives = ("gain", "rate", "roa")
    design_default_for = ("roa",)

    def parse(self, table: SpecTable, n: int, p: int) -> dict[str, Any]:
        out = parse_gain(table, n, p, ("deadbeat", "pinv", "place"))
        out["step"] = table.positive("step")
        out["threshold"] = table.positive("threshold")
        out["shrink"] = parse_unit_shrink(table, self.name, "elastic_net")
        return out

    def design_axes(self, objective: str) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
        """The steps; for the region of attraction also the deadbeat gain beside the
        synthesised one."""
        rows = ("deadbeat", "synthesised") if objective == "roa" else (1.0,)
        return rows, DESIGN_STEPS

    def design_section(
        self, system: System, row: Any, col: Any, *, threshold: float
    ) -> dict[str, Any]:
        section = super().design_section(system, row, col, threshold=threshold)
        if row == "deadbeat":
            section["gain"] = "deadbeat"
        return section

    def design_hint(self, system: System, objective: str) -> str:
        """Shrink 1 rarely admits a global certificate: the elastic net, or the region of
        attraction."""
        if objective == "roa":
            return ""
        at_one = np.any(np.abs(np.linalg.eigvals(system.A) - 1.0) <= 1e-9)
        why = (
            "the plant has an eigenvalue at 1, so no quadratic certificate can exist"
            if at_one
            else "its sector [0, 1] contains the identity, which quadratic certificates "
            "rarely survive"
        )
        return (
            f"a D-SSO has shrink 1 and {why}; try --observer elastic-net, or --objective roa "
            "for the largest certified region of attraction"
        )

    def parameter_strategy(self, system: System) -> SearchStrategy[dict[str, Any]]:
        """deadbeat, place, pinv or an explicit matrix (where it can be computed), step in
        [0.05, 1], threshold in [0.01, 0.5]."""
        from hypothesis import strategies as st

        from .strategies import STEP, THRESHOLD, gain_drawer, real

        draw_gain = gain_drawer(system, ("deadbeat", "place", "pinv", "matrix"))

        @st.composite
        def tables(draw: Any) -> dict[str, Any]:
            out = draw_gain(draw)
            out["step"] = real(draw, STEP)
            out["threshold"] = real(draw, THRESHOLD)
            return out

        return tables()
