"""An observer gain L designed against the certificate: the dissipation LMI with L free.

For the soft-threshold observers (D-SSO, elastic net) the error state is the
Lur'e system of ``ssecert.observers.lure`` with

    A = [[A_p - L S, -L], [0, 0]],  B = [[0], [I]],  E = [[L], [0]],

and the dissipation inequality of ``ssecert.stability.lmi.iss_certificate``,
V(xi+) - (1 - alpha) V(xi) + |e|^2 - g |a|^2 <= 0 under the sector
constraints, is quadratic in L.  With P = diag(P1, D) block diagonal (the
structure the certificates use) and a Schur complement, the inequality reads

    [[ (1 - alpha) diag(P, 0, 0) - Ce'Ce - sector terms + g,  (P H)' ],
     [ P H,                                                    P      ]] >= 0,

H = [A B E], whose first block row P1 [A_p - L S, -L, 0, L] is linear in
Y = P1 L.  One Clarabel solve (cvxpy) minimises g = gamma^2 over (P1, D, T,
Y); the gain is L = P1^-1 Y.  Nothing of the solve is trusted: the design
with that gain is certified again by the ordinary certificates, from
scratch, and only their verified gamma is reported.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..budget import Budget, Refusal, Resource
from ..observers.base import ObserverDesign
from ..observers.lure import LureModel
from ..solvers import solve_conic, solved
from .outcomes import SynthesisCode

__all__ = [
    "GainSynthesis",
    "SynthesisCode",
    "synthesize_gain",
    "synthesize_rate_gain",
    "with_gain",
]


@dataclass(frozen=True)
class GainSynthesis:
    """A gain proposed by the synthesis LMI, and how the solve ended (unverified): ``code``
    with the solver's status or the refusal; ``status`` is its sentence."""

    L: np.ndarray | None
    gamma_proposed: float | None
    code: SynthesisCode
    seconds: float
    alpha: float | None = None
    P: np.ndarray | None = None
    multipliers: np.ndarray | None = None
    g: float | None = None
    # the state coordinates x = diag(state_scaling) x_b the LMI was solved in (None: the
    # user's), where its certificate is best verified
    state_scaling: np.ndarray | None = None
    # and the sensors' units, 2^-sensor_exponent (``LureModel.scaled``)
    sensor_exponent: int = 0
    solver: str = ""  # the solver's status, or the type of the exception it raised
    refusal: Refusal | None = None  # REFUSED: the memory the LMI would need, and the budget
    rows: int = 0  # REFUSED: the LMI's rows
    decay: float | None = None  # NO_DECAY: the smallest decay found infeasible

    @property
    def status(self) -> str:
        """How the solve ended, in words (``synthesis_messages.status_text``)."""
        from .synthesis_messages import status_text

        return status_text(self.code, self.solver, self.refusal, self.rows, self.decay)

    def to_dict(self) -> dict[str, Any]:
        return {
            "L": self.L,
            "gamma_proposed": self.gamma_proposed,
            "status": self.status,
            "seconds": self.seconds,
            "alpha": self.alpha,
        }


def synthesize_gain(
    design: ObserverDesign,
    *,
    alpha: float = 1e-3,
    time_limit: float | None = None,
    budget: Budget | None = None,
    linear: float | None = None,
) -> GainSynthesis:
    """The gain L minimising the l2 gain from attack to estimation error that the
    dissipation LMI certifies, for the design's step, threshold and shrink (its own gain is
    ignored); a candidate only: certify the design built with it.

    Parameters
    ----------
    design : ObserverDesign
        A D-SSO or elastic-net design (window 1, one step per sample) or a Luenberger design.
    alpha : float, default 1e-3
        Decay imposed with the gain (V(xi+) <= (1 - alpha) V(xi) without attack).
    time_limit : float, optional
        Seconds for the solve (Clarabel stops there; no gain then).
    budget : Budget, optional
        Memory allowed (default ``Budget()``, 2 GiB): a synthesis LMI whose interior-point
        system would need more is refused, with the estimate in the status.
    linear : float, optional
        Also require the linear loop F = A - L S to contract by ``linear`` per step in the
        P1-norm, F' P1 F <= linear^2 P1 (so rho(F) <= linear): with the same P1 and Y = P1 L
        the constraint [[linear^2 P1, (P1 F)'], [P1 F, P1]] >= 0 stays linear.  The lever
        that makes the gain use its sensors where the certified decay of the whole error
        state is limited by the attack estimate's loop.
    """
    start = time.perf_counter()
    model, refused = _model(design, budget)
    if refused is not None:
        return replace(refused, seconds=_since(start))
    units = _Units.of(design, model)
    problem, variables = _dissipation_problem(*units.problem_data, alpha, linear=linear)
    return units.back(_solved(problem, variables, start, time_limit))


