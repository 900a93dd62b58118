"""Assertions for pytest suites: each passes only on a ``holds`` verdict.

Every assertion runs one of ssecert's analyses and raises ``AssertionError``
unless the answer is ``holds``.  A ``fails`` verdict gives the witness in
terms a user can act on (sensor names with their 0-based indices, the
offending eigenvalue, the stealthy attack and its size); an
``inconclusive`` verdict says what could not be decided and why.  On
success each assertion returns the result it checked.
"""

from __future__ import annotations

import numbers
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..base.format import readable, sig
from ..base.validation import as_float_option, as_int_option, as_real_matrix, describe
from ..results import Certificate, Check, Verdict
from ..spec import Spec
from ..system import System

__all__ = [
    "assert_observable",
    "assert_sparse_observable",
    "assert_deadbeat",
    "assert_schur",
    "assert_certified",
    "assert_recovers",
]


# ---------------------------------------------------------------------------
# formatting


def _num(x: Any, digits: int = 4) -> str:
    """A number in at most ``digits`` significant digits (complex as a+bj)."""
    x = complex(x) if np.iscomplexobj(x) else float(x)
    x = x + 0  # no "-0"
    if isinstance(x, complex):
        if abs(x.imag) <= 1e-12 * max(abs(x), 1e-300):
            return f"{x.real:.{digits}g}"
        return f"{x.real:.{digits}g}{'+' if x.imag >= 0 else '-'}{abs(x.imag):.{digits}g}j"
    return f"{x:.{digits}g}"


def _num_versus_one(z: complex) -> str:
    """An eigenvalue in 12 significant digits; a real one that rounds onto +-1 as its distance
    from it ("1 - 1.1e-16")."""
    if z.imag == 0 and abs(abs(z.real) - 1.0) < 1e-6:
        text = readable(abs(z.real), 12, versus=1.0)
        if z.real > 0:
            return text
        return f"-({text})" if " " in text else f"-{text}"
    return _num(z, 12)


def _vector(v: Any, limit: int = 8) -> str:
    """[a, b, ...]: a short vector in full, a long one cut after ``limit`` entries."""
    arr = np.asarray(v).ravel()
    items = [_num(x) for x in arr[:limit]]
    if arr.size > limit:
        items.append(f"... ({arr.size} entries)")
    return "[" + ", ".join(items) + "]"


def _sensor(system: System, index: int) -> str:
    return f"{system.sensors[index]} (index {index})"


def _sensors(system: System, indices: Sequence[int]) -> str:
    return ", ".join(_sensor(system, int(i)) for i in indices) or "no sensor"


def _label(system: System) -> str:
    return f"system {system.name!r} (n = {system.n}, p = {system.p})"


def _require_system(system: Any, name: str = "system") -> System:
    if not isinstance(system, System):
        hint = " (a design's plant is design.system)" if isinstance(system, Spec) else ""
        raise TypeError(f"{name} must be a ssecert.System{hint}, got {describe(system)}")
    return system


def _require_spec(design: Any) -> Spec:
    if not isinstance(design, Spec):
        raise TypeError(
            f"design must be a ssecert.Spec (load_spec, spec_from_dict or the ssecert_example "
            f"fixture), got {describe(design)}"
        )
    return design


# ---------------------------------------------------------------------------
# witnesses in brief


def _unobservable_brief(check: Check) -> str:
    w = check.witness or {}
    dim = w.get("unobservable_dimension", check.fields.get("unobservable_dimension"))
    text = f"a {dim}-dimensional unobservable subspace"
    if "z" in w:
        text += f", direction z = {_vector(w['z'])} (C A^k z = 0 for every k)"
    eigs = [e.get("eigenvalue") for e in w.get("unobservable_eigenvalues", []) or []]
    if eigs:
        text += f", at eigenvalue{'s' if len(eigs) > 1 else ''} {', '.join(_num(e) for e in eigs)}"
    return text


