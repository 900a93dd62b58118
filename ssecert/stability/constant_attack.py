"""Where an observer's error goes under a constant attack: to zero, to a bias, or away.

Under a constant attack a the error state of the Lur'e model
(``ssecert.observers.lure``) moves to an equilibrium xi* of
xi+ = A xi + B phi(Cw xi + Dw a) + E a, if anywhere.  The equilibria are
found over the soft threshold's active/sign patterns and confirmed in exact
arithmetic (``ssecert.stability.equilibria``).

When the observer has a circle-criterion certificate (sector [0, q]), the
same certificate proves that every trajectory converges to a unique
equilibrium: the shrinkage is slope-restricted in [0, q], so the increments
phi(w1) - phi(w2) lie in the same sector as phi itself, and the certificate's
inequality holds for the difference of any two trajectories under the same
attack (the attack cancels).  The outcome is then proved: the error converges
to zero when e* = 0 exactly, otherwise to the bias e*.  Without a certificate
the outcome is what a simulation from zero error shows (``proved`` false):
growth past ``UNBOUNDED`` times the attack's size and then ``UNBOUNDED`` times further
within ``STEPS`` more steps (or an overflow) is reported unbounded, convergence to the nearest exactly confirmed
equilibrium is observed, not proved; a run that does neither (a cycle) is
undecided.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from itertools import combinations, islice
from typing import Any

import numpy as np

from ..budget import Budget
from ..observers.lure import LureModel
from .equilibria import attacked_equilibria
from .lmi import sensor_units
from .search_messages import searched_text

__all__ = ["constant_attack_outcomes", "default_attacks"]

STEPS = 20_000  # simulated from zero error, stopping once settled
SETTLED = 1e-12  # relative change per step below which the simulation has settled
UNBOUNDED = 1e8  # growth over the attack's size, and then again, that counts as unbounded
MAX_SUPPORTS = 10


def default_attacks(
    p: int, s: int, scenarios: Sequence[Mapping[str, Any]] = ()
) -> list[tuple[str, np.ndarray]]:
    """The constant attacks analysed: each constant scenario with listed sensors (the top of
    its magnitude range, positive on every attacked sensor), or, without one, a unit attack on
    each of the first ``MAX_SUPPORTS`` supports of s sensors."""
    out = []
    for sc in scenarios:
        if sc.get("attack") == "constant" and sc.get("sensors") is not None:
            a = np.zeros(p)
            a[list(sc["sensors"])] = float(sc["magnitude"][1])
            out.append((f"scenario {sc['name']}", a))
    if out or s <= 0:
        return out
    for support in islice(combinations(range(p), min(s, p)), MAX_SUPPORTS):
        a = np.zeros(p)
        a[list(support)] = 1.0
        out.append((f"unit attack on sensors {list(support)}", a))
    return out


def constant_attack_outcomes(
    model: LureModel,
    attacks: Sequence[tuple[str, np.ndarray]],
    *,
    certified: bool,
    budget: Budget | None = None,
) -> list[dict[str, Any]]:
    """One record per attack: ``outcome`` ("converges to zero", "converges to a bias",
    "unbounded" or "undecided"), ``proved``, the ``bias`` e* and its norm, the equilibria
    found and the simulation from zero error.  Nothing when the simulations (``STEPS`` steps
    of every attack) do not fit ``budget`` (default ``Budget()``)."""
    # a stacked attack (windowed observers) is not analysed
    kept = [(name, np.asarray(a, dtype=float)) for name, a in attacks]
    kept = [(name, a) for name, a in kept if a.shape == (model.r,)]
    if not kept:
        return []
    N, m = model.N, model.m
    # (a run past UNBOUNDED times the attack's size may take up to twice STEPS)
    flops = 4.0 * STEPS * len(kept) * (N * N + 2 * N * m + N * model.r)
    if (budget or Budget()).check("constant attacks", flops=flops) is not None:
        return []
    weight = _units(model)
    runs = _simulate(model, np.array([a for _, a in kept]), weight)
    records = []
    for (name, a), sim in zip(kept, runs):
        equilibria, searched, undecided = attacked_equilibria(model, a)
        record: dict[str, Any] = {
            "attack": name,
            "vector": a,
            "equilibria": len(equilibria),
            "equilibrium_search": searched_text(searched),
            "simulation": sim,
        }
        if sim["unbounded"] and not certified:
            record.update(
                outcome="unbounded",
                proved=False,
                how=f"the simulation from zero error grew past {UNBOUNDED:.0e} times the "
                f"attack's size and then {UNBOUNDED:.0e} times further (or overflowed)",
            )
        elif certified and len(equilibria) == 1 and not undecided:
            _settle(record, equilibria[0], proved=True)
            record["how"] = (
                "the stability certificate proves convergence to the unique equilibrium "
                "(the shrinkage is slope-restricted, so it holds for increments)"
            )
        elif sim["unbounded"]:  # a certified design cannot grow without bound
            record.update(
                outcome="undecided",
                proved=False,
                how="the simulation from zero error grew large although the stability "
                "certificate bounds it (rounding in the simulation); the equilibrium search "
                f"gave {len(equilibria)} equilibria",
            )
        else:
            # the nearest exactly confirmed equilibrium, where it is near (another can lie
            # within the tolerance: a bias of 4e-4 beside the zero error reached)
            distances = [_distance(sim["final"], eq, weight) for eq in equilibria]
            nearest = int(np.argmin(distances)) if distances else -1
            if sim["settled"] and nearest >= 0 and distances[nearest] <= 1e-6 * sim["scale"]:
                _settle(record, equilibria[nearest], proved=False)
                record["how"] = (
                    "observed: the simulation from zero error settles on this exactly confirmed "
                    "equilibrium (no certificate proves that it always does)"
                )
            elif sim["settled"]:
                # (a family of equilibria, from duplicate sensors, sits in a pattern whose
                # equations are singular: the search confirms none of its points)
                record.update(
                    outcome="undecided",
                    proved=False,
                    how="the simulation from zero error settled, but not near an equilibrium "
                    f"confirmed exactly ({record['equilibrium_search'] or 'none searched'})",
                )
            else:
                record.update(
                    outcome="undecided", proved=False, how="the simulation did not settle"
                )
        records.append(record)
    return records


def _settle(record: dict[str, Any], eq: dict[str, Any], *, proved: bool) -> None:
    bias = np.asarray(eq["initial_error"], dtype=float)
    with np.errstate(over="ignore"):
        size = float(np.linalg.norm(bias))
    top = float(np.max(np.abs(bias))) if bias.size else 0.0
    if not math.isfinite(size) and math.isfinite(top):  # the squares overflowed, not the norm
        size = top * float(np.linalg.norm(bias / top))
    record.update(
        outcome="converges to zero" if eq.get("error_is_zero") else "converges to a bias",
        proved=proved,
        bias=bias,
        bias_norm=size,
        attack_estimate=np.asarray(eq["attack_estimate"], dtype=float),
        exact=bool(eq.get("exact")),
    )


def _row_norms(v: np.ndarray) -> np.ndarray:
    """Each row's 2-norm, finite for finite rows: where the squares overflow (entries past
    1e154) the row is brought near 1 by a power of two first; inf or NaN for a row that is
    not finite."""
    out = np.linalg.norm(v, axis=1)
    over = np.flatnonzero(np.isinf(out) & np.all(np.isfinite(v), axis=1))
    if over.size:
        k = np.frexp(np.max(np.abs(v[over]), axis=1))[1]
        out[over] = np.ldexp(np.linalg.norm(np.ldexp(v[over], -k[:, None]), axis=1), k)
    return out


def _distance(final: np.ndarray, eq: dict[str, Any], weight: np.ndarray) -> float:
    point = np.concatenate([eq["initial_error"], eq["attack_estimate"]])
    return float(np.linalg.norm((np.asarray(final) - point) * weight))


def _simulate(model: LureModel, attacks: np.ndarray, weight: np.ndarray) -> list[dict[str, Any]]:
    """From zero error and zero attack estimate under each constant attack (rows of
    ``attacks``, simulated together), until each settles or grows past its limit, its size
    measured as the norm of ``weight`` * xi (``_units``)."""
    count = attacks.shape[0]
    xi = np.zeros((count, model.N))
    shift = attacks @ model.Dw.T if model.m else np.zeros((count, 0))
    push = attacks @ model.E.T
    # the attack's size in the states' units: its first step from zero error (a state in units
    # 2^40 times smaller moves 2^40 times more, which is not growth)
    out: list[dict[str, Any] | None] = [None] * count
    live = np.arange(count)
    with np.errstate(all="ignore"):  # an overflow is the growth this looks for
        first = push + (model.phi(shift) @ model.B.T if model.m else 0.0)
        scale = np.maximum(np.abs(attacks).max(axis=1, initial=0.0), 1.0)
        scale = np.maximum(scale, np.nan_to_num(_row_norms(first * weight), posinf=0.0))
        # past UNBOUNDED times the attack's size a run must grow UNBOUNDED times further
        # (a large bias, 1e8 for a unit attack on a sensor that reads the state 2^30 times
        # smaller, is reached and kept), in STEPS more steps (a growth at the rate that
        # took it there in at most STEPS steps takes no more)
        limit = UNBOUNDED * scale
        cap = np.full(count, STEPS)
        crossed = np.zeros(count, dtype=bool)
        for k in range(1, 2 * STEPS + 1):
            x = xi[live]
            nxt = x @ model.A.T + push[live]
            if model.m:
                nxt = nxt + model.phi(x @ model.Cw.T + shift[live]) @ model.B.T
            size = _row_norms(nxt * weight)
            finite = np.all(np.isfinite(nxt), axis=1)
            past = finite & (size > limit[live])
            newly = past & ~crossed[live]
            limit[live[newly]] = UNBOUNDED * size[newly]
            cap[live[newly]] = k + STEPS
            crossed[live[newly]] = True
            grew = ~finite | (past & ~newly)
            change = _row_norms((nxt - x) * weight)
            settled = ~grew & (change <= SETTLED * np.maximum(size, scale[live]))
            for j in np.flatnonzero(grew | settled):
                row = int(live[j])
                if grew[j]:
                    out[row] = {"steps": k, "unbounded": True, "settled": False,
                                "final": nxt[j], "growth": float(size[j] / scale[row]),
                                "scale": float(scale[row])}  # fmt: skip
                else:
                    out[row] = {"steps": k, "unbounded": False, "settled": True, "final": nxt[j],
                                "scale": float(scale[row])}  # fmt: skip
            xi[live] = nxt
            ended = grew | settled | (k >= cap[live])
            for j in np.flatnonzero(ended & ~(grew | settled)):
                row = int(live[j])
                out[row] = {"steps": k, "unbounded": False, "settled": False, "final": nxt[j],
                            "scale": float(scale[row])}  # fmt: skip
            live = live[~ended]
            if live.size == 0:
                break
    return [r for r in out if r is not None]


def _units(model: LureModel) -> np.ndarray:
    """The weights the growth is measured with: each attack estimate in the units of its
    channel's sensor (``lmi.sensor_units``: a sensor read in units 1e9 times smaller has an
    attack estimate 1e9 times larger for the same error, which is not growth), the error in
    its own; ones where the sensors' units are near 1."""
    units = sensor_units(model)
    return np.ones(model.N) if units is None else 1.0 / units.s
