"""ssecert's exact observability against python-flint's exact linear algebra.

ssecert decides the observability of the exact data (A, C) (the floats taken as rationals) by a
Krylov rank modulo a prime (a proof when it is n) and, when that rank is short, an exact kernel
vector re-checked in integers (``ssecert.numerics.exact.exact_observability``).  The reference is
python-flint (FLINT's fmpz matrices): the floats scaled to integers by powers of two, the
observability matrix formed exactly, its rank (``fmpz_mat.rank``) and, when short, a kernel
vector (``nullspace``).  Both must agree.  Plants: random Gaussian (observable) and the same with
its last state decoupled from A and C (unobservable), n = 5 to 30.

    python benchmarks/bench_exact.py [--repeat N]

Without python-flint (``python -m pip install python-flint``) it says so and gives no row.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

import numpy as np
from _common import best_of, row, yes_no

from ssecert.numerics.exact import exact_observability

NAME = "exact observability vs python-flint"
SIZES = ((5, 3), (10, 6), (20, 12), (30, 20))


def _integers(M: np.ndarray) -> list[list[int]]:
    """M times the power of two that makes every entry an integer."""
    shift = 0
    for x in M.ravel():
        if x != 0:
            _, exponent = math.frexp(float(x))
            shift = max(shift, 53 - exponent)
    return [[int(float(x) * 2.0**shift) if shift < 1000 else int(x * 2**shift) for x in r]
            for r in M]  # fmt: skip


def flint_observability(A: np.ndarray, C: np.ndarray) -> str:
    """'observable' or 'unobservable' by FLINT: the exact rank of the observability matrix of
    the integer-scaled data, and a kernel vector (checked) when it is short."""
    import flint

    n = A.shape[0]
    Ai, Ci = flint.fmpz_mat(_integers(A)), flint.fmpz_mat(_integers(C))
    blocks, M = [Ci], Ci
    for _ in range(n - 1):
        M = M * Ai
        blocks.append(M)
    rows = [[B[i, j] for j in range(n)] for B in blocks for i in range(B.nrows())]
    O = flint.fmpz_mat(rows)
    if O.rank() == n:
        return "observable"
    kernel, nullity = O.nullspace()
    z = flint.fmpz_mat([[kernel[i, 0]] for i in range(n)])
    assert nullity >= 1 and all(v == 0 for v in (O * z).entries())
    return "unobservable"


def _plants() -> list[tuple[str, np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(0)
    out = []
    for n, p in SIZES:
        A, C = rng.standard_normal((n, n)), rng.standard_normal((p, n))
        out.append((f"generic n = {n}, p = {p} (observable)", A, C))
        A, C = A.copy(), C.copy()
        A[-1, :-1] = A[:-1, -1] = C[:, -1] = 0.0  # the last state decoupled and unseen
        out.append((f"n = {n}, p = {p}, last state unseen (unobservable)", A, C))
    return out


def measure(repeat: int) -> list[dict[str, Any]]:
    out = []
    for case, A, C in _plants():
        ours, mine = best_of(lambda A=A, C=C: exact_observability(A, C).state, repeat)
        theirs, flints = best_of(lambda A=A, C=C: flint_observability(A, C), repeat)
        out.append({"case": case, "ssecert": ours, "flint": theirs, "same": mine == flints,
                    "state": mine})  # fmt: skip
    return out


def to_rows(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    import flint

    return [
        row(
            NAME,
            r["case"],
            r["ssecert"],
            r["flint"],
            f"python-flint {flint.__version__} (fmpz rank and nullspace)",
            f"same answer: {yes_no(r['same'])} ({r['state']}); ssecert: Krylov rank modulo a "
            "prime, an exact kernel vector when short",
        )
        for r in results
    ]


def rows(quick: bool = False) -> list[dict[str, Any]]:
    """The rows where python-flint is installed, else none (the reason printed)."""
    try:
        import flint  # noqa: F401
    except ImportError:
        print("bench_exact: not run: python-flint is not installed")
        return []
    return to_rows(measure(1 if quick else 3))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    results = measure(parser.parse_args().repeat)
    for r in results:
        print(f"{r['case']}: ssecert {r['ssecert'] * 1e3:.1f} ms, flint {r['flint'] * 1e3:.1f} "
              f"ms ({r['flint'] / r['ssecert']:.2f}x); same answer: {r['same']}")  # fmt: skip
    if not all(r["same"] for r in results):
        raise SystemExit("the answers differ")


if __name__ == "__main__":
    main()
