"""Observer synthesis on a 15-state, 30-sensor plant: ssecert's LMI against the plain one,
and the whole design search within its one-minute budget.

ssecert's synthesis LMI takes the Schur complement of the error block P1 only (the attack
estimate's part of V(xi+) is linear in its own D); the plain formulation is what one writes
first: the Schur complement of the whole block-diagonal P = diag(P1, D).  Both are solved by
cvxpy with Clarabel for the same (shrink, step) and must propose gains whose certified
gamma agree.  Then ``design_observer`` (elastic net, objective gain, time budget 60 s) on
the packaged random-n15-p30 plant: the time to its first certified candidate, to its end,
the candidates tried and the certified gamma.

    python benchmarks/bench_design.py [--budget SECONDS]
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import cvxpy as cp
import numpy as np
from _common import row

from ssecert.design.search import design_observer
from ssecert.design.synthesis import synthesize_gain
from ssecert.examples import load_example
from ssecert.observers import build_observer
from ssecert.observers.lure import LureModel

CASE = "random-n15-p30"
PARAMS = {"kind": "elastic_net", "step": 0.3, "threshold": 0.1, "shrink": 0.3}


def plain(design: Any, alpha: float = 1e-3) -> tuple[float, float | None]:
    """The synthesis LMI with the Schur complement of the whole P = diag(P1, D)."""
    model = LureModel.from_design(design)
    n, S, A_p = design.system.n, design.sensing, design.system.A
    N, m, r = model.N, model.m, model.r
    start = time.perf_counter()
    P1 = cp.Variable((n, n), symmetric=True)
    Y = cp.Variable((n, S.shape[0]))
    g = cp.Variable(nonneg=True)
    d, t = cp.Variable(m), cp.Variable(m)
    Z = np.zeros
    D, T = cp.diag(d), cp.diag(t)
    P = cp.bmat([[P1, Z((n, m))], [Z((m, n)), D]])
    PH = cp.bmat([[P1 @ A_p - Y @ S, -Y, Z((n, m)), Y], [Z((m, n)), Z((m, m)), D, Z((m, r))]])
    qTC, qTD = model.q * T @ model.Cw, model.q * T @ model.Dw
    left = cp.bmat(
        [
            [(1 - alpha) * P - model.Ce.T @ model.Ce, -qTC.T, Z((N, r))],
            [-qTC, 2 * T, -qTD],
            [Z((r, N)), -qTD.T, g * np.eye(r)],
        ]
    )
    big = cp.bmat([[left, PH.T], [PH, P]])
    cons = [P1 >> np.eye(n), d >= 1, t >= 1e-6, 0.5 * (big + big.T) >> 1e-7 * np.eye(big.shape[0])]
    problem = cp.Problem(cp.Minimize(g), cons)
    problem.solve(solver=cp.CLARABEL)
    seconds = time.perf_counter() - start
    return seconds, (float(np.sqrt(g.value)) if g.value is not None else None)


def measure(budget: float) -> dict[str, Any]:
    system = load_example(CASE).system
    template = build_observer(system, {**PARAMS, "gain": np.zeros((system.n, system.p))})
    start = time.perf_counter()
    mine = synthesize_gain(template)
    mine_seconds = time.perf_counter() - start
    plain_seconds, plain_gamma = plain(template)
    start = time.perf_counter()
    result = design_observer(system, "elastic_net", time_budget=budget)
    search = time.perf_counter() - start
    return {
        "lmi_size": (2 * (system.n + system.p) + 2 * system.p, 2 * system.n + 3 * system.p),
        "mine": (mine_seconds, mine.gamma_proposed),
        "plain": (plain_seconds, plain_gamma),
        "search": search,
        "result": result,
        "budget": budget,
    }


def to_rows(m: dict[str, Any]) -> list[dict[str, Any]]:
    mine_s, mine_g = m["mine"]
    plain_s, plain_g = m["plain"]
    agree = mine_g is not None and plain_g is not None and abs(mine_g - plain_g) <= 1e-3 * plain_g
    res = m["result"]
    certified = [c for c in res.candidates if c.get("certified")]
    first = min((c["seconds_since_start"] for c in certified), default=float("nan"))
    return [
        row(
            "design synthesis LMI",
            f"{CASE}, shrink 0.3, step 0.3",
            mine_s,
            plain_s,
            "Schur complement of the whole P (cvxpy, Clarabel)",
            f"proposed gamma {mine_g:.4g} vs {plain_g:.4g} ({'agree' if agree else 'DIFFER'}); "
            f"LMI {m['lmi_size'][1]} vs {m['lmi_size'][0]} rows",
        ),
        row(
            "design search",
            f"{CASE}, elastic net, budget {m['budget']:g} s",
            m["search"],
            None,
            "",
            f"{len(res.candidates)} candidates, {len(certified)} certified (the first after "
            f"{first:.1f} s), "
            f"{'grid exhausted' if res.complete else 'stopped by the budget'}; certified "
            f"gamma {res.gamma:.4g}"
            if res.gamma is not None
            else "no design certified",
        ),
    ]


def print_results(m: dict[str, Any]) -> None:
    for r in to_rows(m):
        ref = "" if r["reference"] is None else f", reference {r['reference']:.2f} s"
        print(f"{r['benchmark']} ({r['case']}): {r['ssecert']:.2f} s{ref}; {r['note']}")


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The figures as table rows (quick: a 20-second search budget)."""
    return to_rows(measure(20.0 if quick else 60.0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--budget", type=float, default=60.0, help="search budget, seconds")
    print_results(measure(parser.parse_args().budget))


if __name__ == "__main__":
    main()
