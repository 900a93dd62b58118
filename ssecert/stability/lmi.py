"""LMI certificates for the sparse observers, written as Lur'e systems.

With e = x_hat - x and the attack estimate a_hat, every sparse observer
(SSO, D-SSO, the elastic-net observer) is

    xi(k+1) = A xi(k) + B phi(w(k)) + E a(k),    xi = (e, a_hat),
    w(k)    = Cw xi(k) + Dw a(k),
    A = [[F, -L], [0, 0]],  B = [[0], [I]],  Cw = [-step L2 S, I - step L2],
    E = [[L], [0]],         Dw = step L2,

where F = A_plant - L S and phi = shrink * soft_threshold acts componentwise:
it lies in the sector [0, q] (q = shrink) and is slope-restricted in [0, q].

* ``circle_certificate``: V = xi' P xi decreases along every trajectory
  without attack, by the S-procedure with a diagonal multiplier T >= 0 on
  phi_i (q w_i - phi_i) >= 0.  Two structural facts come first:
  near the origin phi = 0 (dead zone), so an unstable F makes the origin
  locally unstable (fails); and the sector contains the linear map
  phi = q w, so if that closed loop A + q B Cw is not Schur no sector
  certificate can exist (inconclusive, with the reason; for shrink = 1 and
  an eigenvalue of A at 1 it has that eigenvalue: e = v, a_hat = -C v); nor
  when another corner of the channels' sectors, phi_i = k_i w_i with k_i in
  {0, q}, gives a loop that is not Schur (``channel_vertex_instability``, up
  to 12 channels): the LMIs are then not solved;
* ``iss_certificate``: V(xi+) - V(xi) <= -alpha V(xi) - |e|^2 + gamma^2 |a|^2,
  which gives input-to-state stability with decay alpha and the l2 gain
  gamma from attack to estimation error.

The LMIs are solved with cvxpy and Clarabel, first with the structure the
proof needs (P block diagonal between e and a_hat, diagonal on a_hat: ten
times faster on the thesis-sized plant), then, if that fails and the LMI is
small enough, with a full P.  Nothing is taken from the solver's status:
the LMI is recomputed in numpy from the returned P and T, symmetrised, and
its largest eigenvalue must beat a floating-point error bound by a factor
``clear``; P must pass a Cholesky test with a margin and T must be
nonnegative.  Otherwise the verdict is inconclusive.  The cvxpy problems
and their solve live in ``lmi_solver``, the recomputation and the
re-verification in ``lmi_verification``; this module decides.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import numpy as np

from ..budget import Budget, Refusal
from ..numerics.exact import UNITS_SPREAD
from ..observers.lure import LureModel, scaling_text
from ..results import Verdict
from ..solvers import solver_label
from . import lmi_messages
from .lmi_messages import corner_reason, verify_text
from .lmi_solver import ETA, _solve, lmi_cost  # noqa: F401  (ETA stays importable here)
from .lmi_verification import circle_matrix, iss_matrix, verify_certificate
from .outcomes import LMICause, LMICode, VerifyProblem

__all__ = [
    "LureModel",
    "LMICertificate",
    "circle_certificate",
    "iss_certificate",
    "iss_from_circle",
    "circle_matrix",
    "iss_matrix",
    "verify_certificate",
    "lmi_cost",
    "lure_model_cost",
    "channel_vertex_instability",
    "corner_reason",
    "balanced_retry",
    "output_scaled",
    "input_units",
    "in_input_units",
    "input_units_note",
    "sensor_units",
    "in_sensor_units",
    "to_original_coordinates",
    "where_verified",
]

FULL_LIMIT = 80  # largest LMI dimension tried with a full P
VERTEX_LIMIT = 12  # most channels whose 2^m corner loops are checked
# Lyapunov structures, cheapest first: P = diag(P1, D) with D diagonal; the
# same with a full cross block P12; a full P.
STRUCTURES = ("block-diagonal", "cross", "full")


def lure_model_cost(n: int, m: int, r: int) -> tuple[float, float]:
    """Bytes and operations of a Lur'e model with n error states, m nonlinearities and r
    attack inputs: its matrices, and the eigenvalues of its N x N closed loops (N = n + m)."""
    N = n + m
    nbytes = 8.0 * (3 * N * N + 2 * N * m + 2 * N * r + m * r + n * N + 2 * m * m)
    return nbytes, 30.0 * N**3


@dataclass(frozen=True)
class LMICertificate:
    """A verified (or not) LMI certificate.

    Attributes
    ----------
    verdict : Verdict
        Given as a Verdict or its name (``"holds"``, ``"fails"``,
        ``"inconclusive"``).
    kind : str
        ``"circle"`` or ``"iss"``.
    P : ndarray or None
        Lyapunov matrix (full, symmetric).
    multipliers : ndarray or None
        Diagonal of T.
    margin : float or None
        ``-lambda_max(LMI) / ||P||`` of the recomputed LMI.
    error_bound : float
        Floating-point error bound on that eigenvalue, same units.
    decay : float or None
        alpha with V(xi+) <= (1 - alpha) V(xi) (circle: without attack).
    gamma : float or None
        l2 gain from attack to estimation error (ISS).
    structure : str
        ``"block-diagonal"`` or ``"full"``.
    details : dict
        Solver status and times, pre-check results, witness.
    code : LMICode
        How it came out (verified, reused, refused, decided before the LMIs, solved and not
        verified...): decisions read it, never ``details``' keys or ``reason``.
    cause : LMICause
        Why, for the words (``reason``, written by ``lmi_messages``) and for tests.
    facts : mapping
        The numbers and names the words of ``cause`` need, and the ``notes`` gathered on the
        way (balanced retries, a second multiplier); not written to JSON.
    """

    verdict: Verdict
    kind: str
    P: np.ndarray | None = None
    multipliers: np.ndarray | None = None
    margin: float | None = None
    error_bound: float = 0.0
    decay: float | None = None
    gamma: float | None = None
    structure: str = ""
    details: dict[str, Any] = field(default_factory=dict)
    code: LMICode = field(kw_only=True)
    cause: LMICause = field(kw_only=True, default=LMICause.CERTIFIED)
    facts: Mapping[str, Any] = field(kw_only=True, default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "verdict", Verdict(self.verdict))  # a name is accepted too

    @property
    def reason(self) -> str:
        """Why it came out as it did, in words (``lmi_messages``; empty when it holds)."""
        return lmi_messages.reason(self.cause, self.facts)

    def noted(self, note: str) -> LMICertificate:
        """The same certificate with ``note`` (words from ``lmi_messages`` or another
        outcome's reason) after its reason."""
        return replace(self, facts={**self.facts, "notes": (*self.facts.get("notes", ()), note)})

    def evidence(self) -> dict[str, Any]:
        """JSON-serialisable evidence for re-verification."""
        return {
            "P": self.P,
            "multipliers_T": self.multipliers,
            "margin": self.margin,
            "error_bound": self.error_bound,
            "decay_alpha": self.decay,
            "gamma": self.gamma,
            "structure": self.structure,
            **self.details,
        }


def _model_refusal(model: LureModel, budget: Budget) -> Refusal | None:
    """Why the structural pre-checks (eigenvalues of N x N closed loops) are not affordable."""
    nbytes, flops = lure_model_cost(model.n_e, model.m, model.r)
    return budget.check(
        f"the Lur'e model with {model.N} states and {model.m} nonlinearities",
        nbytes=nbytes,
        flops=flops,
    )


def _solve_refusal(model: LureModel, kind: str, structure: str, budget: Budget) -> Refusal | None:
    nbytes, flops = lmi_cost(model, kind, structure)
    size = model.N + model.m + (model.r if kind == "iss" else 0)
    return budget.check(
        f"the {structure} LMI with {size} rows (cvxpy and {solver_label()})",
        nbytes=nbytes,
        flops=flops,
    )


def _prechecks(
    model: LureModel,
) -> tuple[Verdict | None, LMICause, dict[str, Any], dict[str, Any]]:
    """Structural facts that decide before any LMI is solved."""
    from .lyapunov import instability_witness

    n = model.n_e
    F = model.A[:n, :n]
    details: dict[str, Any] = {}
    if not model.finite():
        return Verdict.INCONCLUSIVE, LMICause.NOT_FINITE, {}, details
    rho_F = float(np.abs(np.linalg.eigvals(F)).max()) if n else 0.0
    details["spectral_radius_F"] = rho_F
    if rho_F >= 1 - 1e-12:
        from .spectral import SchurState, schur_decision

        decision = schur_decision(F, exact=model.exact_A(error_block=True))
        details["exact_decision"] = decision.to_dict()
        if decision.state is not SchurState.STABLE:
            witness = instability_witness(F, decision=decision)
            details["witness"] = witness
            if witness is not None and witness["verified"]:
                facts = {"decision": decision.reason, "channels": model.m}
                return Verdict.FAILS, LMICause.ERROR_MATRIX_UNSTABLE, facts, details
            facts = {"radius": rho_F, "decision": decision.reason}
            return Verdict.INCONCLUSIVE, LMICause.ERROR_MATRIX_UNDECIDED, facts, details
    if model.m:
        rho_q = float(np.abs(np.linalg.eigvals(model.vertex(model.q))).max())
        details["spectral_radius_at_sector_vertex"] = rho_q
        if rho_q >= 1 - 1e-9:
            from .spectral import SchurState, schur_decision

            vertex = schur_decision(model.vertex(model.q), exact=_exact_vertex(model))
            details["sector_vertex_decision"] = vertex.to_dict()
            if vertex.state is not SchurState.UNSTABLE:
                facts = {"q": model.q, "radius": rho_q, "decision": vertex.reason}
                return Verdict.INCONCLUSIVE, LMICause.VERTEX_WITHIN_ROUNDING, facts, details
            if model.q >= 1 - 1e-12:
                facts = {"radius": rho_q, "decision": vertex.reason, "rigorous": vertex.rigorous}
                return Verdict.INCONCLUSIVE, LMICause.IDENTITY_IN_SECTOR, facts, details
            facts = {"q": model.q, "decision": vertex.reason}
            return Verdict.INCONCLUSIVE, LMICause.VERTEX_UNSTABLE, facts, details
        corner = channel_vertex_instability(model)
        if corner is not None:
            details["channel_corner"] = corner
            return Verdict.INCONCLUSIVE, LMICause.CORNER_UNSTABLE, {"corner": corner}, details
    return None, LMICause.CERTIFIED, {}, details


def _exact_vertex(model: LureModel) -> Any:
    """The exact large-signal loop A + q B Cw of the spec's data (an ``ExactMatrix``; of the
    model's own floats when they are its data)."""
    from ..numerics.exact_powers import ExactMatrix

    def build() -> Any:
        exact = model.exact()
        if exact is None:
            return None
        return exact.A + (exact.B @ exact.Cw).times(model.q)

    return ExactMatrix(build, None, "the loop A + q B Cw formed exactly from the spec's data")


def _exact_corner(model: LureModel, gains: np.ndarray) -> Any:
    """The exact loop A + B diag(k) Cw of the spec's data for the corner ``gains`` (each 0 or
    the float q; of the model's own floats when they are its data)."""
    from ..numerics.exact_powers import Dyadic, ExactMatrix

    def build() -> Any:
        exact = model.exact()
        if exact is None:
            return None
        on = np.flatnonzero(gains)
        if on.size == 0:
            return exact.A
        B = Dyadic(exact.B.ints[:, on], exact.B.exponent)
        Cw = Dyadic(exact.Cw.ints[on, :], exact.Cw.exponent)
        return exact.A + (B @ Cw).times(model.q)

    return ExactMatrix(build, None, "the corner's loop formed exactly from the spec's data")


def channel_vertex_instability(model: LureModel) -> dict[str, Any] | None:
    """A corner k in {0, q}^m whose linear loop A + B diag(k) Cw is not Schur, or None.

    Each channel phi_i = k_i w_i with k_i in [0, q] is a sector (and slope)
    restricted nonlinearity, so a certificate that treats the channels
    separately (the circle criterion with a diagonal multiplier, the
    Zames-Falb multipliers here) would prove that loop stable: when it is not,
    no such certificate exists.  None also when m > ``VERTEX_LIMIT``.
    """
    m = model.m
    if m == 0 or m > VERTEX_LIMIT:
        return None
    corners = np.array(list(itertools.product((0.0, model.q), repeat=m)))
    loops = model.A[None] + np.einsum("ij,kj,jl->kil", model.B, corners, model.Cw)
    with np.errstate(all="ignore"):
        radii = np.abs(np.linalg.eigvals(loops)).max(axis=1)
    if not np.all(np.isfinite(radii)):
        return None
    worst = int(np.argmax(radii))
    if radii[worst] <= 1 + 1e-9:
        return None
    # the corner's loop formed exactly from the spec's data must be unstable too
    from .spectral import SchurState, schur_decision

    decision = schur_decision(loops[worst], exact=_exact_corner(model, corners[worst]))
    if decision.state is not SchurState.UNSTABLE:
        return None
    return {
        "gains": corners[worst],
        "spectral_radius": float(radii[worst]),
        "corners": int(corners.shape[0]),
        "unstable_corners": int((radii > 1 + 1e-9).sum()),
    }


def to_original_coordinates(
    cert: LMICertificate,
    s: np.ndarray,
    N: int,
    sensors: int = 0,
    channels: np.ndarray | None = None,
) -> LMICertificate | None:
    """A certificate of ``model.scaled(s, sensors, channels)`` written for ``model`` (None
    if not exactly).

    With xi = diag(s) xi_b the Lyapunov function zeta_b' P_b zeta_b is zeta' P zeta with
    P = T P_b T, T = diag(1 / s, ...) (``SensorUnits.coordinates``: the first N coordinates
    are states; a Zames-Falb certificate's lifted past inputs and outputs follow, each times
    its channel's 2^j): exact for powers of two.  With the channels and the attack in units
    2^-sensors (sigma = 2^sensors times the user's), the sector multipliers and gamma^2 are
    sigma^2 times those of the scaled model; with ``channels``, each channel's multiplier
    (and its Zames-Falb delays) is 4^channels[i] times its own (gamma^2 still 4^sensors).
    Every number written back must give the verified one back exactly when its power of two
    is undone (none beyond the floats or rounded into the subnormals); else None.  The
    margin and error bound stay those verified in the balanced coordinates, where the LMI
    is recomputed; ``state_scaling`` records s (``sensor_exponent`` the attack's units,
    ``channel_exponents`` the channels').
    """
    if cert.P is None:
        return None
    j = int(sensors)
    per = None if channels is None else np.asarray(channels, dtype=np.int64)
    units = SensorUnits(np.asarray(s, dtype=float), j, per)
    m = 0 if cert.multipliers is None else int(np.size(cert.multipliers))
    if cert.P.shape[0] > N and m == 0:
        return None  # a lifted P without its channels
    inv = units.coordinates(cert.P.shape[0], m)
    with np.errstate(over="ignore", invalid="ignore"):  # beyond the floats: no certificate
        P = cert.P * inv[:, None] * inv[None, :]
        t = (
            None
            if cert.multipliers is None
            else np.ldexp(cert.multipliers, units.multiplier_exponents)
        )
    if not np.all(np.isfinite(P)) or not np.array_equal(P / inv[:, None] / inv[None, :], cert.P):
        return None
    if t is not None and not _undone(t, cert.multipliers, units.multiplier_exponents):
        return None
    where = "the balanced coordinates xi = diag(state_scaling) xi_b"
    if per is not None:
        where += (
            f", with each channel and its part of the nonlinearity's output in units "
            f"2^-channel_exponents[i] (its multiplier times 4^channel_exponents[i] there) and "
            f"the attack in units 2^{-j} (sensor_exponent: gamma^2 times 4^{j} there)"
        )
    elif j:
        where += (
            f", with the channels, the nonlinearity's output and the attack in units 2^{-j} "
            f"(sensor_exponent: multipliers and gamma^2 times 4^{j} there)"
        )
    eta = ", eta" if "eta" in cert.details else ""  # (a Zames-Falb certificate's)
    details = {
        **cert.details,
        **units.delays(cert, back=True),
        "state_scaling": np.asarray(s, dtype=float),
        "margin_coordinates": f"margin and error_bound{eta} are those of the LMI recomputed "
        f"in {where}, where it was verified; P is written for the spec's coordinates, where the "
        "same inequality holds by congruence, with its margin relative to ||P|| changed by the "
        "scaling"
        + (
            " (and eta divided by max(state_scaling)^2: V(zeta+) - V(zeta) + sigma <= -eta "
            "|xi_b|^2 <= -eta / max(state_scaling)^2 |xi|^2)"
            if eta
            else ""
        ),
    }
    gamma = cert.gamma
    if per is not None:
        details["channel_exponents"] = per.tolist()
    # every number written back must be exactly the one verified, times its power of two
    # (beyond the floats, or into the subnormals where bits are lost: no certificate)
    # (the number written back, the one verified, the power of two between)
    written: list[tuple[Any, Any, Any]] = []
    for key in ("u_delays", "v_delays"):
        if key in details:
            k = 2 * units.channel_exponents(np.shape(details[key])[-1])
            written.append((details[key], cert.details[key], k))
    with np.errstate(over="ignore"):
        if j or per is not None:
            details["sensor_exponent"] = j
            if gamma is not None:
                gamma = float(np.ldexp(gamma, j))
                written.append((gamma, cert.gamma, j))
            if details.get("gamma_squared") is not None:
                details["gamma_squared"] = float(np.ldexp(details["gamma_squared"], 2 * j))
                written.append((details["gamma_squared"], cert.details["gamma_squared"], 2 * j))
    if not all(_undone(x, x_b, k) for x, x_b, k in written):
        return None
    if "sum_bound_factor" in details:  # sum |xi|^2 <= max(s)^2 sum |xi_b|^2
        with np.errstate(over="ignore"):
            details["sum_bound_factor"] = float(
                np.float64(np.max(s)) ** 2
                * np.float64(np.linalg.eigvalsh(P[:N, :N])[-1])
                / details["eta"]
            )
    return replace(cert, P=P, multipliers=t, gamma=gamma, details=details)


def _undone(value: Any, before: Any, exponents: Any) -> bool:
    """Whether ``value`` = ``before`` 2^exponents exactly: finite, and the power of two
    undone gives ``before`` back bit for bit (no overflow, no bits lost to the subnormals)."""
    value = np.asarray(value, dtype=float)
    with np.errstate(over="ignore"):
        back = np.ldexp(value, -np.asarray(exponents))
    return bool(np.all(np.isfinite(value)) and np.array_equal(back, np.asarray(before, float)))


# the channels' largest entry within this factor of 1 keeps the sensors' units
SENSOR_SPREAD = UNITS_SPREAD


@dataclass(frozen=True)
class SensorUnits:
    """Where an LMI of a model is solved first (``sensor_units``): the states scaled by s,
    the attack in units 2^-exponent, the channels too, or each in units 2^-channels[i]."""

    s: np.ndarray
    exponent: int
    channels: np.ndarray | None = None

    @property
    def multiplier_exponents(self) -> int | np.ndarray:
        """The sector multipliers are 2^this times those solved in these units."""
        return 2 * (self.exponent if self.channels is None else self.channels)

    def channel_exponents(self, m: int) -> np.ndarray:
        """Each of the m channels is in units 2^-this (the nonlinearity's output alike)."""
        if self.channels is not None:
            return np.asarray(self.channels, dtype=np.int64)
        return np.full(m, self.exponent, dtype=np.int64)

    def coordinates(self, size: int, m: int) -> np.ndarray:
        """T with zeta_b = diag(T) zeta for a Lyapunov function over ``size`` coordinates: the
        states divided by s and, beyond them, a Zames-Falb certificate's past nonlinearity
        outputs and inputs (m per delay, ``zames_falb``), each times its channel's 2^j."""
        N = self.s.size
        T = np.empty(size)
        T[:N] = 1.0 / self.s
        if size > N:
            T[N:] = np.tile(np.ldexp(1.0, self.channel_exponents(m)), (size - N) // max(m, 1))
        return T

    def delays(self, cert: LMICertificate, back: bool) -> dict[str, Any]:
        """A Zames-Falb certificate's delayed coefficients (``u_delays``, ``v_delays``, one
        column per channel) in the user's units (``back``) or in these: like the multipliers,
        4^j times those of the scaled model; {} for a certificate without them."""
        out: dict[str, Any] = {}
        for key in ("u_delays", "v_delays"):
            value = cert.details.get(key)
            if value is not None:
                value = np.asarray(value, dtype=float)
                k = 2 * self.channel_exponents(value.shape[-1])
                out[key] = np.ldexp(value, k if back else -k)
        return out

    def apply(self, model: LureModel) -> LureModel:
        return model.scaled(self.s, sensors=self.exponent, channels=self.channels)

    def back(self, cert: LMICertificate, N: int) -> LMICertificate | None:
        return to_original_coordinates(cert, self.s, N, self.exponent, self.channels)


def sensor_units(model: LureModel, *, channels: bool = True) -> SensorUnits | None:
    """The coordinates an LMI of ``model`` is solved in first where its sensors are in units
    far from 1 or from each other; None where they are near 1.

    The units are those of the channels' error columns Cw[:, :n_e].  Where the largest
    entries of the channels' rows are within ``SENSOR_SPREAD`` of each other, one unit for
    all: where their largest entry is not within ``SENSOR_SPREAD`` of 1, the channels, the
    nonlinearity's output (and so the attack estimate, scaled by 2^-j on its states) and the
    attack in units of the power of two 2^-j that brings that entry into [1, 2).  Where
    they are farther apart, each channel (and its part of the nonlinearity's output and of
    the attack estimate) in units of its own, the power of two that brings its row's
    largest entry into [1, 2), and the attack in units 2^-j still.  All exact
    (``LureModel.scaled``): the soft threshold is positively homogeneous, so the sector
    stays [0, q], and its multipliers are diagonal: the same inequalities, without entries
    1e6 apart (sensors in units of 1e-3 read a decay 1e4 times too small, sensors 1e3 and
    1e-3 a decay of 1.5e-9 for one of 0.04)."""
    from ..numerics.exact import pow2_scale, pow2_units

    if model.n_e == 0 or model.m == 0:
        return None
    rows = model.Cw[:, : model.n_e]
    if not rows.size:
        return None
    with np.errstate(invalid="ignore"):
        tops = np.max(np.abs(rows), axis=1)
    if not np.all(np.isfinite(tops)):
        return None
    sigma = pow2_units(float(tops.max()), SENSOR_SPREAD)
    j = math.frexp(sigma)[1] - 1
    seen = tops[tops > 0]
    rest = model.N - model.n_e  # the attack estimate's states: one per channel, or none
    per = None
    if channels and seen.size and seen.max() >= SENSOR_SPREAD * seen.min() and rest in (0, model.m):
        per = np.array([math.frexp(pow2_scale(t))[1] - 1 if t > 0 else j for t in tops.tolist()])
    elif sigma == 1.0:
        return None
    if abs(j) > 511 or (per is not None and np.abs(per).max() > 511):
        return None  # 4^j would leave the floats (a certificate written back with them is
        # refused where it does: ``to_original_coordinates``)
    if per is None:
        scale = np.full(rest, math.ldexp(1.0, -j))
    else:
        scale = np.ldexp(1.0, -per) if rest else np.ones(0)
    return SensorUnits(np.concatenate([np.ones(model.n_e), scale]), j, per)


def in_sensor_units(
    model: LureModel, certify: Callable[[LureModel], LMICertificate], *, channels: bool = True
) -> LMICertificate | None:
    """``certify`` run on ``model`` in the units of ``sensor_units`` and its certificate
    written back (``to_original_coordinates``); None where the units are near 1 or it
    certifies nothing there."""
    units = sensor_units(model, channels=channels)
    if units is None:
        return None
    inside = certify(units.apply(model))
    if inside.verdict is not Verdict.HOLDS or inside.P is None:
        return None
    return units.back(inside, model.N)


def where_verified(
    model: LureModel,
    cert: LMICertificate,
    compute: Callable[[LureModel, LMICertificate], LMICertificate],
) -> LMICertificate | None:
    """``compute`` run where ``cert`` was verified and its result written back for ``model``:
    in the balanced coordinates of its ``state_scaling`` (with ``cert`` there, exactly:
    ``to_original_coordinates`` undone); None when ``cert`` was verified in ``model``'s own."""
    s = cert.details.get("state_scaling")
    if s is None or cert.P is None:
        return None
    s = np.asarray(s, dtype=float)
    j = int(cert.details.get("sensor_exponent", 0))
    listed = cert.details.get("channel_exponents")
    units = SensorUnits(s, j, None if listed is None else np.asarray(listed, dtype=np.int64))
    scale = 1.0 / units.coordinates(cert.P.shape[0], model.m)
    with np.errstate(over="ignore"):
        P_b = cert.P * scale[:, None] * scale[None, :]
        t_b = (
            None
            if cert.multipliers is None
            else np.ldexp(cert.multipliers, -units.multiplier_exponents)
        )
    if not np.all(np.isfinite(P_b)):
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            cert.kind,
            code=LMICode.NOT_REPRESENTABLE,
            cause=LMICause.P_OUT_OF_RANGE,
        )
    inside = replace(
        cert,
        P=P_b,
        multipliers=t_b,
        gamma=None if cert.gamma is None else math.ldexp(cert.gamma, -j),
        details={
            **{
                k: v
                for k, v in cert.details.items()
                if k not in ("state_scaling", "sensor_exponent", "channel_exponents")
            },
            **units.delays(cert, back=False),
        },
    )
    found = compute(units.apply(model), inside)
    if found.verdict is not Verdict.HOLDS:
        return found
    back = units.back(found, model.N)
    if back is None:
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            found.kind,
            code=LMICode.NOT_REPRESENTABLE,
            cause=LMICause.NOT_SCALED_BACK,
        )
    return back