def _stealthy_brief(system: System, check: Check) -> list[str]:
    """Breaking set, max_removable vs 2s, and the stealthy attack with its size."""
    f, w = check.fields, check.witness or {}
    s = f.get("max_attacked")
    mr = f.get("max_removable")
    breaking = list(f.get("breaking_set") or [])
    lines = []
    if mr == -1:
        lines.append(
            "(A, C) itself is not observable: every sensor set is a breaking set, "
            "and no attack is needed to hide the direction z."
        )
    else:
        if s is None:  # pragma: no cover - sparse_observability checks always record it
            raise ValueError("the sparse_observability check has no max_attacked field")
        lines.append(f"max_removable = {mr} < 2s = {2 * s}.")
        lines.append(
            f"Breaking sensor set: {_sensors(system, breaking)}; removing "
            f"{'it' if len(breaking) == 1 else 'them'} leaves the plant unobservable."
        )
    if "attack_a" in w:
        a = np.asarray(w["attack_a"], dtype=float)
        b = np.asarray(w["attack_b"], dtype=float)
        z = np.asarray(w["z"], dtype=float)
        steps = a.shape[0]
        checked = (
            "verified by simulation"
            if w.get("verified")
            else f"NOT verified: output mismatch {w.get('residual', float('nan')):.2e}"
        )
        size_a = float(np.abs(a).max(initial=0.0))
        size_b = float(np.abs(b).max(initial=0.0))
        direction = f"z = {_vector(z)} (||z|| = {_num(np.linalg.norm(z))})"
        head = f"Stealthy attack over {steps} step{'s' if steps != 1 else ''} ({checked}): "
        if not w.get("sensors_a") and not w.get("sensors_b"):
            lines.append(
                f"{head}no attack is needed: x0 and x0 + z give identical outputs for {direction}."
            )
        elif not w.get("sensors_b"):
            lines.append(
                f"{head}an attacker on {_sensors(system, w['sensors_a'])} makes x0 look exactly "
                f"like x0 + z, undetectably. With {direction} the largest |attack| entry is "
                f"{_num(size_a)}; the attack scales with z, so it can be as large as desired."
            )
        else:
            lines.append(
                f"{head}the plant from x0 under attack_a on {_sensors(system, w['sensors_a'])} "
                f"and from x0 + z under attack_b on {_sensors(system, w['sensors_b'])} give "
                f"identical outputs. With {direction} the largest |entry| is {_num(size_a)} in "
                f"attack_a and {_num(size_b)} in attack_b; the attacks scale with z, so they can "
                f"be as large as desired."
            )
    return lines


def _instability_brief(w: Mapping[str, Any]) -> str:
    """Eigenvalue and growing initial error of an instability witness."""
    parts = []
    if "kind" in w:
        parts.append(str(w["kind"]))
    if "eigenvalue" in w:
        lam = (
            complex(w["eigenvalue"])
            if not isinstance(w["eigenvalue"], Mapping)
            else complex(w["eigenvalue"]["re"], w["eigenvalue"]["im"])
        )
        parts.append(f"eigenvalue {_num(lam)} of modulus {abs(lam):.6g}")
    for key in ("initial_error", "e0"):
        if key in w:
            parts.append(f"initial error {_vector(w[key])}")
    if "a_hat0" in w:
        parts.append(f"initial attack estimate {_vector(w['a_hat0'])}")
    if w.get("grows_by_factor_2"):
        parts.append("grows by a factor 2 in simulation")
    if "steps" in w:
        parts.append(f"over {w['steps']} steps")
    for key in ("growth", "residual"):
        if key in w and not isinstance(w[key], (list, tuple, np.ndarray)):
            parts.append(f"{key} {_num(w[key])}")
    return "; ".join(parts)


def _witness_brief(system: System, check: Check) -> list[str]:
    if check.verdict is not Verdict.FAILS or not check.witness:
        return []
    if check.id == "observability":
        return [_unobservable_brief(check)]
    if check.id == "sparse_observability":
        return _stealthy_brief(system, check)
    brief = _instability_brief(check.witness)
    return [brief] if brief else []


# ---------------------------------------------------------------------------
# assertions


