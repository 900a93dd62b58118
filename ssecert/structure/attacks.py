"""Stealthy attacks: the counterexample behind a failed sparse-observability check.

If removing the sensor set B leaves (A, C) unobservable, some z != 0 has
C_i A^k z = 0 for every sensor i outside B and every k.  Split B into
parts B_a and B_b of at most s sensors each and let

    a_a(k) = P_a C A^k z,        a_b(k) = -P_b C A^k z,

with P_a, P_b the selections of the sensors in B_a, B_b.  Then the plant
started at x0 under attack a_a and the plant started at x0 + z under attack
a_b produce identical outputs at every step:

    C A^k x0 + P_a C A^k z = C A^k (x0 + z) - P_b C A^k z,

because (I - P_a - P_b) C A^k z = 0.  No estimator can tell x0 from x0 + z.
When B has at most s sensors, B_b is empty and a_a alone is an undetectable
attack: it makes x0 look exactly like x0 + z.

The construction assumes the attacked sensor set is fixed over the window,
as the sparse-observability definition does.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, NamedTuple

import numpy as np

from ..base.validation import as_index_list, as_int_option, as_real_matrix
from ..system import System
from ..tolerances import Tolerances

__all__ = [
    "StealthyAttack",
    "stealthy_attack",
    "initial_state",
    "WITNESS_MAX_STEPS",
    "WITNESS_MAX_ENTRIES",
]

# The witness is simulated and reported over at most this many steps (and
# steps x p entries): beyond n steps it adds nothing, since C_i A^k z = 0 for
# k < n implies it for every k (Cayley-Hamilton).
WITNESS_MAX_STEPS = 10_000
WITNESS_MAX_ENTRIES = 1_000_000


def initial_state(n: int, rng: np.random.Generator) -> np.ndarray:
    """x0 with entries of magnitude uniform in [2, 3] and random signs."""
    return rng.uniform(2.0, 3.0, n) * rng.choice([-1.0, 1.0], n)


@dataclass(frozen=True)
class StealthyAttack:
    """Two attacks that make x0 and x0 + z indistinguishable.

    Attributes
    ----------
    z : ndarray, shape (n,)
        Unit-norm indistinguishable direction.
    sensors_a, sensors_b : tuple of int
        Attacked sensors of the two explanations (0-based), at most s each.
    attack_a, attack_b : ndarray, shape (horizon, p)
        ``attack_a[k] = P_a C A^k z`` and ``attack_b[k] = -P_b C A^k z``.
    x0 : ndarray, shape (n,)
        Initial state of the simulated check.
    outputs_a, outputs_b : ndarray, shape (horizon, p)
        Simulated outputs from x0 under attack_a and from x0 + z under
        attack_b.
    residual : float
        ``max_k ||outputs_a[k] - outputs_b[k]|| / max_k ||C|| ||A^k z||`` over the
        first n steps (exact agreement there implies it at every step).
    verified : bool
        ``residual <= witness_rtol``.
    rtol : float
    horizon : int
        Steps requested; the arrays cover the first ``attack_a.shape[0]`` of
        them (fewer when the horizon exceeds ``WITNESS_MAX_STEPS``).
    overflow_at : int or None
        First step at which the simulation of an unstable plant overflows,
        when that is after n steps: the arrays stop there.
    time_scale : float
        1, or a power of two gamma when the witness on the plant itself
        overflows before n steps: the arrays are then those of the plant
        (gamma A, D C), and the plant's own attack is
        ``attack_a[k] / (gamma**k * sensor_scales)`` (and its outputs
        likewise), beyond the floating-point range.
    sensor_scales : ndarray, shape (p,), or None
        D, the powers of two of the sensor rows, with ``time_scale``.
    """

    z: np.ndarray
    sensors_a: tuple[int, ...]
    sensors_b: tuple[int, ...]
    attack_a: np.ndarray
    attack_b: np.ndarray
    x0: np.ndarray
    outputs_a: np.ndarray
    outputs_b: np.ndarray
    residual: float
    verified: bool
    rtol: float
    horizon: int | None = None
    overflow_at: int | None = None
    time_scale: float = 1.0
    sensor_scales: np.ndarray | None = None

    @property
    def undetectable(self) -> bool:
        """True when one attack alone suffices (sensors_b is empty)."""
        return not self.sensors_b

    def to_dict(self) -> dict[str, Any]:
        """JSON fields of the witness."""
        out: dict[str, Any] = {
            "z": self.z,
            "sensors_a": list(self.sensors_a),
            "sensors_b": list(self.sensors_b),
            "attack_a": self.attack_a,
            "attack_b": self.attack_b,
            "x0": self.x0,
            "residual": self.residual,
            "verified": self.verified,
            "residual_rtol": self.rtol,
            "meaning": (
                "the plant from x0 under attack_a and the plant from x0 + z under attack_b "
                "give identical outputs"
                + ("; attack_a alone is undetectable" if self.undetectable else "")
            ),
        }
        steps = int(self.attack_a.shape[0])
        out["steps"] = steps
        if self.time_scale != 1.0 and self.sensor_scales is not None:
            out["time_scale_log2"] = int(np.log2(self.time_scale))
            out["sensor_scales_log2"] = [int(v) for v in np.log2(self.sensor_scales)]
            out["units"] = (
                "the attack on the plant itself grows beyond the floating-point range, so "
                "attack_a, attack_b and the outputs are those of the plant (gamma A, D C) with "
                "gamma = 2^time_scale_log2 and D = diag(2^sensor_scales_log2); the plant's own "
                "attack at step k is attack_a[k] / (gamma^k D), and the same x0 and z make it "
                "stealthy, since x(k) scales by gamma^k"
            )
        if self.horizon is not None and self.horizon > steps:
            why = (
                f"the simulated states overflow in floating point at step {self.overflow_at:,}"
                if self.overflow_at is not None
                else f"longer witnesses are cut at {WITNESS_MAX_STEPS:,} steps"
            )
            out["horizon"] = self.horizon
            out["truncated"] = (
                f"shown and verified over the first {steps:,} of the {self.horizon:,} steps of "
                f"the horizon ({why}); attack_a(k) = P_a C A^k z continues in the same way, "
                f"and the outputs coincide at every later step too, because C_i A^k z = 0 for "
                f"k < n implies it for every k (Cayley-Hamilton)"
            )
        return out


def stealthy_attack(
    system: System,
    breaking_set: Sequence[int],
    z: np.ndarray,
    max_attacked: int,
    *,
    horizon: int | None = None,
    seed: int = 0,
    tolerances: Tolerances | None = None,
) -> StealthyAttack:
    """Build the stealthy attack of a breaking set and verify it by simulation.

    Parameters
    ----------
    system : System
    breaking_set : sequence of int
        Sensors whose removal leaves the plant unobservable (at most 2s of
        them, else no split into two s-sparse attacks exists).
    z : ndarray, shape (n,)
        A direction with ``C_i A^k z = 0`` for the sensors outside
        ``breaking_set``; normalised here.
    max_attacked : int
        s, the number of sensors each attack may use.
    horizon : int, optional
        Number of simulated steps (default n); at most ``WITNESS_MAX_STEPS``
        and ``WITNESS_MAX_ENTRIES / p`` (but at least n) are simulated and
        returned, which decides the witness for every horizon.
    seed : int, default 0
        Seed of the simulated initial state x0.
    tolerances : Tolerances, optional

    Returns
    -------
    StealthyAttack

    Raises
    ------
    ValueError
        If the breaking set has more than 2s sensors or z is zero.

    Examples
    --------
    >>> from ssecert import System
    >>> ugv = System([[1.0, 0.0099], [0.0, 0.9876]], [[1, 0], [0, 1], [0, 1]])
    >>> w = stealthy_attack(ugv, [0], [1.0, 0.0], 1, horizon=5)
    >>> w.verified, w.undetectable
    (True, True)
    """
    tol = Tolerances.check(tolerances)
    s = as_int_option(max_attacked, "max_attacked", min_value=0)
    B = sorted(as_index_list(breaking_set, "breaking_set", upper=system.p))
    if len(B) > 2 * s and B:
        raise ValueError(
            f"breaking_set has {len(B)} sensors; a split into two attacks of at most "
            f"max_attacked = {s} sensors needs at most {2 * s}"
        )
    z = _unit_direction(z, system.n)
    requested = system.n if horizon is None else as_int_option(horizon, "horizon", min_value=1)
    H = min(requested, max(system.n, min(WITNESS_MAX_STEPS, WITNESS_MAX_ENTRIES // system.p)))
    sensors_a = tuple(B[:s]) if B else ()
    sensors_b = tuple(B[s:]) if B else ()
    # unstable plants can overflow over long horizons: the mismatch is then
    # not finite and the witness simply fails verification
    with np.errstate(over="ignore", invalid="ignore"):
        attack_a, attack_b = _attack_signals(system, z, sensors_a, sensors_b, H)
        # independent simulation of the two explanations
        x0 = initial_state(system.n, np.random.default_rng(seed))
        run = _explanations(system, x0, z, attack_a, attack_b)
        run, overflow_at, all_finite = _before_overflow(run, system.n)
        residual = _mismatch(run, system)
    if not all_finite and overflow_at is None:
        scaled = _in_scaled_units(system, B, z, s, requested, seed, tol)
        if scaled is not None:
            return scaled
    return StealthyAttack(
        z=z,
        sensors_a=sensors_a,
        sensors_b=sensors_b,
        attack_a=run.attack_a,
        attack_b=run.attack_b,
        x0=x0,
        outputs_a=run.outputs_a,
        outputs_b=run.outputs_b,
        residual=residual,
        verified=bool(residual <= tol.witness_rtol),
        rtol=tol.witness_rtol,
        horizon=requested,
        overflow_at=overflow_at,
    )


class _Explanations(NamedTuple):
    """The two explanations of the same outputs, simulated step by step."""

    attack_a: np.ndarray
    attack_b: np.ndarray
    outputs_a: np.ndarray  # from x0 under attack_a
    outputs_b: np.ndarray  # from x0 + z under attack_b
    scales: np.ndarray  # ||C|| ||x_b(k) - x_a(k)||, what the mismatch is measured against


def _unit_direction(z: np.ndarray, n: int) -> np.ndarray:
    """z scaled to unit norm, its first clearly nonzero entry positive."""
    z = np.array(as_real_matrix(z, "z", shape=(n,), ndim=1))
    nz = np.linalg.norm(z)
    if nz == 0.0:
        raise ValueError("z must be nonzero")
    z = z / nz
    nonzero = np.flatnonzero(np.abs(z) > 1e-12)
    if nonzero.size and z[nonzero[0]] < 0:
        z = -z
    return z


def _attack_signals(
    system: System,
    z: np.ndarray,
    sensors_a: tuple[int, ...],
    sensors_b: tuple[int, ...],
    steps: int,
) -> tuple[np.ndarray, np.ndarray]:
    """attack_a[k] = P_a C A^k z and attack_b[k] = -P_b C A^k z for the first steps."""
    A, C, p = system.A, system.C, system.p
    mask_a = np.zeros(p)
    mask_a[list(sensors_a)] = 1.0
    mask_b = np.zeros(p)
    mask_b[list(sensors_b)] = 1.0
    attack_a = np.empty((steps, p))
    attack_b = np.empty((steps, p))
    w = z.copy()
    for k in range(steps):
        y = C @ w
        attack_a[k] = mask_a * y
        attack_b[k] = -mask_b * y
        w = A @ w
    return attack_a, attack_b


def _explanations(
    system: System, x0: np.ndarray, z: np.ndarray, attack_a: np.ndarray, attack_b: np.ndarray
) -> _Explanations:
    """Outputs of the plant from x0 under attack_a and from x0 + z under attack_b."""
    A, C = system.A, system.C
    steps, p = attack_a.shape
    xa, xb = x0.copy(), x0 + z
    outputs_a = np.empty((steps, p))
    outputs_b = np.empty((steps, p))
    scales = np.empty(steps)
    normC = float(np.linalg.norm(C, 2))
    for k in range(steps):
        outputs_a[k] = C @ xa + attack_a[k]
        outputs_b[k] = C @ xb + attack_b[k]
        scales[k] = normC * float(np.linalg.norm(xb - xa))
        xa, xb = A @ xa, A @ xb
    return _Explanations(attack_a, attack_b, outputs_a, outputs_b, scales)


def _before_overflow(run: _Explanations, n: int) -> tuple[_Explanations, int | None, bool]:
    """The run cut at its first overflow when that is at or after step n, that step, all finite."""
    # an unstable plant overflows after enough steps; the steps before the first
    # overflow decide the witness when they are at least n (Cayley-Hamilton)
    finite = (
        np.all(np.isfinite(run.attack_a), axis=1)
        & np.all(np.isfinite(run.attack_b), axis=1)
        & np.all(np.isfinite(run.outputs_a), axis=1)
        & np.all(np.isfinite(run.outputs_b), axis=1)
        & np.isfinite(run.scales)
    )
    if finite.all():
        return run, None, True
    first = int(np.argmin(finite))
    if first < n:
        return run, None, False
    return _Explanations(*(part[:first] for part in run)), first, False


def _mismatch(run: _Explanations, system: System) -> float:
    """Largest output mismatch over the first n steps, relative to the states' gap."""
    # the mismatch is measured over the first n steps only: C_i A^k z = 0 for k < n
    # implies it for every k (Cayley-Hamilton), and later steps would only measure
    # rounding growing with unstable modes, making the verdict depend on the horizon
    window = min(run.outputs_a.shape[0], system.n)
    outputs_a, outputs_b = run.outputs_a[:window], run.outputs_b[:window]
    diff = float(np.max(np.linalg.norm(outputs_a - outputs_b, axis=1)))
    # rounding in the simulated states themselves is of order eps * ||x||
    normC = float(np.linalg.norm(system.C, 2))
    floor = np.finfo(float).eps * normC * float(max(np.abs(outputs_a).max(initial=0.0), 1.0))
    residual = diff / max(float(run.scales[:window].max()), floor, np.finfo(float).tiny)
    if not np.isfinite(residual):
        residual = float("inf")
    return residual


def _in_scaled_units(
    system: System,
    B: list[int],
    z: np.ndarray,
    s: int,
    horizon: int,
    seed: int,
    tol: Tolerances,
) -> StealthyAttack | None:
    """The witness on (gamma A, D C), powers of two, when the plant's own overflows early."""
    from ..numerics.exact import pow2_row_scaling
    from ..numerics.linalg import unit_normalized

    work, gamma = unit_normalized(system)
    if gamma == 1.0:
        return None
    D = pow2_row_scaling(system.C)
    witness = stealthy_attack(work, B, z, s, horizon=horizon, seed=seed, tolerances=tol)
    if not (np.all(np.isfinite(witness.attack_a)) and np.all(np.isfinite(witness.outputs_a))):
        return None
    return replace(witness, time_scale=gamma, sensor_scales=D)