def output_scaled(model: LureModel, spread: float = 16.0) -> tuple[float, LureModel]:
    """(c, model with Ce / c): c a power of two near ||Ce||, so that the dissipation LMIs are
    solved for the output e / c (the gain in units the solver can handle) and their
    certificate (P, T, g) scaled back by c^2, exactly; c = 1 when ||Ce|| is within ``spread``
    of 1."""
    norm = float(np.linalg.norm(model.Ce, 2)) if model.Ce.size else 0.0
    if not np.isfinite(norm) or norm <= 0.0 or 1.0 / spread < norm < spread:
        return 1.0, model
    exponent = round(float(np.log2(norm)))
    if abs(exponent) > 511:  # c^2, and the certificate scaled back by it, would leave the floats
        return 1.0, model
    c = 2.0**exponent
    return c, replace(model, Ce=model.Ce / c)


def input_units(model: LureModel, spread: float = 16.0) -> tuple[int, LureModel]:
    """(k, model with its attack a = 2^k a_b, ``LureModel.input_scaled``): k the power of two
    that brings the 2-norm of the attack's input [E; Dw] near 1, so that the dissipation LMI
    meets an attack in units the solver can handle (its margin, imposed on every block, would
    otherwise keep gamma^2 above it: a gain of 1e-3 read as 1e-2); k = 0 when that norm is
    within ``spread`` of 1.  The certificate (P, T) is the same, gamma^2 is 4^-k times the
    solved one."""
    inputs = np.vstack([model.E, model.Dw]) if model.r else np.zeros((0, 0))
    norm = float(np.linalg.norm(inputs, 2)) if inputs.size else 0.0
    if not np.isfinite(norm) or norm <= 0.0 or 1.0 / spread < norm < spread:
        return 0, model
    k = -round(float(np.log2(norm)))
    if abs(k) > 255:  # 4^k, and gamma^2 scaled back by it, would leave the floats
        return 0, model
    return k, in_input_units(model, k)