def assert_observable(system: System) -> Check:
    """Assert that (A, C) is observable (``ssecert.observability`` holds).

    Parameters
    ----------
    system : System

    Returns
    -------
    Check
        The ``observability`` check (index in ``fields["observability_index"]``).

    Raises
    ------
    AssertionError
        If the plant is not observable (the message gives the dimension of
        the unobservable subspace and a direction z that no sensor sees) or
        observability could not be decided (the message says why).
    TypeError
        If ``system`` is not a System.

    Examples
    --------
    >>> import numpy as np
    >>> from ssecert import System
    >>> assert_observable(System([[1.0, 0.0099], [0.0, 0.9876]], [[1, 0]])).value
    2
    >>> assert_observable(System(np.eye(2), [[1, 0]]))
    Traceback (most recent call last):
    ...
    AssertionError: system 'system' (n = 2, p = 1) is not observable: a 1-dimensional ...
    """
    __tracebackhide__ = True  # pytest shows the caller's line, not ours
    from ..structure.observability import observability

    system = _require_system(system)
    check = observability(system)
    if check.verdict is Verdict.HOLDS:
        return check
    if check.verdict is Verdict.FAILS:
        raise AssertionError(
            f"{_label(system)} is not observable: {_unobservable_brief(check)}. {check.summary}"
        )
    raise AssertionError(
        f"observability of {_label(system)} could not be decided (inconclusive): {check.summary}"
    )


def assert_sparse_observable(
    system: System,
    s: int,
    *,
    method: str = "auto",
    max_sets: int | None = None,
    horizon: int | None = None,
) -> Check:
    """Assert that the plant tolerates s attacked sensors: 2 s <= max_removable.

    Parameters
    ----------
    system : System
    s : int
        Number of attacked sensors (>= 0).
    method : {"auto", "enumeration", "eigenspace"}, default "auto"
        Sparse-observability method.
    max_sets : int, optional
        Enumeration budget (default that of ``sparse_observability``).
    horizon : int, optional
        Steps of the stealthy-attack witness (default n).

    Returns
    -------
    Check
        The ``sparse_observability`` check.

    Raises
    ------
    AssertionError
        If s attacked sensors cannot be corrected: the message names the
        breaking sensor set by name and 0-based index, compares
        max_removable with 2s, and gives the stealthy attack (its sensors,
        its largest entry, the indistinguishable direction z and the number
        of steps it was verified over).  Also when the check is
        inconclusive, with the reason.
    TypeError
        If ``system`` is not a System.
    ValueError
        If s, method, max_sets or horizon is out of range.

    Examples
    --------
    >>> from ssecert import System
    >>> ugv = System([[1.0, 0.0099], [0.0, 0.9876]], [[1, 0], [0, 1], [0, 1]],
    ...              sensors=["position", "velocity-a", "velocity-b"], name="ugv")
    >>> assert_sparse_observable(ugv, 0).fields["max_removable"]
    0
    >>> assert_sparse_observable(ugv, 1)
    Traceback (most recent call last):
    ...
    AssertionError: system 'ugv' (n = 2, p = 3) is not 1-sparse observable: 1 attacked sensor ...
    """
    __tracebackhide__ = True  # pytest shows the caller's line, not ours
    from ..structure.sparse import DEFAULT_MAX_SETS, sparse_observability

    system = _require_system(system)
    s = as_int_option(s, "s", min_value=0)
    check = sparse_observability(
        system,
        s,
        method=method,
        max_sets=DEFAULT_MAX_SETS if max_sets is None else max_sets,
        horizon=horizon,
    )
    if check.verdict is Verdict.HOLDS:
        return check
    if check.verdict is Verdict.FAILS:
        lines = [
            f"{_label(system)} is not {s}-sparse observable: {s} attacked sensor"
            f"{'s' if s != 1 else ''} cannot be corrected."
        ]
        lines += _stealthy_brief(system, check)
        raise AssertionError("\n".join(lines))
    raise AssertionError(
        f"{s}-sparse observability of {_label(system)} could not be decided "
        f"(inconclusive): {check.summary}"
    )


