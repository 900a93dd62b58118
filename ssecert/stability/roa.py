"""A certified region of attraction of a sparse observer: the invariant part of its dead zone.

Near the origin the soft threshold is exactly zero: while every entry of
w = Cw xi is at most the threshold in magnitude, the error state of the
Lur'e model (``ssecert.observers.lure``) follows the linear map
xi+ = A xi.  When A is Schur with a verified Lyapunov matrix P
(A' P A - P < 0, ``lyapunov_certificate``), every sublevel set
{xi' P xi <= c} is invariant under that map, and the largest one inside the
dead zone, c* = min_i threshold^2 / (Cw_i P^-1 Cw_i'), is invariant under the
observer itself: from any initial state in it the error converges to zero.
An observer starts with a_hat(0) = 0, so the region is reported as the
radius r of initial estimation errors: ||e(0)|| <= r puts xi(0) in the set.
Each radius is checked by simulating initial errors on its sphere before it
is reported.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..observers.lure import LureModel
from .lyapunov import lyapunov_certificate

__all__ = ["region_of_attraction"]

SAFETY = 1.0 - 1e-9  # the level used, a hair inside the dead zone's largest invariant set
SAMPLES = 64  # initial errors on the sphere of the radius, simulated
STEPS = 200


def region_of_attraction(model: LureModel, *, seed: int = 0) -> dict[str, Any]:
    """The certified radius of initial estimation errors (a_hat(0) = 0) from which the observer
    converges without attack, with how it was found; radius 0 with the reason when none is."""
    if model.m == 0 or model.threshold <= 0:
        return {"radius": 0.0, "reason": "the observer has no dead zone (no soft threshold)"}
    lyap = lyapunov_certificate(model.A)
    if lyap.verdict.value != "holds" or lyap.P is None or lyap.method != "lyapunov":
        why = "is not stable" if lyap.verdict.value == "fails" else "has no verified P"
        return {
            "radius": 0.0,
            "reason": f"the linear dynamics of the dead zone (xi+ = A xi) {why}: {lyap.reason}",
        }
    P = 0.5 * (lyap.P + lyap.P.T)
    Pinv_Cw = np.linalg.solve(P, model.Cw.T)  # columns P^-1 Cw_i'
    spread = np.einsum("ij,ji->i", model.Cw, Pinv_Cw)  # Cw_i P^-1 Cw_i'
    spread = np.where(spread > 0, spread, np.inf)
    level = SAFETY * float(np.min(model.threshold**2 / spread))
    n_e = model.n_e
    top = float(np.linalg.eigvalsh(P[:n_e, :n_e])[-1])
    radius = math.sqrt(level / top) if math.isfinite(level) and top > 0 else 0.0
    if radius <= 0:
        return {"radius": 0.0, "reason": "the dead zone holds no invariant sublevel set"}
    replay = _replay(model, radius, P, level, seed)
    if not replay["confirmed"]:
        return {
            "radius": 0.0,
            "reason": "a simulated initial error on the certified sphere left the invariant "
            "set (please report this design)",
            "replay": replay,
        }
    return {
        "radius": radius,
        "level": level,
        "P": P,
        "lyapunov_margin": lyap.margin,
        "lyapunov_error_bound": lyap.error_bound,
        "binding_row": int(np.argmin(model.threshold**2 / spread)),
        "method": "largest invariant sublevel set of the dead zone's Lyapunov function",
        "replay": replay,
    }


def _replay(model: LureModel, radius: float, P: np.ndarray, level: float, seed: int) -> dict:
    """Simulate initial errors of norm ``radius`` (a_hat(0) = 0, no attack): the certificate
    says they never leave the level set and V = xi' P xi decreases along them."""
    rng = np.random.default_rng(seed)
    e0 = rng.standard_normal((SAMPLES, model.n_e))
    e0 *= radius / np.linalg.norm(e0, axis=1, keepdims=True)
    xi0 = np.concatenate([e0, np.zeros((SAMPLES, model.N - model.n_e))], axis=1)
    path = model.simulate(xi0, STEPS)  # (steps + 1, samples, N)
    V = np.einsum("ksi,ij,ksj->ks", path, P, path)
    highest = float(V.max() / level)
    decreasing = bool(np.all(np.diff(V, axis=0) <= 1e-9 * level))
    return {
        "samples": SAMPLES,
        "steps": STEPS,
        "highest_level_reached": highest,
        "decreasing": decreasing,
        "final_over_initial": float(V[-1].max() / max(V[0].max(), np.finfo(float).tiny)),
        "confirmed": decreasing and highest <= 1.0 + 1e-6,
    }