def in_input_units(model: LureModel, k: int) -> LureModel:
    """The model with its attack a = 2^k a_b (``LureModel.input_scaled``, every input alike):
    the inequality ``input_units`` solves, where a certificate is verified again when it does
    not verify in the user's units (gamma^2 times 4^k there)."""
    return model.input_scaled(np.full(model.r, k, dtype=np.int64))


def input_units_note(k: int) -> dict[str, str]:
    """The details of a certificate verified with its attack in units 2^k (``in_input_units``)."""
    return {
        "input_scaling": f"2^{k}",
        "margin_coordinates": "margin and error_bound are those of the LMI "
        f"recomputed with the attack in units 2^{k} (a = 2^{k} a_b, gamma^2 times "
        f"4^{k}), where it was verified",
    }


def balanced_retry(
    model: LureModel,
    certify: Callable[[LureModel], LMICertificate],
    *,
    enabled: bool = True,
    attempts: list[dict[str, Any]] | None = None,
) -> tuple[LMICertificate | None, str]:
    """``certify`` run again on the model in balanced state coordinates (``LureModel.
    balancings``: gebal's, then the canonical one where units are far apart), its certificate written
    back for ``model`` (with ``attempts``, those made in the original coordinates, as
    ``unbalanced_attempts``); (None, why) when not ``enabled``, when there is no balancing to
    try or when it certifies nothing."""
    notes = ""
    for s in model.balancings() if enabled else ():
        cert = certify(model.scaled(s))
        if cert.verdict is Verdict.HOLDS:
            back = to_original_coordinates(cert, s, model.N)
            if back is not None and attempts is not None:
                back = replace(back, details={**back.details, "unbalanced_attempts": attempts})
            if back is not None:
                return back, ""
            why = lmi_messages.not_written_back(2 * int(np.max(np.abs(np.log2(s)))))
        else:
            why = cert.reason
        notes += lmi_messages.balanced_note(scaling_text(s), why)
    return None, notes