def assert_deadbeat(A: Any, L: Any, C: Any, *, rtol: float | None = None) -> int:
    """Assert that the observer error matrix A - L C is nilpotent (a deadbeat observer).

    Observers are written x_hat+ = A x_hat + L (y - C x_hat), so the error
    obeys e+ = (A - L C) e and vanishes in k steps iff (A - L C)^k = 0.  The
    test is on the gain as given: F = A - L C is formed exactly from the
    floats of A, L and C and its powers computed in integers
    (``ssecert.design.gains.verify_deadbeat``).  By default the property is
    decided exactly: some power F^k, k <= n, is exactly zero.  A gain computed
    in floating point is usually nilpotent only to rounding; ``rtol`` accepts
    it when ||F^k|| <= rtol ||A||^k with ||F^(k-1)|| clearly above and a
    certified spectral radius below 1 (a gain that rounding made unstable
    fails, however small its powers look).

    Parameters
    ----------
    A : array_like, shape (n, n)
    L : array_like, shape (n, p)
    C : array_like, shape (p, n)
    rtol : float, optional
        Opt-in tolerance: a power with ||F^k|| / ||A||^k <= rtol counts as zero
        (``ssecert.design.gains.DEADBEAT_RTOL`` = 1e-8 is what ssecert's own
        deadbeat check uses), both norms in balanced power-of-two state units.
        Being relative to ||A||, it accepts any F that is small against A: with
        A = 2^30 I + F and L C = 2^30 I it accepts F = 0.875 I, whose error
        shrinks by 0.875 a step.  Default: exact nilpotency only.

    Returns
    -------
    int
        The nilpotency index k: the error vanishes exactly after k steps (to the
        tolerance ``rtol`` when given).

    Raises
    ------
    AssertionError
        If A - L C is not nilpotent (the message gives the power k = n and
        the residual ||F^k|| / ||A||^k, and whether it is nilpotent to a
        tolerance), the tolerance test cannot conclude (it gives both powers),
        or the gain as given is not certified stable (it gives the certified
        bounds on the spectral radius); also says when A + L C is nilpotent,
        i.e. when L has the opposite sign convention (the thesis's L1 = -L).
    ValueError
        If the matrices have inconsistent shapes or non-finite entries, or
        ``rtol`` is not a positive number.

    Examples
    --------
    >>> from ssecert import System
    >>> from ssecert.design.gains import deadbeat_gain
    >>> plant = System([[1.0, 0.0099], [0.0, 0.9876]], [[1, 0]])
    >>> assert_deadbeat(plant.A, deadbeat_gain(plant).L, plant.C, rtol=1e-8)
    2
    >>> assert_deadbeat([[0.0, 1.0], [0.0, 0.0]], [[0.0], [0.0]], [[0.0, 0.0]])
    2
    """
    __tracebackhide__ = True  # pytest shows the caller's line, not ours
    A = as_real_matrix(A, "A")
    n = A.shape[0]
    if A.shape[1] != n:
        raise ValueError(f"A must be square, got shape {A.shape}")
    C = as_real_matrix(C, "C", shape=(None, n), shape_hint="the number of states, from A")
    L = as_real_matrix(L, "L", shape=(n, C.shape[0]), shape_hint="n x p: states by sensors")
    if rtol is not None and not (
        isinstance(rtol, numbers.Real) and not isinstance(rtol, bool) and 0 < rtol < 1
    ):
        raise ValueError(f"rtol must be a number in (0, 1) or None (exact), got {rtol!r}")
    from ..design.gains import DEADBEAT_RTOL, verify_deadbeat

    test = verify_deadbeat(A, L, C, rtol=DEADBEAT_RTOL if rtol is None else float(rtol))
    if rtol is None:
        if test.exact_index is not None and test.exact_index <= n:
            return int(test.exact_index)
        raise AssertionError(_not_exactly_nilpotent(test, A, L, C))
    if test.verified:
        if test.index is None:  # pragma: no cover - verified means a nilpotency index was found
            raise RuntimeError("verify_deadbeat verified a gain without a nilpotency index")
        return int(test.index)
    raise AssertionError(_deadbeat_problem(test, A, L, C))


