"""Claims of 001, Cilia's MSc thesis: Lyapunov and ISS background (Ch. 2), observers and the
Lasso algorithms (Ch. 4), the elastic-net observer and its theorems (Ch. 5).

The thesis writes x+ = A x, y = C x + a with p sensors and n states, as ssecert does.
"""

from __future__ import annotations

import sympy as sp

from ._core import Finding, claim

__all__: list[str] = []


@claim(
    "thesis.young",
    where="001 Prop. 2 (2.2)",
    statement="For a, b in R^n and gamma > 0: 2 a^T b <= gamma a^T a + (1/gamma) b^T b.",
    recorded="holds",
)
def young() -> Finding:
    # gamma a^T a + b^T b / gamma - 2 a^T b = || sqrt(gamma) a - b / sqrt(gamma) ||^2, a sum
    # of squares: an identity sympy verifies for symbolic vectors of any fixed length
    g = sp.symbols("gamma", positive=True)
    checked = []
    for n in (1, 2, 3, 5):
        a = sp.Matrix(sp.symbols(f"a1:{n + 1}", real=True))
        b = sp.Matrix(sp.symbols(f"b1:{n + 1}", real=True))
        gap = g * (a.T * a)[0] + (b.T * b)[0] / g - 2 * (a.T * b)[0]
        square = sum((sp.sqrt(g) * a[i] - b[i] / sp.sqrt(g)) ** 2 for i in range(n))
        if sp.simplify(sp.expand(gap - square)) != 0:
            raise AssertionError(f"the sum-of-squares identity failed for n = {n}")
        checked.append(n)
    return Finding(
        "holds",
        "The gap gamma a^T a + b^T b / gamma - 2 a^T b equals ||sqrt(gamma) a - b / "
        "sqrt(gamma)||^2, a sum of squares, so it is never negative; equality holds exactly "
        "when b = gamma a. The thesis's proof (Cauchy-Schwarz, then the arithmetic-geometric "
        "mean inequality) is correct.",
        {
            "method": "symbolic",
            "identity": "gamma a'a + b'b/gamma - 2 a'b = ||sqrt(gamma) a - b/sqrt(gamma)||^2",
            "verified_by": "sympy expansion, symbolic vectors of length n",
            "n": checked,
        },
    )


# Chapter 5's claims live in their own module; importing it registers them after these
from . import _thesis_ch5  # noqa: E402, F401