def circle_certificate(
    model: LureModel,
    *,
    structure: str = "auto",
    solver_options: dict[str, Any] | None = None,
    clear: float = 100.0,
    reuse: Sequence[tuple[np.ndarray, np.ndarray]] = (),
    budget: Budget | None = None,
    balance: bool = True,
) -> LMICertificate:
    """Circle-criterion certificate of global asymptotic stability without attack.

    Parameters
    ----------
    model : LureModel
    structure : {"auto", "block-diagonal", "cross", "full"}, default "auto"
        ``auto`` tries, cheapest first, P = diag(P1, D) with D diagonal
        (error and attack estimate decoupled), then the same with a full
        cross block, then a full P when the LMI has at most 80 rows.
    solver_options : dict, optional
        Passed to Clarabel.
    clear : float, default 100
        Required ratio of the verified margin to the error bound.
    reuse : sequence of (P, t)
        Candidate certificates (for example from a neighbouring design)
        tried by verification alone before any solve.
    budget : Budget, optional
        Memory and work allowed for one solve (default ``Budget()``: 2 GiB,
        1e12 operations); a structure whose estimated cost (``lmi_cost``)
        exceeds it is skipped, with the estimate in the reason.
    balance : bool, default True
        When no certificate is found, solve again in balanced state
        coordinates (``balanced_retry``): the same system in exact
        power-of-two units, for plants whose states differ widely in scale.

    Returns
    -------
    LMICertificate
    """
    search = partial(
        _circle_search,
        structure=structure,
        solver_options=solver_options,
        clear=clear,
        budget=budget or Budget(),
    )
    if not reuse:  # (reused certificates are tried in the user's units first)
        first = in_sensor_units(model, search)
        if first is not None:
            return first
    cert = search(model, reuse=reuse)
    if cert.code is not LMICode.NOT_VERIFIED:
        return cert  # certified, decided or refused before any LMI was solved
    # the LMIs were solved and failed: again in balanced coordinates, by the search alone, so
    # that its reason says what it found there and the conclusion below is drawn once
    retry, note = balanced_retry(model, search, enabled=balance, attempts=cert.details["attempts"])
    if retry is not None:
        return retry
    return cert.noted(note + lmi_messages.UNPROVEN_INSTABILITY)