def _not_exactly_nilpotent(test: Any, A: np.ndarray, L: np.ndarray, C: np.ndarray) -> str:
    """The message of an exact ``assert_deadbeat`` on a gain whose powers never vanish."""
    norms, lower = test.relative_norms, test.relative_lower
    k = len(norms)
    if not test.verified:
        return f"no power of A - L C is exactly zero, nor zero to {test.rtol:.0e}: " + (
            _deadbeat_problem(test, A, L, C)
        )
    return (
        f"A - L C is not nilpotent: no power F^k, k = 1..{k}, is exactly zero (F = A - L C "
        f"formed exactly from the given floats; ||F^{k}|| / ||A||^{k} is between "
        f"{sig(lower[-1])} and {sig(norms[-1])}). It is nilpotent to the tolerance "
        f"{test.rtol:.0e}: ||F^{test.index}|| / ||A||^{test.index} <= "
        f"{sig(norms[test.index - 1])}, as a gain computed in floating point usually is; pass "
        f"rtol={test.rtol:.0e} to accept that"
    )


def _deadbeat_problem(test: Any, A: np.ndarray, L: np.ndarray, C: np.ndarray) -> str:
    """Why the tolerance test of ``assert_deadbeat`` did not pass, with the radius bounds."""
    from ..design.gains import verify_deadbeat

    norms, lower = test.relative_norms, test.relative_lower
    if test.index is None:
        k = len(norms)
        problem = (
            f"A - L C is not nilpotent: ||F^{k}|| / ||A||^{k} >= {lower[-1]:.3g} at the "
            f"power k = n = {k} (exactly between {lower[-1]:.3g} and {norms[-1]:.3g}), "
            f"where a nilpotent F has reached 0 (needs <= {test.rtol:.0e}; F = A - L C "
            f"formed exactly from the given floats)"
        )
    elif not test.conclusive:
        k = test.index
        previous = f">= {lower[k - 2]:.3g} only" if k > 1 else "= 1"
        problem = (
            f"the nilpotency test cannot conclude: ||F^{k}|| / ||A||^{k} <= "
            f"{norms[k - 1]:.3g} <= {test.rtol:.0e}, but ||F^{k - 1}|| / ||A||^{k - 1} "
            f"{previous}, not clearly above it (F = A - L C)"
        )
    else:
        k = test.index
        problem = (
            f"||F^{k}|| / ||A||^{k} <= {norms[k - 1]:.3g} looks deadbeat, but the gain as "
            f"given is not certified stable: {test.reason}"
        )
    flipped = verify_deadbeat(A, -np.asarray(L), C, rtol=test.rtol)
    if flipped.verified:
        problem += (
            f". A + L C is nilpotent (index {flipped.index}): L has the opposite sign "
            f"convention; ssecert writes x_hat+ = A x_hat + L (y - C x_hat), the thesis's "
            f"L1 is -L"
        )
    return (
        f"{problem}. Spectral radius of A - L C: certified between {sig(test.radius_lower)} and "
        f"{sig(test.radius_upper)}. Relative norms ||F^k|| / ||A||^k, k = 1..{len(norms)}: "
        f"{_vector(norms)}."
    )


