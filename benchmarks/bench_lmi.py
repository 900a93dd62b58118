"""Circle-criterion certificate: structured formulation against a plain one, in one run.

The plain formulation is what one writes first: a full Lyapunov matrix P of
size n + p and the full block LMI, solved by cvxpy with Clarabel.  ssecert's
formulation keeps only what the proof needs (P block diagonal between the
error and the attack estimate, diagonal on the attack estimate); every
certificate is re-verified outside the solver either way.  Also timed: a
10 x 10 (shrink, step) region map, which re-verifies neighbouring
certificates before solving.

    python benchmarks/bench_lmi.py [--skip-plain]
"""

from __future__ import annotations

import argparse
import time

import cvxpy as cp
import numpy as np

from ssecert import System
from ssecert.examples import load_example
from ssecert.observers import build_observer
from ssecert.stability.lmi import LureModel, circle_certificate, region_map, verify_certificate


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--skip-plain", action="store_true", help="do not time the plain formulation"
    )
    args = parser.parse_args()
    observer = {
        "kind": "elastic_net",
        "gain": "deadbeat",
        "step": 0.05,
        "threshold": 0.1,
        "shrink": 0.5,
    }
    plants = [
        ("random n=10, p=15", random_plant(10, 15)),
        ("thesis-sized n=15, p=30 (random-n15-p30)", load_example("random-n15-p30").system),
    ]
    print(f"{'plant':<42} {'plain (s)':>10} {'ssecert (s)':>12} {'ratio':>7}  verdicts")
    for label, system in plants:
        model = LureModel.from_design(build_observer(system, observer))
        t0 = time.perf_counter()
        cert = circle_certificate(model)
        ours = time.perf_counter() - t0
        if args.skip_plain:
            print(f"{label:<42} {'-':>10} {ours:12.2f} {'-':>7}  ssecert {cert.verdict}")
            continue
        status, seconds, ok = plain(model)
        print(
            f"{label:<42} {seconds:10.2f} {ours:12.2f} {seconds / ours:6.1f}x  plain {status}"
            f"{' (verified)' if ok else ''}, ssecert {cert.verdict} ({cert.structure}, margin "
            f"{cert.margin:.2e})"
        )
    system = load_example("random-n15-p30").system
    design = build_observer(system, observer)
    rm = region_map(design, np.linspace(0.1, 0.9, 10), np.linspace(0.01, 0.3, 10))
    certified = int(np.count_nonzero(rm.verdicts == "holds"))
    print(
        f"10 x 10 (shrink, step) map on the thesis-sized plant: {rm.seconds:.1f} s "
        f"(target < 120 s); {certified} certified, {rm.solves} LMI solves, {rm.reused} "
        f"certificates re-verified from a neighbour"
    )


if __name__ == "__main__":
    main()