def _circle_search(
    model: LureModel,
    *,
    structure: str,
    solver_options: dict[str, Any] | None,
    clear: float,
    budget: Budget,
    reuse: Sequence[tuple[np.ndarray, np.ndarray]] = (),
) -> LMICertificate:
    """``circle_certificate`` in the coordinates ``model`` is written in: the certificate, the
    pre-checks' verdict, a refusal, or inconclusive with what the LMIs (``details["attempts"]``)
    gave."""
    refusal = _model_refusal(model, budget)
    if refusal is not None:
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            "circle",
            details={"budget": budget.to_dict()},
            code=LMICode.NOT_ATTEMPTED,
            cause=LMICause.REFUSED,
            facts={"refusal": refusal},
        )
    verdict, cause, facts, details = _prechecks(model)
    if verdict is not None:
        return LMICertificate(
            verdict,
            "circle",
            details=details,
            code=LMICode.DECIDED_BEFORE,
            cause=cause,
            facts=facts,
        )
    for P_old, t_old in reuse:
        ok, margin, bound, _ = verify_certificate(model, P_old, t_old, clear=clear)
        if ok:
            return _holds(
                model, P_old, t_old, margin, bound, "reused", {**details, "reused": True},
                LMICode.REUSED,
            )  # fmt: skip
    attempts = []
    structures = STRUCTURES if structure == "auto" else [structure]
    for st in structures:
        if st == "full" and structure == "auto" and model.N + model.m > FULL_LIMIT:
            attempts.append(
                {"structure": "full", "status": f"skipped: LMI larger than {FULL_LIMIT}"}
            )
            continue
        skip = _solve_refusal(model, "circle", st, budget)
        if skip is not None:
            attempts.append({"structure": st, "status": f"skipped: {skip}"})
            continue
        P, t, _, info = _solve(model, "circle", st, 0.0, solver_options or {})
        attempts.append(info)
        if P is None or t is None:  # t is None only when the solve failed
            continue
        ok, margin, bound, problem = verify_certificate(model, P, t, clear=clear)
        info["verified"] = ok
        if ok:
            return _holds(
                model, P, t, margin, bound, st, {**details, "attempts": attempts}, LMICode.VERIFIED
            )
        info["verification_problem"] = verify_text(problem)
    return LMICertificate(
        Verdict.INCONCLUSIVE,
        "circle",
        details={**details, "attempts": attempts},
        code=LMICode.NOT_VERIFIED,
        cause=LMICause.CIRCLE_NOT_VERIFIED,
        facts={"attempts": tuple(dict(a) for a in attempts)},  # as they were
    )