def assert_schur(M: Any) -> Any:
    """Assert that every eigenvalue of M lies strictly inside the unit circle, certified.

    The certificate is a Lyapunov matrix P with M^T P M - P < 0, recomputed
    and checked against a floating-point error bound
    (``ssecert.stability.lyapunov.lyapunov_certificate``), or, where no P
    verifies, the exact decision on M's floats (an exact power of norm below
    1, or the Schur-Cohn test of the exact characteristic polynomial); a
    computed spectral radius below 1 alone is not accepted.

    Parameters
    ----------
    M : array_like, shape (n, n)

    Returns
    -------
    LyapunovCertificate
        With P, the contraction factor and the margin.  Decided exactly without a P
        (``decision``), the contraction is the spectral-radius bound 1 - gap rounded to a
        float: for a gap below 2^-53 (a rotation by 0.3 whose floats have determinant
        1 - 1e-17) it reads 1.0, and the gap is in ``margin``.

    Raises
    ------
    AssertionError
        If M has an eigenvalue of modulus >= 1 (the message gives that
        eigenvalue, its modulus and how instability was confirmed) or the
        certificate cannot be verified (it gives the eigenvalue of largest
        modulus and the reason).
    ValueError
        If M is not square or has non-finite entries.

    Examples
    --------
    >>> assert_schur([[0.5, 1.0], [0.0, 0.2]]).contraction < 1
    True
    >>> assert_schur([[0.5, 0.0], [0.0, 1.1]])
    Traceback (most recent call last):
    ...
    AssertionError: M is not Schur stable: eigenvalue 1.1 has modulus 1.1 >= 1 ...
    """
    __tracebackhide__ = True  # pytest shows the caller's line, not ours
    from ..stability.lyapunov import lyapunov_certificate

    M = as_real_matrix(M, "M")
    if M.shape[0] != M.shape[1]:
        raise ValueError(f"M must be square, got shape {M.shape}")
    cert = lyapunov_certificate(M)
    if cert.verdict is Verdict.HOLDS:
        return cert
    eigenvalues = np.linalg.eigvals(M)
    worst = complex(eigenvalues[int(np.argmax(np.abs(eigenvalues)))])
    if cert.witness is not None and "eigenvalue" in cert.witness:
        worst = complex(cert.witness["eigenvalue"])
    # enough digits to tell 1 + 1e-9 from 1
    # (a modulus that rounds onto 1 is written as its distance from it: 1 - 1.1e-16)
    where = (
        f"eigenvalue {_num_versus_one(worst)} has modulus {readable(abs(worst), 12, versus=1.0)}"
    )
    if cert.verdict is Verdict.FAILS:
        w = cert.witness or {}
        proof = w.get("proof") or {}
        if w.get("grows_by_factor_2"):
            how = "an initial state along its eigenvector grows by a factor 2 in simulation"
        elif proof.get("rigorous"):
            how = f"in exact arithmetic on the floats of M: {proof.get('reason')}"
        else:
            how = (
                f"the modulus exceeds 1 by more than its rounding error bound "
                f"{w.get('eigenvalue_error_bound', float('nan')):.1e}"
            )
        raise AssertionError(f"M is not Schur stable: {where} >= 1 (confirmed: {how}).")
    raise AssertionError(
        f"M could not be certified Schur stable (inconclusive): {where}; {cert.reason}."
    )


def assert_certified(design: Spec, *, method: str = "auto") -> Certificate:
    """Assert that every required check of a design holds (``ssecert.analyze``, no simulations).

    Required checks: observability, sparse_observability and, with an
    ``[observer]`` section, observer_gain and observer_stability.  Advisory
    checks (irrepresentable, iss_gain, thesis_assumptions) do not count.

    Parameters
    ----------
    design : Spec
        A validated design (``load_spec``, ``spec_from_dict``, the
        ``ssecert_example`` fixture or ``strategies.observer_designs``).
    method : {"auto", "enumeration", "eigenspace"}, default "auto"
        Sparse-observability method.

    Returns
    -------
    Certificate

    Raises
    ------
    AssertionError
        Listing every required check that fails or is inconclusive, with its
        summary and its witness in brief (breaking sensor set by name and
        index, unobservable direction, growing initial error, ...).
    TypeError
        If ``design`` is not a Spec.

    Examples
    --------
    >>> from ssecert import spec_from_dict
    >>> design = spec_from_dict({"name": "three-sensors",
    ...                          "system": {"A": [[0.5]], "C": [[1.0], [1.0], [1.0]]},
    ...                          "attack": {"max_attacked": 1},
    ...                          "observer": {"kind": "luenberger", "gain": "deadbeat"}})
    >>> assert_certified(design).verdict.value
    'holds'
    """
    __tracebackhide__ = True  # pytest shows the caller's line, not ours
    from ..analyze import analyze

    design = _require_spec(design)
    cert = analyze(design, method=method)
    bad = [c for c in cert.checks if c.required and c.verdict is not Verdict.HOLDS]
    if not bad:
        return cert
    required = sum(1 for c in cert.checks if c.required)
    lines = [
        f"design {design.name!r} ({design.source}) is not certified: {len(bad)} of "
        f"{required} required checks do not hold."
    ]
    for check in bad:
        verdict = "FAILS" if check.verdict is Verdict.FAILS else "inconclusive"
        lines.append(f"- {check.id} {verdict}: {check.summary}")
        lines += [f"    {line}" for line in _witness_brief(design.system, check)]
    raise AssertionError("\n".join(lines))


