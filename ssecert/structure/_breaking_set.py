"""A breaking set found by a sparse-observability method, turned into a fails verdict.

The set is confirmed independently (a staircase on the floats and a Krylov
rank on the exact data, without those sensors), its stealthy attack is
simulated, and the summary says what an attacker on it can do.  A set the
exact data or the simulation do not confirm gives an inconclusive verdict.
``ssecert.structure.sparse`` calls ``_failure`` for every breaking set it
reports.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..numerics.exact import ExactObservability, ExactPlant, Observability
from ..system import System
from ..tolerances import Tolerances
from .attacks import StealthyAttack, stealthy_attack
from .enumeration import SparseMethod, _Outcome
from .outcomes import SparseCode

__all__: list[str] = []


def _failure(
    system: System,
    work: System,
    s: int,
    outcome: _Outcome,
    H: int,
    seed: int,
    tol: Tolerances,
    evidence: dict[str, Any],
    exact: ExactPlant,
    to_user: Callable[[np.ndarray], np.ndarray],
) -> tuple[SparseCode, str, dict[str, Any] | None]:
    """Code (its verdict: fails, or inconclusive where the breaking set is not confirmed),
    summary and stealthy-attack witness of a failing check.

    ``work`` is the plant in power-of-two units used for float decisions (its state
    directions map to the user's by ``to_user``); the witness is built on the user's
    ``system``, from the exact kernel vector of the kept sensors when there is one.
    """
    mr = outcome.max_removable
    B = outcome.breaking_set
    assert mr is not None and B is not None and outcome.z is not None
    kept, sc_rank, decision = _confirm_breaking_set(system, work, B, tol, evidence, exact)
    if decision.state is Observability.UNOBSERVABLE and decision.z is not None:
        z = np.asarray(decision.z, dtype=float)  # the exact data's direction, user's units
    elif outcome.method is SparseMethod.EXACT_ARITHMETIC:
        z = np.asarray(outcome.z, dtype=float)
    else:
        z = to_user(outcome.z)
    if decision.state is Observability.OBSERVABLE:
        return (
            SparseCode.EXACT_DATA_OBSERVABLE,
            (
                f"The {outcome.method} method finds breaking set {list(B)}, but without those sensors "
                f"the exact data are observable (Krylov rank {system.n} modulo a prime): the plant is "
                f"within the precision of the floating-point rank decision of one they break, and "
                f"the answer depends on digits the data do not have."
            ),
            None,
        )
    witness = stealthy_attack(system, B, z, s, horizon=H, seed=seed, tolerances=tol)
    witness_out = _witness_with_exact_check(witness, decision)
    if decision.state is not Observability.UNOBSERVABLE and (
        not witness.verified or (kept and sc_rank >= system.n)
    ):
        return (
            SparseCode.ATTACK_NOT_VERIFIED,
            (
                f"The {outcome.method} method finds breaking set {list(B)}, but the stealthy attack "
                f"built from it does not verify (output mismatch {witness.residual:.2e}, kept sensors "
                f"observable dimension {sc_rank})."
            ),
            witness_out,
        )
    return SparseCode.BREAKING_SET, _failure_summary(system, s, outcome, mr, B), witness_out


def _confirm_breaking_set(
    system: System,
    work: System,
    B: tuple[int, ...],
    tol: Tolerances,
    evidence: dict[str, Any],
    exact: ExactPlant,
) -> tuple[list[int], int, ExactObservability]:
    """The kept sensors, their observable dimension and the exact decision, recorded in evidence.

    An independent confirmation that the kept sensors do not observe the plant:
    a staircase on the floats and a Krylov rank on the exact data.
    """
    from ..numerics.linalg import staircase

    kept = [i for i in range(system.p) if i not in set(B)]
    sc_rank = (
        staircase(work.A, work.C[kept], tolerances=tol, error_model="compound").rank if kept else 0
    )
    decision = exact.observability(tuple(kept))
    evidence["breaking_set_check"] = {
        "kept_sensors": kept,
        "kept_observable_dimension": sc_rank,
        "unobservable": sc_rank < system.n,
        "exact": decision.to_dict(),
    }
    return kept, sc_rank, decision


def _witness_with_exact_check(
    witness: StealthyAttack, decision: ExactObservability
) -> dict[str, Any]:
    """The stealthy attack's dict, with the exact kernel vector when the exact data break too."""
    witness_out = witness.to_dict()
    if decision.state is Observability.UNOBSERVABLE:
        witness_out["exact_check"] = (
            "removing the breaking set leaves the exact data "
            "unobservable: z_exact_integers (up to scale) satisfies "
            "C_i A^k z = 0 exactly for every kept sensor i"
        )
        witness_out["z_exact_integers"] = [str(v) for v in decision.z_exact or []]
    return witness_out


def _what_breaks(system: System, s: int, mr: int, B: tuple[int, ...]) -> str:
    """What an attacker on the breaking set ``B`` can do, in words."""
    names = [system.sensors[i] for i in B]
    if mr == -1:
        return "(A, C) itself is not observable: some states produce no output at all."
    if len(B) <= s:
        return (
            f"Removing sensor{'s' if len(B) > 1 else ''} {', '.join(names)} leaves the plant "
            f"unobservable, and {len(B)} <= s = {s}: an attacker on "
            f"{'them' if len(B) > 1 else 'it'} can mimic a different initial state without "
            f"being detected."
        )
    return (
        f"Removing sensors {', '.join(names)} leaves the plant unobservable; split into two "
        f"groups of at most s = {s}, they give two attacks under which different initial "
        f"states produce the same outputs."
    )


def _failure_summary(system: System, s: int, outcome: _Outcome, mr: int, B: tuple[int, ...]) -> str:
    """The summary of a fails verdict: max_removable against 2s and what breaks the plant."""
    what = _what_breaks(system, s, mr, B)
    if outcome.details.get("max_removable_is_upper_bound"):
        low = int(outcome.details.get("max_removable_at_least", -1))
        return (
            f"max_removable <= {mr} < 2s = {2 * s}: {s} attacked sensor"
            f"{'s' if s != 1 else ''} cannot be corrected, whatever digits the data lack. "
            f"{what} (Smaller sets, from {low + 1} sensors on, are within floating-point "
            f"precision of breaking the plant, so the exact max_removable, between {low} and "
            f"{mr}, is not decided; the verdict does not depend on it.)"
        )
    return (
        f"max_removable = {mr} < 2s = {2 * s}: {s} attacked sensor{'s' if s != 1 else ''} "
        f"cannot be corrected. {what}"
    )