def _holds(
    model: LureModel,
    P: np.ndarray,
    t: np.ndarray,
    margin: float,
    bound: float,
    structure: str,
    details: dict[str, Any],
    code: LMICode,
) -> LMICertificate:
    lam_max_P = float(np.linalg.eigvalsh(P)[-1])
    normP = float(np.linalg.norm(P, 2))
    # V(xi+) - V(xi) <= -margin ||P|| |xi|^2 <= -(margin ||P|| / lambda_max(P)) V(xi)
    decay = min(1.0, margin * normP / lam_max_P)
    return LMICertificate(
        Verdict.HOLDS,
        "circle",
        P=P,
        multipliers=t,
        margin=margin,
        error_bound=bound,
        decay=decay,
        structure=structure,
        details=details,
        code=code,
    )


def iss_certificate(
    model: LureModel,
    *,
    alpha: float = 0.0,
    structure: str = "auto",
    solver_options: dict[str, Any] | None = None,
    clear: float = 100.0,
    budget: Budget | None = None,
    balance: bool = True,
) -> LMICertificate:
    """Dissipation certificate V+ - V <= -alpha V - |e|^2 + gamma^2 |a|^2.

    Parameters
    ----------
    model : LureModel
    alpha : float, default 0
        Decay to keep (for example half the circle certificate's).
    structure, solver_options, clear, budget, balance
        As in ``circle_certificate``.

    Returns
    -------
    LMICertificate
        ``gamma`` is the verified l2 gain from attack to estimation error;
        with ``alpha > 0`` the error dynamics are also input-to-state stable.
    """
    budget = budget or Budget()
    refusal = _model_refusal(model, budget)
    if refusal is not None:
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            "iss",
            details={"budget": budget.to_dict()},
            code=LMICode.NOT_ATTEMPTED,
            cause=LMICause.REFUSED,
            facts={"refusal": refusal},
        )
    verdict, cause, facts, details = _prechecks(model)
    if verdict is not None:
        return LMICertificate(
            verdict,
            "iss",
            details=details,
            code=LMICode.DECIDED_BEFORE,
            cause=cause,
            facts=facts,
        )
    # the same search without its balanced retry: in the sensors' units, and balanced below
    again = partial(
        iss_certificate,
        alpha=alpha,
        structure=structure,
        solver_options=solver_options,
        clear=clear,
        budget=budget,
        balance=False,
    )
    first = in_sensor_units(model, again, channels=False)
    if first is not None:
        return first
    attempts = []
    c, solved = output_scaled(model)  # solved with e in units c, the certificate scaled back
    k, solved = input_units(solved)  # and with a = 2^k a_b: gamma^2 scaled back by 4^-k
    structures = STRUCTURES if structure == "auto" else [structure]
    for st in structures:
        if st == "full" and structure == "auto" and model.N + model.m + model.r > FULL_LIMIT:
            attempts.append(
                {"structure": "full", "status": f"skipped: LMI larger than {FULL_LIMIT}"}
            )
            continue
        skip = _solve_refusal(model, "iss", st, budget)
        if skip is not None:
            attempts.append({"structure": st, "status": f"skipped: {skip}"})
            continue
        P, t, g, info = _solve(solved, "iss", st, alpha, solver_options or {})
        if c != 1.0 and P is not None and t is not None and g is not None:
            with np.errstate(over="ignore"):  # beyond the floats: the verification fails
                P, t, g = P * c**2, t * c**2, g * c**2
            info["output_scaling"] = c
        if k and g is not None:
            g = math.ldexp(g, -2 * k)
            info["input_scaling"] = f"2^{k}"
        attempts.append(info)
        if P is None or t is None or g is None:  # None only when the solve failed
            continue
        # certify a slightly larger gain than the optimum so that the margin survives (the
        # absolute part in the units the LMI was solved in)
        g_cert = g * (1 + 1e-6) + math.ldexp(1e-9 * c**2, -2 * k)
        ok, margin, bound, problem = verify_certificate(
            model, P, t, kind="iss", alpha=alpha, g=g_cert, clear=clear
        )
        where: dict[str, Any] = {}
        if not ok and k:
            # the same inequality with a = 2^k a_b (gamma^2 times 4^k), where it was solved
            ok, margin, bound, problem = verify_certificate(
                in_input_units(model, k),
                P,
                t,
                kind="iss",
                alpha=alpha,
                g=math.ldexp(g_cert, 2 * k),
                clear=clear,
            )
            where = input_units_note(k)
        info["verified"] = ok
        if ok:
            return LMICertificate(
                Verdict.HOLDS,
                "iss",
                P=P,
                multipliers=t,
                margin=margin,
                error_bound=bound,
                decay=alpha,
                gamma=float(np.sqrt(g_cert)),
                structure=st,
                details={**details, "attempts": attempts, "gamma_squared": g_cert, **where},
                code=LMICode.VERIFIED,
            )
        info["verification_problem"] = verify_text(problem)
    retry, note = balanced_retry(model, again, enabled=balance, attempts=attempts)
    if retry is not None:
        return retry
    units = sensor_units(model) if balance else None
    if units is not None and units.channels is not None:
        # each channel in units of its own: a looser gain than one unit for all gives (the
        # attack stays in one unit), where that gives none
        alone = in_sensor_units(model, again, channels=True)
        if alone is not None:
            return alone
    return LMICertificate(
        Verdict.INCONCLUSIVE,
        "iss",
        details={**details, "attempts": attempts},
        code=LMICode.NOT_VERIFIED,
        cause=LMICause.DISSIPATION_NOT_VERIFIED,
        facts={"attempts": tuple(dict(a) for a in attempts), "notes": (note,)},
    )