def _scenario(design: Spec, scenario: str | Mapping[str, Any]) -> dict[str, Any]:
    """The named [[scenario]] of the design, or a mapping validated as the spec loader does."""
    if isinstance(scenario, str):
        for table in design.scenarios:
            if table["name"] == scenario:
                return dict(table)
        names = ", ".join(repr(t["name"]) for t in design.scenarios) or "none"
        raise ValueError(
            f"scenario {scenario!r} is not a [[scenario]] of design "
            f"{design.name!r}; its scenarios: {names}"
        )
    if not isinstance(scenario, Mapping):
        raise TypeError(
            f"scenario must be the name of one of the design's scenarios or a "
            f"mapping with the keys of a [[scenario]] table, got {describe(scenario)}"
        )
    from ..spec import spec_from_dict

    table = {"name": "custom", **scenario}
    system = design.system
    checked = spec_from_dict(
        {
            "name": design.name,
            "system": {
                "A": system.A.tolist(),
                "C": system.C.tolist(),
                "sensors": list(system.sensors),
            },
            "attack": {"max_attacked": design.max_attacked},
            "scenario": [table],
        },
        source="assert_recovers(scenario=...)",
    )
    return dict(checked.scenarios[0])


def _tolerance_words(tol: float, atol: float) -> str:
    if atol == 0:
        return f"a relative state error above tol = {tol:g}"
    if tol == 0:
        return f"an error ||x_hat - x|| above atol = {atol:g}"
    return f"an error ||x_hat - x|| above atol + tol ||x|| (atol = {atol:g}, tol = {tol:g})"


