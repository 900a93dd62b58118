"""Which conic solver cvxpy hands the LMIs to (``--solver NAME``): Clarabel by default.

The certificates do not trust a solver: every matrix a solver proposes is re-verified in numpy
(and exactly where the check says so) before a verdict is given, so another solver changes what
is found, never what is claimed.  ``using_solver`` sets the solver for the analyses within its
block; ``solve_conic`` runs a cvxpy problem with it, translating Clarabel's options (tolerances,
iterations, time limit) to the solver's own names where it has them.  The piecewise region's
LMIs go to Clarabel's own interface when Clarabel is the choice (they are assembled in its
form), and through cvxpy to any other solver (``ssecert.stability._conic``).
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Iterator
from typing import Any

__all__ = [
    "SDP_SOLVERS",
    "check_solver",
    "solve_conic",
    "solved",
    "solver_name",
    "using_solver",
]

#: cvxpy's solvers that handle the semidefinite cones of the LMIs
SDP_SOLVERS = ("CLARABEL", "SCS", "MOSEK", "CVXOPT", "COPT", "SDPA")

_SOLVER: contextvars.ContextVar[str] = contextvars.ContextVar("ssecert_solver", default="CLARABEL")

# Clarabel's option names -> each solver's (None: the solver has no such option)
_OPTIONS: dict[str, dict[str, str | None]] = {
    "CLARABEL": {},
    "SCS": {
        "tol_gap_abs": "eps_abs",
        "tol_gap_rel": "eps_rel",
        "tol_feas": None,
        "max_iter": None,  # Clarabel's interior-point iterations are no guide to SCS's
        "time_limit": "time_limit_secs",
    },
    "CVXOPT": {
        "tol_gap_abs": "abstol",
        "tol_gap_rel": "reltol",
        "tol_feas": "feastol",
        "max_iter": "max_iters",
        "time_limit": None,
    },
}


def solver_name() -> str:
    """The solver the LMIs go to (``"CLARABEL"`` unless ``using_solver`` says otherwise)."""
    return _SOLVER.get()


def solver_label() -> str:
    """The solver the LMIs go to, as a method's words name it ("Clarabel", "SCS", ...)."""
    name = solver_name()
    return "Clarabel" if name == "CLARABEL" else name


def check_solver(name: str) -> str:
    """``name`` upper-cased, when cvxpy has it installed and it handles semidefinite cones.

    Raises
    ------
    ValueError
        Naming the solvers that would do.
    """
    import cvxpy as cp

    wanted = str(name).upper()
    usable = [s for s in SDP_SOLVERS if s in cp.installed_solvers()]
    if wanted not in usable:
        known = set(cp.settings.SOLVERS) | set(cp.installed_solvers())
        why = (
            "is not installed"
            if wanted in SDP_SOLVERS
            else "does not solve semidefinite programs"
            if wanted in known
            else "is not a cvxpy solver"
        )
        raise ValueError(
            f"solver {name!r} {why}; the installed solvers for the LMIs are {', '.join(usable)}"
        )
    return wanted


@contextlib.contextmanager
def using_solver(name: str) -> Iterator[str]:
    """Solve the LMIs of the analyses within the block with ``name`` (``check_solver``)."""
    token = _SOLVER.set(check_solver(name))
    try:
        yield _SOLVER.get()
    finally:
        _SOLVER.reset(token)


def solve_conic(problem: Any, **options: Any) -> None:
    """``problem.solve`` with the chosen solver, Clarabel's ``options`` translated (those the
    solver lacks are left out)."""
    name = solver_name()
    table = _OPTIONS.get(name)
    if table is None:  # a solver without a translation: its own defaults
        translated: dict[str, Any] = {}
    else:
        translated = {}
        for key, value in options.items():
            mapped = table.get(key, key)
            if mapped is not None:
                translated[mapped] = value
    problem.solve(solver=name, **translated)


def solved(problem: Any) -> bool:
    """Whether cvxpy reports ``problem`` solved (optimal, or optimal to reduced accuracy): its
    solution is then a candidate, verified by the caller."""
    import cvxpy as cp

    return problem.status in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE)