def iss_from_circle(
    model: LureModel, circle: LMICertificate, *, clear: float = 100.0, balance: bool = True
) -> LMICertificate:
    """ISS decay and l2 gain from a verified circle certificate, without a new SDP.

    With (kappa P, kappa T) from the circle certificate and alpha = decay / 2,
    the dissipation LMI is [[Z(kappa), X(kappa)], [X', Y(kappa) - g I]] and
    the smallest admissible g is the largest eigenvalue of the Schur
    complement Y - X' Z^-1 X; it is minimised over kappa by a 1-D search and
    the result re-verified like any other certificate.

    Parameters
    ----------
    model : LureModel
    circle : LMICertificate
        A verified (``holds``) circle certificate of ``model``.
    clear : float, default 100
    balance : bool, default True
        When the gain does not verify in the model's coordinates, compute it again in
        balanced state coordinates (``LureModel.balancings``),
        the circle certificate carried there exactly: a state in units 2^30 apart weighs 2^60 in |e|^2 against the
        others, and the margin relative to ||P|| is lost in the user's coordinates only.

    Returns
    -------
    LMICertificate
    """
    if circle.verdict != Verdict.HOLDS or circle.P is None:
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            "iss",
            code=LMICode.NO_BASE,
            cause=LMICause.NO_BASE,
        )
    elsewhere = where_verified(model, circle, partial(iss_from_circle, clear=clear))
    if elsewhere is not None:
        return elsewhere
    found = _gain_from_circle(model, circle, clear)
    if found.verdict is Verdict.HOLDS or not balance:
        return found
    for s in model.balancings():
        carried = replace(circle, details={**circle.details, "state_scaling": s})
        again = where_verified(model, carried, partial(iss_from_circle, clear=clear, balance=False))
        if again is not None and again.verdict is Verdict.HOLDS:
            return again
    return found