def synthesize_rate_gain(
    design: ObserverDesign,
    *,
    gamma: float | None = None,
    backoff: float = 0.97,
    time_limit: float | None = None,
    budget: Budget | None = None,
    bisections: int | None = None,
    linear: float | None = None,
) -> GainSynthesis:
    """The gain L with the fastest decay the dissipation LMI certifies (bisection over
    alpha, one feasibility solve each), optionally keeping the l2 gain below ``gamma``;
    the last feasible alpha times ``backoff`` is solved again, so that the certificate has a
    margin; a candidate only, as ``synthesize_gain`` (``time_limit`` for the whole
    bisection: no solve starts past it; ``bisections``, default ``RATE_BISECTIONS``, the
    number of halvings of the interval of alpha; ``linear`` as in ``synthesize_gain``)."""
    start = time.perf_counter()
    model, refused = _model(design, budget)
    if refused is not None:
        return replace(refused, seconds=_since(start))

    def left() -> float | None:
        return None if time_limit is None else max(time_limit - _since(start), 0.1)

    # one parametrised problem: cvxpy canonicalises it once, each solve only sets alpha
    units = _Units.of(design, model)
    problem, variables = _dissipation_problem(*units.problem_data, 0.5, gamma=gamma, linear=linear)
    low, high, best = 0.0, 1.0, None
    for _ in range(RATE_BISECTIONS if bisections is None else max(int(bisections), 1)):
        if time_limit is not None and _since(start) >= time_limit:
            break
        variables["alpha"].value = 0.5 * (low + high)
        found = units.back(_solved(problem, variables, start, left()))
        if found.L is None:
            high = float(variables["alpha"].value)
        else:
            low, best = float(variables["alpha"].value), found
    if best is None:
        if high == 1.0:
            return GainSynthesis(None, None, SynthesisCode.TIME_LIMIT, _since(start))
        return GainSynthesis(None, None, SynthesisCode.NO_DECAY, _since(start), decay=high)
    # the last feasible alpha sits at the edge: back off so that the certificate has a margin
    variables["alpha"].value = backoff * low
    inner = units.back(_solved(problem, variables, start, left()))
    return replace(inner if inner.L is not None else best, seconds=_since(start))


RATE_BISECTIONS = 7  # alpha to within 2^-7 of the best the LMI allows


def _model(design: ObserverDesign, budget: Budget | None) -> tuple[LureModel, GainSynthesis | None]:
    """The design's Lur'e model, and its synthesis refused (None when it is not)."""
    model = LureModel.from_design(design)
    if design.sensing.shape[0] != design.system.p:
        raise NotImplementedError("gain synthesis needs one attack estimate per sensor")
    return model, _refused(model, design, budget)


def _refused(
    model: LureModel, design: ObserverDesign, budget: Budget | None
) -> GainSynthesis | None:
    """The synthesis LMI refused when it does not fit the memory budget (None when it fits):
    the interior-point method holds a dense matrix of the LMI's svec size squared."""
    rows = model.N + model.m + model.r + design.system.n
    memory = 8.0 * (rows * (rows + 1) / 2) ** 2
    allowed = (budget or Budget()).memory
    if memory <= allowed:
        return None
    refusal = Refusal("the synthesis LMI", Resource.MEMORY, memory, float(allowed))
    return GainSynthesis(None, None, SynthesisCode.REFUSED, 0.0, refusal=refusal, rows=rows)