def assert_recovers(
    design: Spec,
    scenario: str | Mapping[str, Any],
    tol: float,
    *,
    atol: float = 0.0,
    runs: int | None = None,
    steps: int | None = None,
    seed: int | None = None,
) -> Any:
    """Assert that the design's observer recovers the state in every run of a scenario.

    The observer is simulated with ``ssecert.simulation.engine.simulate_scenario``
    (vectorised over runs; run r draws x0, the attack and the noise from
    ``numpy.random.default_rng([seed, r])``).  Every run must end with

        ||x_hat - x|| <= atol + tol * max(||x||, 1e-9 ||x0||),

    as ``numpy.isclose`` combines its tolerances: ``tol`` alone bounds the
    relative state error (ssecert's metric; see ``ssecert.simulation.metrics``),
    ``atol`` alone the absolute error.  On a plant whose state decays the
    relative error grows without bound while the error converges to a bias:
    give ``atol`` there (``assert_recovers(design, scenario, 0, atol=0.5)``).

    Parameters
    ----------
    design : Spec
        A design with an ``[observer]`` section.
    scenario : str or mapping
        The name of one of the design's ``[[scenario]]`` sections, or a
        mapping with the keys of a ``[[scenario]]`` table (``attack``,
        ``sensors`` or ``count``, ``magnitude``, ``period``, ``noise``,
        ``steps``, ``runs``, ``seed``; ``name`` defaults to ``"custom"``),
        validated as the spec loader validates it.
    tol : float
        Largest acceptable final relative error (>= 0; 0 with ``atol`` for an absolute
        tolerance alone).
    atol : float, default 0
        Largest acceptable final absolute error ||x_hat - x|| (>= 0); with both 0 the
        error must vanish.
    runs, steps, seed : int, optional
        Override the scenario's values.

    Returns
    -------
    ScenarioResult
        Per-run, per-step metrics.

    Raises
    ------
    AssertionError
        If some run ends above tol: the message gives the number of such
        runs, the worst run's index and final error, the mean, and the
        scenario (attack kind, sensors, seed, runs, steps) to reproduce it.
        Also when the observer gain cannot be computed.
    TypeError
        If design is not a Spec or scenario is neither a name nor a mapping.
    ValueError
        If the design has no observer, the scenario is unknown or invalid
        (``ssecert.SpecError`` names the key), tol is negative, or a
        stealthy scenario is asked of a plant that has no stealthy attack.

    Examples
    --------
    >>> from ssecert import spec_from_dict
    >>> design = spec_from_dict({"name": "three-sensors",
    ...                          "system": {"A": [[0.5]], "C": [[1.0], [1.0], [1.0]]},
    ...                          "attack": {"max_attacked": 0},
    ...                          "observer": {"kind": "luenberger", "gain": "deadbeat"}})
    >>> result = assert_recovers(design, {"attack": "none", "steps": 5, "runs": 3}, 1e-12)
    >>> result.runs
    3
    """
    __tracebackhide__ = True  # pytest shows the caller's line, not ours
    from ..design.gains import GainError
    from ..observers import build_observer
    from ..simulation.engine import simulate_scenario

    design = _require_spec(design)
    tol = as_float_option(tol, "tol", min_value=0.0)
    atol = as_float_option(atol, "atol", min_value=0.0)
    if design.observer is None:
        raise ValueError(f"design {design.name!r} has no [observer] section to simulate")
    table = _scenario(design, scenario)
    try:
        observer = build_observer(design.system, design.observer)
    except GainError as exc:
        raise AssertionError(
            f"the observer of design {design.name!r} cannot be built: the gain "
            f"cannot be computed ({exc})"
        ) from None
    result = simulate_scenario(
        observer, table, runs=runs, steps=steps, seed=seed, max_attacked=design.max_attacked
    )
    assert result.absolute_error is not None  # simulate_scenario always fills it
    rel: np.ndarray = np.asarray(result.relative_error[-1], dtype=np.float64)
    error: np.ndarray = np.asarray(result.absolute_error[-1], dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        state = np.where(error > 0, error / rel, 0.0)  # max(||x||, 1e-9 ||x0||)
        allowed = atol + tol * state
        bad = ~(error <= allowed)  # NaN (a diverged run) counts as failing
    if not bad.any():
        return result
    final = rel if atol == 0 else error
    excess = rel if atol == 0 else error - allowed
    ranked = np.where(np.isnan(error), np.inf, excess)
    worst = int(np.argmax(ranked))
    shape = ("noise",) if table["attack"] == "none" else ("sensors", "count", "magnitude",
                                                          "period", "noise")  # fmt: skip
    where = ", ".join(f"{key} = {table[key]}" for key in shape if key in table)
    raise AssertionError(
        f"the {observer.kind} observer of design {design.name!r} does not recover under scenario "
        f"{table['name']!r}: {int(bad.sum())} of {result.runs} runs end with "
        + _tolerance_words(tol, atol)
        + f" after {result.steps} steps.\n"
        f"worst run: index {worst}, final {'relative ' if atol == 0 else ''}error "
        f"{_num(final[worst])}"
        + (
            ""
            if atol == 0 or tol == 0 or not np.isfinite(allowed[worst])
            else f" (allowed {_num(allowed[worst])})"
        )
        + f"; mean {_num(np.mean(final))}.\n"
        f"scenario: attack {table['attack']!r}"
        + (f" ({where})" if where else "")
        + f", seed {result.seed}, runs {result.runs}, steps {result.steps}; run r draws from "
        f"numpy.random.default_rng([{result.seed}, r])."
    )