def _gain_from_circle(model: LureModel, circle: LMICertificate, clear: float) -> LMICertificate:
    """``iss_from_circle`` in the model's own coordinates."""
    assert circle.P is not None
    P, t = circle.P, circle.multipliers if circle.multipliers is not None else np.zeros(0)
    alpha = 0.5 * float(circle.decay or 0.0)
    k = model.N + model.m
    perf = iss_matrix(model, np.zeros_like(P), np.zeros_like(t), alpha, 0.0)  # |e|^2 only
    base = iss_matrix(model, P, t, alpha, 0.0) - perf
    if not (np.all(np.isfinite(base)) and np.all(np.isfinite(perf))):
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            "iss",
            code=LMICode.NOT_REPRESENTABLE,
            cause=LMICause.DISSIPATION_OUT_OF_RANGE,
        )
    x, g = _smallest_gain(_schur_gain(base, perf, k), _scale_grid(model, base, k))
    if not np.isfinite(g):
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            "iss",
            code=LMICode.NOT_VERIFIED,
            cause=LMICause.NO_FINITE_GAIN,
        )
    kappa = float(np.exp(x))
    ok, margin, bound, problem, g_cert = _verified_gain(
        model, kappa * P, kappa * t, alpha, g, clear
    )
    if not ok:
        return LMICertificate(
            Verdict.INCONCLUSIVE,
            "iss",
            code=LMICode.NOT_VERIFIED,
            cause=LMICause.GAIN_NOT_VERIFIED,
            facts={"problem": problem},
        )
    return LMICertificate(
        Verdict.HOLDS,
        "iss",
        P=kappa * P,
        multipliers=kappa * t,
        margin=margin,
        error_bound=bound,
        decay=alpha,
        gamma=float(np.sqrt(g_cert)),
        structure=circle.structure,
        details={
            "method": "from the circle certificate (scaled, Schur complement in the attack)",
            "kappa": kappa,
            "gamma_squared": g_cert,
        },
        code=LMICode.VERIFIED,
    )


def _schur_gain(base: np.ndarray, perf: np.ndarray, k: int) -> Callable[[float], float]:
    """g(log kappa): the largest eigenvalue of the Schur complement of kappa base + perf.

    Infinite where Z (its leading k x k block) is not negative definite.
    """

    def gain(log_kappa: float) -> float:
        with np.errstate(over="ignore", invalid="ignore"):
            kappa = float(np.exp(log_kappa))
            M = kappa * base + perf
        if not np.all(np.isfinite(M)):
            return np.inf
        Z, X, Y = M[:k, :k], M[:k, k:], M[k:, k:]
        try:
            zmax = float(np.linalg.eigvalsh(Z)[-1])
            if zmax >= 0:
                return np.inf
            S = Y - X.T @ np.linalg.solve(Z, X)
            value = float(np.linalg.eigvalsh(0.5 * (S + S.T))[-1])
        except np.linalg.LinAlgError:  # singular Z: this kappa gives no gain
            return np.inf
        return value if np.isfinite(value) else np.inf

    return gain


def _scale_grid(model: LureModel, base: np.ndarray, k: int) -> np.ndarray:
    """60 values of log kappa over 8 decades, from where Z can first be negative definite."""
    # kappa must make Z negative definite: Z = kappa Zc + diag(Ce'Ce, 0)
    zc = float(np.linalg.eigvalsh(base[:k, :k])[-1])
    ce = float(np.linalg.norm(model.Ce, 2)) ** 2
    with np.errstate(over="ignore", divide="ignore"):
        lo = np.log(1.01 * ce / max(-zc, np.finfo(float).tiny))
    return lo + np.linspace(0.0, np.log(1e8), 60)


def _smallest_gain(gain: Callable[[float], float], grid: np.ndarray) -> tuple[float, float]:
    """(log kappa, g) of the smallest gain: the grid's best, refined between its neighbours."""
    from scipy.optimize import minimize_scalar

    values = np.array([gain(x) for x in grid])
    best = int(np.argmin(values))
    a, b = grid[max(best - 1, 0)], grid[min(best + 1, grid.size - 1)]
    if not np.isfinite(values[best]):
        return float(grid[best]), float(values[best])
    refined = minimize_scalar(gain, bounds=(a, b), method="bounded")
    if refined.fun <= values[best]:
        return float(refined.x), float(refined.fun)
    return float(grid[best]), float(values[best])


def _verified_gain(
    model: LureModel, P: np.ndarray, t: np.ndarray, alpha: float, g: float, clear: float
) -> tuple[bool, float, float, VerifyProblem | None, float]:
    """``verify_certificate``'s answer for gamma^2 slightly above g, and that gamma^2.

    The Schur complement is tight by construction, so a relative margin of
    1e-6 is tried first, then one of 1 %.
    """
    g_cert = max(g, 0.0) * (1 + 1e-6) + 1e-9
    ok, margin, bound, problem = verify_certificate(
        model, P, t, kind="iss", alpha=alpha, g=g_cert, clear=clear
    )
    if not ok:
        # the Schur complement is tight by construction: keep a relative margin
        g_cert = max(g, 0.0) * 1.01 + 1e-6
        ok, margin, bound, problem = verify_certificate(
            model, P, t, kind="iss", alpha=alpha, g=g_cert, clear=clear
        )
    return ok, margin, bound, problem, g_cert