@dataclass(frozen=True)
class _Units:
    """The coordinates the synthesis LMI is solved in: x = diag(s) x_b with powers of two s
    that balance the plant's states (``state_balancing``), so that an LMI solver meets a
    plant written with states in units 2^30 apart as it meets the plant in its own units,
    and, where the sensing's largest entry (in those states) is not within a factor 2^4 of
    1, sensors in units of a power of two sigma that bring it into [1, 2): the attack, the
    attack estimate and the channels multiplied by sigma (the soft threshold is positively
    homogeneous, so its sector stays [0, q]), which multiplies the sector multipliers and
    gamma^2 by sigma^-2 and the gain by sigma^-1.  The error norm |e| keeps the user's
    units (``LureModel.scaled`` keeps Ce S), so the LMI is the user's, by an exact
    congruence; the error's weight Ce S is then divided by a power of two c (its largest
    entry in [1, 2)), which divides V, the multipliers and gamma^2 by c^2: the same LMI,
    without entries 2^60 apart."""

    model: LureModel
    A: np.ndarray
    sensing: np.ndarray
    states: np.ndarray | None = None
    weight: float = 1.0
    sensors: float = 1.0  # sigma

    @classmethod
    def of(cls, design: ObserverDesign, model: LureModel) -> _Units:
        from ..numerics.exact import pow2_row_scaling, pow2_scale, pow2_units
        from ..numerics.linalg import state_balancing

        A, S = design.system.A, design.sensing
        if model.n_e != A.shape[0]:
            return cls(model, A, S)
        s = state_balancing(A, pow2_row_scaling(S)[:, None] * S, canonical=True)
        states = np.ones(A.shape[0]) if s is None else s
        sensed = S * states[None, :]
        top = float(np.max(np.abs(sensed))) if sensed.size else 0.0
        sigma = pow2_units(top)
        if s is None and sigma == 1.0:
            return cls(model, A, S)
        # the attack estimate in the sensors' units too: a_hat = a_hat_b / sigma
        full = np.concatenate([states, np.full(model.N - model.n_e, 1.0 / sigma)])
        balanced = model.scaled(full, sensors=math.frexp(sigma)[1] - 1)
        top = float(np.max(np.abs(balanced.Ce))) if balanced.Ce.size else 0.0
        c = 1.0 / pow2_scale(top) if top > 0 and np.isfinite(top) else 1.0
        balanced = replace(balanced, Ce=balanced.Ce / c)
        A_b = A * (states[None, :] / states[:, None])
        return cls(balanced, A_b, sensed * sigma, full, c, sigma)

    @property
    def problem_data(self) -> tuple[LureModel, np.ndarray, np.ndarray]:
        return self.model, self.A, self.sensing

    def back(self, found: GainSynthesis) -> GainSynthesis:
        """The solve's gain, P, multipliers and gamma in the user's coordinates:
        L = sigma S L_b, P = c^2 S^-1 P_b S^-1 (S with 1 / sigma for the attack estimate),
        T = (c sigma)^2 T_b, gamma = c sigma gamma_b."""
        full, c = self.states, self.weight * self.sensors
        if full is None or found.L is None:
            return found
        n = self.model.n_e
        P = None if found.P is None else self.weight**2 * found.P / np.outer(full, full)
        return replace(
            found,
            L=full[:n, None] * self.sensors * found.L,
            P=P,
            multipliers=None if found.multipliers is None else c * c * found.multipliers,
            g=None if found.g is None else c * c * found.g,
            gamma_proposed=None if found.gamma_proposed is None else c * found.gamma_proposed,
            state_scaling=full,
            sensor_exponent=math.frexp(self.sensors)[1] - 1,
        )


