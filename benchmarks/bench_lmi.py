"""Circle-criterion certificate: structured formulation against a plain one, in one run.

The plain formulation is what one writes first: a full Lyapunov matrix P of
size n + p and the full block LMI, solved by cvxpy with Clarabel.  ssecert's
formulation keeps only what the proof needs (P block diagonal between the
error and the attack estimate, diagonal on the attack estimate); every
certificate is re-verified outside the solver either way.  Also timed: a
10 x 10 (shrink, step) region map, which re-verifies neighbouring
certificates before solving.

    python benchmarks/bench_lmi.py [--skip-plain] [--grid N]
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass
from typing import Any

import cvxpy as cp
import numpy as np
from _common import best_of, row, yes_no

from ssecert import System
from ssecert.examples import load_example
from ssecert.observers import build_observer
from ssecert.stability.lmi import LureModel, circle_certificate, verify_certificate
from ssecert.stability.region import region_map


def plain(model: LureModel) -> tuple[str, float, bool]:
    """Full P, full LMI; returns status, seconds and whether it verifies."""
    N, m = model.N, model.m
    start = time.perf_counter()
    P = cp.Variable((N, N), symmetric=True)
    t = cp.Variable(m)
    G = np.hstack([model.A, model.B])
    Z = np.zeros
    M = G.T @ P @ G - cp.bmat([[P, Z((N, m))], [Z((m, N)), Z((m, m))]])
    qCT = model.q * model.Cw.T @ cp.diag(t)
    M = M + cp.bmat([[Z((N, N)), qCT], [qCT.T, -2 * cp.diag(t)]])
    M = 0.5 * (M + M.T)
    problem = cp.Problem(cp.Minimize(0), [P >> np.eye(N), t >= 1e-6, M << -1e-4 * np.eye(N + m)])
    problem.solve(solver=cp.CLARABEL)
    seconds = time.perf_counter() - start
    ok = False
    if P.value is not None:
        ok = verify_certificate(model, 0.5 * (P.value + P.value.T), t.value)[0]
    return problem.status, seconds, ok


def random_plant(n: int, p: int, seed: int = 0) -> System:
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A = A / np.abs(np.linalg.eigvals(A)).max()  # eigenvalue of modulus 1, as in the thesis
    return System(A, rng.standard_normal((p, n)))


OBSERVER = {
    "kind": "elastic_net",
    "gain": "deadbeat",
    "step": 0.05,
    "threshold": 0.1,
    "shrink": 0.5,
}


@dataclass(frozen=True)
class PlantResult:
    label: str
    seconds: float
    verdict: str
    structure: str
    margin: float
    plain_status: str | None
    plain_seconds: float | None
    plain_verified: bool


@dataclass(frozen=True)
class RegionResult:
    grid: int
    seconds: float
    certified: int
    solves: int
    reused: int


@dataclass(frozen=True)
class Results:
    plants: list[PlantResult]
    region: RegionResult | None


def measure(*, skip_plain: bool = False, grid: int = 10) -> Results:
    """Both formulations on each plant, then a grid x grid region map (none for grid 0)."""
    plants = [
        ("random n=10, p=15", random_plant(10, 15)),
        ("thesis-sized n=15, p=30 (random-n15-p30)", load_example("random-n15-p30").system),
    ]
    results = []
    for label, system in plants:
        model = LureModel.from_design(build_observer(system, OBSERVER))
        ours, cert = best_of(lambda model=model: circle_certificate(model), 1)
        status, seconds, ok = (None, None, False) if skip_plain else plain(model)
        results.append(
            PlantResult(
                label,
                ours,
                str(cert.verdict),
                str(cert.structure),
                float(cert.margin),
                status,
                seconds,
                ok,
            )
        )
    if grid < 1:
        return Results(results, None)
    system = load_example("random-n15-p30").system
    design = build_observer(system, OBSERVER)
    rm = region_map(design, np.linspace(0.1, 0.9, grid), np.linspace(0.01, 0.3, grid))
    certified = int(np.count_nonzero(rm.verdicts == "holds"))
    return Results(results, RegionResult(grid, rm.seconds, certified, rm.solves, rm.reused))


def print_results(r: Results) -> None:
    print(f"{'plant':<42} {'plain (s)':>10} {'ssecert (s)':>12} {'ratio':>7}  verdicts")
    for p in r.plants:
        if p.plain_seconds is None:
            print(f"{p.label:<42} {'-':>10} {p.seconds:12.2f} {'-':>7}  ssecert {p.verdict}")
            continue
        print(
            f"{p.label:<42} {p.plain_seconds:10.2f} {p.seconds:12.2f} "
            f"{p.plain_seconds / p.seconds:6.1f}x  plain {p.plain_status}"
            f"{' (verified)' if p.plain_verified else ''}, ssecert {p.verdict} ({p.structure}, "
            f"margin {p.margin:.2e})"
        )
    m = r.region
    if m is not None:
        print(
            f"{m.grid} x {m.grid} (shrink, step) map on the thesis-sized plant: {m.seconds:.1f} s "
            f"(target < 120 s for 10 x 10); {m.certified} certified, {m.solves} LMI solves, "
            f"{m.reused} certificates re-verified from a neighbour"
        )


def to_rows(r: Results) -> list[dict[str, Any]]:
    out = []
    for p in r.plants:
        note = (
            f"ssecert {p.verdict} ({p.structure}, margin {p.margin:.2g}); plain "
            f"{p.plain_status}, verified: {yes_no(p.plain_verified)}"
        )
        out.append(
            row(
                "structured LMI vs plain",
                f"{p.label}, elastic-net observer",
                p.seconds,
                p.plain_seconds,
                "full P, full LMI (cvxpy + Clarabel)",
                note,
            )
        )
    m = r.region
    if m is not None:
        note = (
            f"{m.certified} of {m.grid * m.grid} certified, {m.solves} LMI solves, {m.reused} "
            f"re-verified from a neighbour"
        )
        case = f"{m.grid} x {m.grid} (shrink, step) map, thesis-sized plant"
        out.append(row("LMI region map", case, m.seconds, None, "-", note))
    return out


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The figures as table rows (quick: no region map)."""
    return to_rows(measure(grid=0 if quick else 10))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--skip-plain", action="store_true", help="do not time the plain formulation"
    )
    parser.add_argument(
        "--grid", type=int, default=10, help="region map points per axis (0: no map)"
    )
    args = parser.parse_args()
    print_results(measure(skip_plain=args.skip_plain, grid=args.grid))


if __name__ == "__main__":
    main()
