"""What every observer kind provides, and the design it builds.

Every observer of ssecert is written

    x_hat(k+1) = A x_hat(k) + L (y(k) - y_hat(k)),   y_hat = S x_hat + a_hat,
    a_hat(k+1) = shrink * S_threshold(a_hat(k) - step * L2 (y_hat(k) - y(k))),

with S the sensing matrix (C, or the stacked O_tau for an SSO with window
tau > 1) and the attack estimate absent for observers that do not estimate
the attack.  The error matrix of the linear part is F = A - L S.

An observer kind (one module of this package each) is a subclass of
``ObserverKind`` registered under the name a spec's ``[observer] kind``
gives.  It reads its spec table, builds an ``ObserverDesign``, writes the
design's error dynamics in Lur'e form for the certificates, gives the
batched simulator, says what ``ssecert design`` searches (``design_axes``,
``design_section``) and draws its parameters for ``ssecert.testing``
(``parameter_strategy``); spec loading, certification, simulation, the
report, the design command and the strategies use only these methods and
attributes and never a kind's name.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..budget import Budget
from ..design.gains import (
    Gain,
    GainError,
    GainMethod,
    deadbeat_gain,
    ogd_gain,
    pinv_gain,
    place_gain,
)
from ..numerics.exact_powers import Dyadic, ExactMatrix, as_dyadic, dyadic, exact_error_matrix
from ..system import System, discrete_time
from ..tolerances import Tolerances, product_rounding
from .lure import EXACT_ENTRIES, ExactLure, LureModel

if TYPE_CHECKING:
    from hypothesis.strategies import SearchStrategy

    from ..spec.table import SpecTable
    from .dynamic import DynamicObserver

__all__ = ["ObserverDesign", "ObserverKind", "LINEAR_GAINS", "GAIN_CHOICES"]

LINEAR_GAINS = ("deadbeat", "place", "pinv")
# gains the spec defines by a step (L = step A S^T): exact from the step, not from the floats;
# gain methods (``Gain.method``), whatever kind's design holds them (an SSO's region family is
# an elastic-net design with the SSO's gain)
#: the method of the SSO's gain L = step A O_tau^T (its kind names it; not a GainMethod)
SSO_GAIN = "sso"
DERIVED_GAINS = (GainMethod.OGD, SSO_GAIN)
GAIN_CHOICES = ("deadbeat", "place", "ogd", "pinv")
# the grids ``ssecert design`` searches for the kinds with a step, and a shrink
# (``ssecert.design.search.STEPS`` and ``SHRINKS``)
DESIGN_STEPS = (0.1, 0.3, 0.5, 0.7, 1.0)
DESIGN_SHRINKS = (0.3, 0.5, 0.7, 0.9)


@dataclass(frozen=True)
class ObserverDesign:
    """A fully specified observer for a plant.

    Attributes
    ----------
    kind : str
        The name of its ``ObserverKind``.
    system : System
    gain : Gain
        L with its verification.
    sensing : ndarray, shape (m, n)
        Output matrix the observer uses: C, or O_tau for an SSO window.
    step, threshold, shrink : float or None
        nu (or epsilon), lambda and q; None for linear observers.
    L2 : ndarray, shape (m, m), or None
    window, inner_steps : int
    parameters : dataclass instance or None
        The kind's own parameters beyond the general form above (a frozen dataclass the
        kind declares, shown with the design); None for the built-in kinds, which the
        general form describes.
    """

    kind: str
    system: System
    gain: Gain
    sensing: np.ndarray
    step: float | None = None
    threshold: float | None = None
    shrink: float = 1.0
    L2: np.ndarray | None = None
    window: int = 1
    inner_steps: int = 1
    parameters: Any = None

    @property
    def observer_kind(self) -> ObserverKind:
        """The registered kind that built this design."""
        from .registry import get_kind

        return get_kind(self.kind)

    @property
    def L(self) -> np.ndarray:
        return self.gain.L

    @property
    def error_matrix(self) -> np.ndarray:
        """The linear error dynamics while the attack estimate is zero (F = A - L S)."""
        return self.observer_kind.error_matrix(self)

    @property
    def sparse(self) -> bool:
        """True for observers that also estimate the attack."""
        return self.observer_kind.estimates_attack

    def to_control(self, plant: Any = None) -> Any:
        """The observer as a discrete-time python-control ``StateSpace``, where it is linear.

        A Luenberger observer x_hat(k+1) = (A - L C) x_hat(k) + L y(k): inputs the sensors
        (by name), outputs the estimate ``x_hat[0]`` ... (sampling time unspecified, ``dt =
        True``).  With ``plant``, the python-control ``StateSpace`` the system came from
        (``System.from_control``), its known input u enters as it enters the plant,
        x_hat(k+1) = (A - L C) x_hat(k) + L y(k) + (B - L D) u(k), after the sensors as
        inputs (the plant's input names), and the plant's sampling time is kept: without it
        the estimate of a plant driven by u does not converge.

        Raises
        ------
        ValueError
            For an observer that estimates the attack (its soft thresholds are not linear),
            naming the linear part it has; for a ``plant`` whose A and C are not the system's.
        TypeError
            For a ``plant`` that is not a python-control ``StateSpace``.
        """
        if self.sparse or self.window != 1:
            rows, cols = self.error_matrix.shape
            raise ValueError(
                f"a {self.kind} observer is not linear (its soft thresholds estimate the "
                "attack), so it has no StateSpace; its linear error dynamics while the attack "
                f"estimate is zero are its error_matrix (F = A - L S, {rows} x {cols})"
            )
        import control

        A, L = self.system.A, self.L
        n, p = L.shape
        inputs, B_hat, dt = list(self.system.sensors), L, True
        if plant is not None:
            B, D, dt = _plant_input(plant, self.system)
            names = [f"u[{i}]" for i in range(B.shape[1])]
            labels = list(getattr(plant, "input_labels", names))
            inputs += labels if len(set(labels) | set(inputs)) == len(labels) + p else names
            B_hat = np.hstack([L, B - L @ D])
        return control.ss(
            A - L @ self.sensing,
            B_hat,
            np.eye(n),
            np.zeros((n, B_hat.shape[1])),
            dt,
            inputs=inputs,
            outputs=[f"x_hat[{i}]" for i in range(n)],
            name=f"{self.system.name}_observer",
        )

    def to_dict(self) -> dict[str, Any]:
        return self.observer_kind.describe(self)

    def parameter(self, name: str) -> float:
        """``step`` or ``threshold`` of a design that has it; ValueError otherwise."""
        value = getattr(self, name)
        if value is None:
            raise ValueError(f"the {self.kind} observer design has no {name}")
        return float(value)


class ObserverKind:
    """One kind of observer: what the spec says, and what certification and simulation need.

    Subclasses set the class attributes and implement ``parse``, ``build``
    and ``simulator``; the defaults of the other methods fit an observer
    x_hat+ = A x_hat + L (y - S x_hat) (with an attack estimate when
    ``estimates_attack``).  Register a subclass with
    ``ssecert.observers.register``.

    Attributes
    ----------
    name : str
        The spec's ``[observer] kind``.
    keys : tuple of str
        The keys its ``[observer]`` table may hold (``kind`` included).
    estimates_attack : bool
        True when the observer also estimates the attack (a sparse
        observer): its certificates are LMIs on a Lur'e model, the thesis's
        assumptions are checked, and its certified (shrink, step) region is
        mapped.
    key_schemas : mapping, optional
        A JSON Schema for each of ``keys`` but ``kind`` (the spec file's
        schema, ``ssecert.schemas.spec_schema``, is built from them).
    required_keys : tuple of str
        The keys the table must hold.
    aliases : tuple of str
        Other names the command line accepts for it (``ssecert design --observer``); its
        help writes the first.
    label, design_note : str
        How messages name it ("the D-SSO") and what sets it apart ("shrink 1").
    design_objectives : tuple of str
        The objectives of ``ssecert design`` it can be designed for (``design_axes`` and
        ``design_section`` say how); none: ``ssecert design`` does not offer it.
    design_default_for : tuple of str
        The objectives for which ``ssecert design`` designs it when no kind is named.
    """

    name: ClassVar[str]
    keys: ClassVar[tuple[str, ...]]
    estimates_attack: ClassVar[bool] = False
    #: JSON Schemas of its keys but ``kind`` (``ssecert.schemas``; a kind without them is
    #: described as an object with its ``kind``), and those it requires
    key_schemas: ClassVar[Mapping[str, Any] | None] = None
    required_keys: ClassVar[tuple[str, ...]] = ()
    aliases: ClassVar[tuple[str, ...]] = ()
    label: ClassVar[str] = ""
    design_note: ClassVar[str] = ""
    design_objectives: ClassVar[tuple[str, ...]] = ()
    design_default_for: ClassVar[tuple[str, ...]] = ()

    def parse(self, table: SpecTable, n: int, p: int) -> dict[str, Any]:
        """The validated parameters of an ``[observer]`` table (``kind`` excluded).

        ``table.check_keys(self.keys)`` has passed.  Raise ``table.error``
        for a wrong value.
        """
        raise NotImplementedError(f"observer kind {self.name!r} does not read a spec table")

    def build(
        self, system: System, params: Mapping[str, Any], budget: Budget, tolerances: Tolerances
    ) -> ObserverDesign:
        """The design for ``system`` from the validated parameters.

        Raise ``GainError`` when the gain cannot be computed and
        ``ResourceLimitError`` (``budget.require``) when its matrices would
        not fit the memory budget.
        """
        raise NotImplementedError(f"observer kind {self.name!r} does not build designs")

    def simulator(self, design: ObserverDesign) -> DynamicObserver:
        """The batched simulator of ``design`` (``ssecert.observers.dynamic``)."""
        raise NotImplementedError(f"observer kind {self.name!r} cannot be simulated")

    def error_matrix(self, design: ObserverDesign) -> np.ndarray:
        """The linear error dynamics while the attack estimate is zero: F = A - L S."""
        return design.system.A - design.gain.L @ design.sensing

    def exact_sensing(self, design: ObserverDesign) -> np.ndarray | Dyadic:
        """The sensing matrix S as the design defines it: the floats of C (a float matrix is
        its own exact value), or an exact ``Dyadic`` when S is a product (O_tau)."""
        return design.sensing

    def exact_gain(self, design: ObserverDesign) -> np.ndarray | Dyadic:
        """The gain L as the spec defines it: the printed floats of a matrix, deadbeat, place
        or pinv gain (the design's output), or for a gain derived from the step (``ogd``, the
        SSO's L = step A S^T) its exact value, of which the printed floats are the rounding."""
        step = design.gain.details.get("step")
        if design.gain.method in DERIVED_GAINS and step is not None:
            S = as_dyadic(self.exact_sensing(design))
            return (dyadic(design.system.A) @ S.T).times(float(step))
        return design.gain.L

    def gain_rounding(self, design: ObserverDesign) -> float:
        """An a-priori bound on ||L_printed - L_exact||_2 (0 for a gain that is its floats)."""
        step = design.gain.details.get("step")
        if design.gain.method in DERIVED_GAINS and step is not None:
            S = self.exact_sensing(design)
            if isinstance(S, Dyadic):
                return math.inf  # a product itself: measured on the exact value instead
            return product_rounding(design.system.A, S.T, scale=float(step))
        return 0.0

    def exact_error(self, design: ObserverDesign) -> ExactMatrix:
        """The exact F = A - L S of the spec's data (the floats of A and S, the gain as
        ``exact_gain`` defines it), of which ``error_matrix`` is the rounding; formed on
        demand."""
        S = self.exact_sensing(design)
        L = self.exact_gain(design)
        bound = None
        dL = self.gain_rounding(design)
        if not isinstance(S, Dyadic) and math.isfinite(dL):
            normS = float(np.linalg.norm(S, 2)) * (1 + 1e-12)
            bound = product_rounding(design.gain.L, S, design.system.A) + dL * normS
        if isinstance(L, Dyadic):
            return ExactMatrix.error_matrix(
                design.system.A,
                L,
                S,
                bound=bound,
                source=(
                    "F = A - L C with L = step A C^T, formed exactly from the floats of A, C "
                    "and the step"
                    if design.window == 1
                    else f"F = A - L O_tau with L = step A O_tau^T (window tau = {design.window}), "
                    "formed exactly from the floats of A, C and the step"
                ),
            )
        return ExactMatrix.error_matrix(design.system.A, L, S, bound=bound)

    def lure_model(self, design: ObserverDesign) -> LureModel:
        """The error dynamics in Lur'e form, for the LMI certificates.

        The default is e+ = F e + L a with no nonlinearity.  Raises
        NotImplementedError, with the reason, when ``lure_gap`` gives one.
        """
        gap = self.lure_gap(design)
        if gap:
            raise NotImplementedError(gap)
        return self.lure_form(design)

    def lure_form(self, design: ObserverDesign) -> LureModel:
        """The Lur'e model itself (``lure_model`` has checked ``lure_gap``); linear by default."""
        F = self.error_matrix(design)
        exact = self.exact_error(design)
        return LureModel.linear(
            F,
            design.gain.L,
            exact_F=lambda: exact.value,
            formation_error=exact.bound if exact.bound is not None else math.inf,
        )

    def lure_gap(self, design: ObserverDesign) -> str | None:
        """Why ``design`` has no Lur'e form (so no LMI certificate), or None.

        Asked before the model is built, so that a design without one costs
        no memory.
        """
        return None

    def dead_zone_refusal(self, design: ObserverDesign) -> str:
        """Why ``dead_zone_model`` would be too large to build and certify ('' when it is not):
        the size in the spec that makes it so, asked before anything is allocated."""
        return ""

    def dead_zone_model(self, design: ObserverDesign, *, noise: bool = False) -> LureModel | None:
        """For a design without a Lur'e form (``lure_gap``): its error dynamics while every soft
        threshold stays in its dead zone, as a Lur'e model with B = 0 (xi+ = A xi) whose rows
        Cw are every threshold's input, so that the region-of-attraction search applies; None
        when the kind has none.  With ``noise``, its input (E, Dw) is the measurement
        vector's noise, entering as an attack on every row does (None when the kind does not
        form it).  Raises ``ResourceLimitError`` when ``dead_zone_refusal`` gives a
        reason."""
        return None

    def region_family(self, design: ObserverDesign) -> ObserverDesign | None:
        """The design whose (shrink, step) the certified-region map varies, or None."""
        return None

    def simulation_flops(self, design: ObserverDesign) -> float:
        """Operations of one simulated step of one run (for the simulation's work estimate)."""
        n, p = design.system.n, design.system.p
        m = design.sensing.shape[0] if self.estimates_attack else 0
        return 2.0 * (n + m) * (n + 2 * m + p)

    def describe(self, design: ObserverDesign) -> dict[str, Any]:
        """What the certificate and the report show of the design."""
        out: dict[str, Any] = {"kind": design.kind, "gain_method": design.gain.method}
        out["L"] = design.gain.L
        if self.estimates_attack:
            out.update(
                step=design.step,
                threshold=design.threshold,
                shrink=design.shrink,
                L2=design.L2,
                window=design.window,
                inner_steps=design.inner_steps,
            )
        if design.parameters is not None:
            out.update(dataclasses.asdict(design.parameters))
        return out

    # What ``ssecert design`` and ``ssecert.testing`` ask of a kind

    def design_axes(self, objective: str) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
        """The two axes of the grid ``ssecert design`` searches for ``objective``: the values
        of each handed to ``design_section`` (one cell, the gain alone, by default)."""
        return (None,), (None,)

    def design_section(
        self, system: System, row: Any, col: Any, *, threshold: float
    ) -> dict[str, Any]:
        """The ``[observer]`` section of the grid cell (``row``, ``col``) of ``design_axes``.

        Its ``gain`` is a zero n x p matrix where the synthesis LMI is to choose it
        (``ssecert.design.synthesis``), or a named gain the design keeps as it is;
        ``threshold`` is the soft threshold the search keeps fixed, for a kind that has one.
        """
        return {"kind": self.name, "gain": np.zeros((system.n, system.p)).tolist()}

    def design_hint(self, system: System, objective: str) -> str:
        """What to try instead when ``ssecert design`` certified no design of this kind for
        ``objective`` ('' when nothing is suggested)."""
        return ""

    def parameter_strategy(self, system: System) -> SearchStrategy[dict[str, Any]]:
        """A hypothesis strategy of the keys of its ``[observer]`` table but ``kind``, valid
        for ``system`` (``ssecert.testing.observer_designs`` draws from it; a draw whose gain
        cannot be built is rejected there).  Import hypothesis inside: it is needed only for
        testing."""
        raise NotImplementedError(f"observer kind {self.name!r} has no parameter strategy")


# Shared by several kinds ---------------------------------------------------


#: JSON Schema fragments of the observers' keys (``ObserverKind.key_schemas``)
MATRIX_SCHEMA: dict[str, Any] = {
    "type": "array",
    "minItems": 1,
    "items": {"type": "array", "minItems": 1, "items": {"type": "number"}},
    "description": "a matrix as a list of rows",
}
POSITIVE_SCHEMA: dict[str, Any] = {"type": "number", "exclusiveMinimum": 0}
POLES_SCHEMA: dict[str, Any] = {
    "type": "array",
    "minItems": 1,
    "items": {
        "oneOf": [
            {"type": "number"},
            {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
        ]
    },
    "description": 'one pole per state (with gain = "place"): a number or [re, im], complex '
    "ones in conjugate pairs",
}
UNIT_SHRINK_SCHEMA: dict[str, Any] = {"const": 1, "description": "1 (the default)"}


def gain_schema(choices: tuple[str, ...]) -> dict[str, Any]:
    """The schema of ``gain``: one of ``choices`` or an n x p matrix."""
    return {"oneOf": [{"enum": list(choices)}, MATRIX_SCHEMA], "default": "deadbeat"}


def parse_gain(
    table: SpecTable, n: int, p: int, choices: tuple[str, ...], default: str = "deadbeat"
) -> dict[str, Any]:
    """``gain`` (one of ``choices`` or an n x p matrix) and, for ``place``, ``poles``."""
    out: dict[str, Any] = {}
    gain = table.get("gain", default)
    if isinstance(gain, str):
        gain = table.choice("gain", gain, choices)
    else:
        gain = table.matrix("gain", gain, shape=(n, p), shape_hint="n x p: states by sensors")
    out["gain"] = gain
    if isinstance(gain, str) and gain == "place":
        out["poles"] = table.poles("poles", n)
    elif "poles" in table:
        raise table.error("poles", 'poles are only used with gain = "place"')
    return out


def parse_unit_shrink(table: SpecTable, kind: str, instead: str) -> float:
    """The shrink of an SSO or D-SSO: 1, written or not (the kind ``instead`` for another)."""
    if "shrink" in table:
        shrink = table.real("shrink", table.get("shrink"))
        if shrink != 1.0:
            raise table.error(
                "shrink",
                f'the {kind} observer has shrink = 1; use kind = "{instead}" for '
                f"shrink < 1, got {shrink}",
            )
    return 1.0


def gain_from_choice(
    system: System, params: Mapping[str, Any], tolerances: Tolerances | None = None
) -> Gain:
    """The gain a validated ``gain`` (and ``poles``, ``step``) asks for.

    ``tolerances`` decide the deadbeat gain's power test (``deadbeat_rtol``,
    ``certificate_clear``); the other gains do not depend on them.
    """
    choice = params.get("gain", "deadbeat")
    if not isinstance(choice, str):
        L = np.asarray(choice, dtype=float)
        return Gain(
            L=L,
            method=GainMethod.MATRIX,
            error_matrix=system.A - L @ system.C,
            verified=True,
            details={},
        )
    if choice == "deadbeat":
        return deadbeat_gain(system, tolerances=tolerances)
    if choice == "place":
        return place_gain(system, params["poles"])
    if choice == "pinv":
        return pinv_gain(system)
    if choice == "ogd":
        return ogd_gain(system, params["step"])
    raise GainError(f"unknown gain {choice!r}")


def check_finite(gain: Gain) -> Gain:
    """``gain``, or GainError when L or A - L C overflows."""
    if not (np.all(np.isfinite(gain.L)) and np.all(np.isfinite(gain.error_matrix))):
        raise GainError(
            "the gain L or the error matrix A - L C has entries that overflow in floating point"
        )
    return gain


def soft_lure_model(design: ObserverDesign) -> LureModel:
    """The Lur'e form of an observer with a soft-thresholded attack estimate (one step).

    xi = (e, a_hat): A = [[F, -L], [0, 0]], B = [[0], [I]],
    Cw = [-step L2 S, I - step L2], E = [[L], [0]], Dw = step L2, and the
    nonlinearity shrink * soft_threshold in the sector [0, shrink].
    """
    A_p = design.system.A
    S = design.sensing
    n, m = A_p.shape[0], S.shape[0]
    L = design.gain.L
    F = A_p - L @ S
    nu = design.parameter("step")
    L2 = design.L2 if design.L2 is not None else np.eye(m)
    A = np.block([[F, -L], [np.zeros((m, n)), np.zeros((m, m))]])
    B = np.vstack([np.zeros((n, m)), np.eye(m)])
    Cw = np.hstack([-nu * L2 @ S, np.eye(m) - nu * L2])
    E = np.vstack([L, np.zeros((m, m))])
    Dw = nu * L2
    Ce = np.hstack([np.eye(n), np.zeros((n, m))])
    exact_S = design.observer_kind.exact_sensing(design)
    formation = _soft_formation_error(design, nu, L2)
    N = n + m
    fits = N * (N + 2 * m) + m * (N + m) <= EXACT_ENTRIES

    def build() -> ExactLure | None:
        if not fits:
            return None
        return _exact_soft_lure(A_p, design.observer_kind.exact_gain(design), exact_S, nu, L2)

    return LureModel(
        A,
        B,
        Cw,
        E,
        Dw,
        Ce,
        float(design.shrink),
        n,
        float(design.threshold or 0.0),
        build,
        formation,
        design.observer_kind.exact_error(design),
    )


def _soft_formation_error(design: ObserverDesign, nu: float, L2: np.ndarray) -> float:
    """A-priori bound on the rounding of the soft Lur'e model's float matrices (F, nu L2 S,
    I - nu L2 and nu L2), from Higham's bound on each product; inf for a sensing matrix that
    is itself a product (its rounding is measured on the exact model instead)."""
    if design.observer_kind.exact_sensing(design) is not design.sensing:
        return math.inf
    S, L, A_p = design.sensing, design.gain.L, design.system.A
    m = S.shape[0]
    dL = design.observer_kind.gain_rounding(design)  # in F (times ||S||), in -L and in E
    parts = [
        product_rounding(L, S, A_p) + dL * float(np.linalg.norm(S, 2)) * (1 + 1e-12),
        dL,
        dL,
        product_rounding(L2, S, scale=nu),
        product_rounding(L2, np.eye(m), np.eye(m), scale=nu),
        product_rounding(L2, np.eye(m), scale=nu),
    ]
    return math.sqrt(sum(v * v for v in parts)) * (1 + 1e-12)


def _exact_soft_lure(
    A_p: np.ndarray,
    L: np.ndarray | Dyadic,
    S: np.ndarray | Dyadic,
    nu: float,
    L2: np.ndarray,
) -> ExactLure:
    """The exact matrices of ``soft_lure_model`` from the floats of A, nu and L2 and the
    floats or exact values of L and S."""
    n = A_p.shape[0]
    Sd = as_dyadic(S)
    m = Sd.shape[0]
    Ld = as_dyadic(L)
    nuL2 = dyadic(L2).times(nu)
    if np.array_equal(L2, np.diag(np.diag(L2))):  # diagonal L2: scale rows, no product
        diag = dyadic(np.diag(L2)[:, None]).times(nu)
        nuL2S = Dyadic(Sd.ints * diag.ints, Sd.exponent + diag.exponent)
    else:
        nuL2S = nuL2 @ Sd
    I_m = Dyadic.eye(m)
    return ExactLure(
        A=Dyadic.block(
            [[exact_error_matrix(A_p, L, Sd), -Ld], [Dyadic.zeros((m, n)), Dyadic.zeros((m, m))]]
        ),
        B=Dyadic.block([[Dyadic.zeros((n, m))], [I_m]]),
        Cw=Dyadic.block([[-nuL2S, I_m - nuL2]]),
        E=Dyadic.block([[Ld], [Dyadic.zeros((m, m))]]),
        Dw=nuL2,
    )


def _plant_input(plant: Any, system: Any) -> tuple[np.ndarray, np.ndarray, Any]:
    """B, D and dt of the python-control plant ``system`` came from (``to_control``)."""
    import control

    if not isinstance(plant, control.StateSpace):
        raise TypeError(
            "plant must be the python-control StateSpace the system came from, got "
            f"{type(plant).__name__}"
        )
    A, C = np.asarray(plant.A, dtype=float), np.asarray(plant.C, dtype=float)
    if (
        A.shape != system.A.shape
        or C.shape != system.C.shape
        or not (np.array_equal(A, system.A) and np.array_equal(C, system.C))
    ):
        raise ValueError(
            f"plant: its A and C ({A.shape[0]} states, {C.shape[0]} outputs) are not the "
            f"system's ({system.n} states, {system.p} sensors): pass the StateSpace the system "
            "was made from"
        )
    dt = discrete_time(plant, "plant", "the observer is discrete-time")
    B, D = np.asarray(plant.B, dtype=float), np.asarray(plant.D, dtype=float)
    if not (np.all(np.isfinite(B)) and np.all(np.isfinite(D))):
        raise ValueError("plant: B and D must be finite to enter the observer")
    return B, D, dt