def _dissipation_problem(
    model: LureModel,
    A_p: np.ndarray,
    S: np.ndarray,
    alpha: float,
    *,
    gamma: float | None = None,
    linear: float | None = None,
) -> tuple[Any, dict[str, Any]]:
    """The dissipation LMI with Y = P1 L, in Schur form on the P1 block only (the a_hat
    block's V(xi+) = w' D w is linear in D), minimising g = gamma^2 (or, with ``gamma``,
    only feasible with g <= gamma^2), for the plant matrix A_p and sensing S."""
    import cvxpy as cp

    n = A_p.shape[0]
    N, m, r = model.N, model.m, model.r
    P1 = cp.Variable((n, n), symmetric=True)
    Y = cp.Variable((n, S.shape[0]))
    g = cp.Variable(nonneg=True)
    decay = cp.Parameter(nonneg=True, value=alpha)
    cons = [P1 >> np.eye(n)]
    Z = np.zeros
    if m:
        d = cp.Variable(m)
        t = cp.Variable(m)
        cons += [d >= 1, t >= 1e-6]
        D, T = cp.diag(d), cp.diag(t)
        P = cp.bmat([[P1, Z((n, m))], [Z((m, n)), D]])
        PH = cp.hstack([P1 @ A_p - Y @ S, -Y, Z((n, m)), Y])
        qTC = model.q * T @ model.Cw
        qTD = model.q * T @ model.Dw
        top = (1 - decay) * P - model.Ce.T @ model.Ce
        left = cp.bmat(
            [
                [top, -qTC.T, Z((N, r))],
                [-qTC, 2 * T - D, -qTD],
                [Z((r, N)), -qTD.T, g * np.eye(r)],
            ]
        )
    else:
        P = P1
        PH = cp.hstack([P1 @ A_p - Y @ S, Y])
        top = (1 - decay) * P - model.Ce.T @ model.Ce
        left = cp.bmat([[top, Z((N, r))], [Z((r, N)), g * np.eye(r)]])
    big = cp.bmat([[left, PH.T], [PH, P1]])
    cons.append(0.5 * (big + big.T) >> 1e-7 * np.eye(big.shape[0]))
    if linear is not None:
        PF = P1 @ A_p - Y @ S
        loop = cp.bmat([[float(linear) ** 2 * P1, PF.T], [PF, P1]])
        cons.append(0.5 * (loop + loop.T) >> 1e-7 * np.eye(2 * n))
    if gamma is None:
        problem = cp.Problem(cp.Minimize(g), cons)
    else:
        problem = cp.Problem(cp.Minimize(0), [*cons, g <= gamma**2])
    return problem, {"P1": P1, "Y": Y, "g": g, "alpha": decay, **({"d": d, "t": t} if m else {})}


def _solved(
    problem: Any, variables: dict[str, Any], start: float, time_limit: float | None = None
) -> GainSynthesis:
    """One Clarabel solve of a synthesis LMI; the gain L = P1^-1 Y it proposes."""
    import cvxpy as cp

    options = dict(SOLVER_OPTIONS)
    if time_limit is not None:
        options["time_limit"] = float(time_limit)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a candidate: certified afterwards either way
            solve_conic(problem, **options)
    except (cp.error.SolverError, ArithmeticError, ValueError) as exc:
        return GainSynthesis(
            None, None, SynthesisCode.SOLVER_FAILED, _since(start), solver=type(exc).__name__
        )
    P1, Y, g = variables["P1"].value, variables["Y"].value, variables["g"].value
    if Y is None or P1 is None or not solved(problem):
        return GainSynthesis(
            None, None, SynthesisCode.NOT_SOLVED, _since(start), solver=str(problem.status)
        )
    L = np.linalg.solve(0.5 * (P1 + P1.T), Y)
    if not np.all(np.isfinite(L)):
        return GainSynthesis(None, None, SynthesisCode.NOT_FINITE, _since(start))
    g = max(float(np.asarray(g)), 0.0) if g is not None else None
    P = 0.5 * (P1 + P1.T)
    t = np.zeros(0)
    if "d" in variables:
        P = np.block(
            [
                [P, np.zeros((len(P), len(variables["d"].value)))],
                [np.zeros((len(variables["d"].value), len(P))), np.diag(variables["d"].value)],
            ]
        )
        t = np.asarray(variables["t"].value, dtype=float)
    return GainSynthesis(
        L,
        None if g is None else float(np.sqrt(g)),
        SynthesisCode.SOLVED,
        _since(start),
        alpha=float(variables["alpha"].value),
        P=P,
        multipliers=t,
        g=g,
        solver=str(problem.status),
    )


# A candidate is certified afterwards from scratch, so the solve need not be tight.
SOLVER_OPTIONS = {"tol_gap_abs": 1e-6, "tol_gap_rel": 1e-6, "tol_feas": 1e-7, "max_iter": 60}


def with_gain(design: ObserverDesign, L: np.ndarray) -> ObserverDesign:
    """``design`` with the gain L (an explicit matrix, as a spec file would give it)."""
    from ..observers.base import gain_from_choice

    gain = gain_from_choice(design.system, {"gain": np.asarray(L, dtype=float)})
    return replace(design, gain=replace(gain, details={"synthesised": True}))


def _since(start: float) -> float:
    return round(time.perf_counter() - start, 3)
