"""Spec -> Certificate: every structural check of a design, no simulations."""

from __future__ import annotations

import datetime as _dt
import importlib.metadata
import platform
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

from .budget import Budget, Laps
from .context import AnalysisContext, sparse_key
from .inputs import as_spec
from .noise import MeasurementNoise
from .numerics.linalg import balanced_units, eigen_clusters
from .results import Certificate, Check, Step, Verdict, Withdrawn, decide, withdraw
from .spec import Spec
from .structure.cost import rounded_seconds
from .structure.irrepresentable import irrepresentable
from .structure.observability import observability
from .structure.sparse import DEFAULT_MAX_SETS, DEFAULT_TIME_BUDGET, sparse_observability
from .tolerances import Tolerances

__all__ = ["analyze", "environment"]


def _against_observability(sparse: Check, observable: Check) -> Check:
    """The sparse-observability check as reported: withdrawn (``withdraw``) where its
    max_removable contradicts the observability check decided before it (max_removable >= 0
    exactly when (A, C) is observable).  The two are decided by different methods from the
    same eigenvalues, so this finds nothing on a correct run: what it finds is a defect,
    reported as such by the check that sees it."""
    removable = sparse.fields.get("max_removable")
    lower = sparse.fields.get("max_removable_is_lower_bound")
    why = None
    if observable.verdict is Verdict.HOLDS and removable == -1 and not lower:
        why = "(A, C) observable, and max_removable = -1"
    elif observable.verdict is Verdict.FAILS and removable is not None and removable >= 0:
        why = f"(A, C) unobservable, and max_removable = {removable} >= 0"
    return sparse if why is None else withdraw(sparse, observable, why)


def _withdrawn_notes(checks: list[Check]) -> list[str]:
    """A note for each check withdrawn for contradicting another (``withdraw``)."""
    return [
        f"{c.id} contradicted {c.evidence['contradicts']} ({c.evidence['contradiction']}); it "
        f"is reported inconclusive"
        for c in checks
        if c.code is Withdrawn.CONTRADICTS
    ]


def environment() -> dict[str, str]:
    """Versions of ssecert, Python and the numerical libraries."""
    import numpy
    import scipy

    from ._version import __version__

    versions = {
        "ssecert": __version__,
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
    }
    for module in ("control", "cvxpy", "clarabel", "sympy"):
        versions[module] = _installed_version(module)
    return versions


def _installed_version(module: str) -> str:
    """The version of a module, without importing it when it is not loaded yet (importing
    python-control alone can take seconds)."""
    loaded = sys.modules.get(module)
    if loaded is not None and hasattr(loaded, "__version__"):
        return str(loaded.__version__)
    try:
        return importlib.metadata.version(module)
    except importlib.metadata.PackageNotFoundError:  # pragma: no cover - depends on the install
        return "not installed"


def analyze(
    spec: Any,
    *,
    max_attacked: int | None = None,
    horizon: int | None = None,
    observer: Mapping[str, Any] | None = None,
    method: str = "auto",
    max_sets: int = DEFAULT_MAX_SETS,
    seed: int = 0,
    tolerances: Tolerances | None = None,
    progress: Callable[[str, int, int], None] | None = None,
    budget: Budget | None = None,
    context: AnalysisContext | None = None,
    time_budget: float | None = DEFAULT_TIME_BUDGET,
    client: Any | None = None,
    device: str | None = None,
    noise: MeasurementNoise | float | None = None,
) -> Certificate:
    """Run the structural checks of a design.

    Parameters
    ----------
    spec : Spec, System, control.StateSpace, scipy.signal.dlti, str or path
        A validated design (``load_spec`` or ``spec_from_dict``), or what
        ``ssecert.inputs.as_spec`` makes one of: a plant (then
        ``max_attacked`` is required), a discrete-time python-control or
        SciPy system, a spec file or a packaged example's name.
    max_attacked, horizon : int, optional
        s and tau, overriding the spec's.
    observer : mapping, optional
        An ``[observer]`` section, replacing the spec's.
    method : {"auto", "enumeration", "eigenspace"}, default "auto"
        Sparse-observability method.
    max_sets : int, default 50,000,000
        Enumeration budget (sensor sets, hyperplanes or supports).
    seed : int, default 0
        Seed of the initial state used to simulate the stealthy attack.
    tolerances : Tolerances, optional
    progress : callable, optional
        ``progress(check_id, done, total)`` during long enumerations.
    budget : Budget, optional
        Memory and work allowed for each analysis step (default ``Budget()``:
        2 GiB, 1e12 operations); a step that does not fit is inconclusive
        with its estimate.
    time_budget : float or None, default 5
        Seconds spent refining max_removable once the sparse-observability
        verdict is decided (``sparse_observability``); None for the exact
        value however long it takes.
    client : dask.distributed.Client, optional
        Split the enumerations (sensor sets, attack supports) over the
        client's workers, with the same answers as in-process.
    device : {"cpu", "cuda", "numpy"}, optional
        Screen the sensor sets of the sparse-observability enumeration on
        an accelerator, with the same answers (``sparse_observability``).
    context : AnalysisContext, optional
        Where the run keeps what later steps share (the observer built from
        the design, the sparse-observability check whose stealthy attack the
        simulations replay); ``certify`` passes its own.
    noise : MeasurementNoise or float, optional
        Bounded measurement noise, replacing the spec's ``[noise]`` section (a
        number: that bound on every sample of every sensor, replacing the section's
        measurement bound only, its process noise kept).

    Returns
    -------
    Certificate
        Checks ``observability``, ``sparse_observability`` (required) and
        ``irrepresentable`` (advisory); with noise (the ``noise`` argument or
        the spec's ``[noise]``) also ``decoder_error_bound``, ``l1_error_bound`` and
        ``lasso_error_bound`` (advisory); with an
        ``[observer]`` section also
        ``observer_gain``, ``observer_stability`` (required), ``iss_gain``
        and ``thesis_assumptions`` (advisory).

    Examples
    --------
    >>> from ssecert.examples import load_example
    >>> cert = analyze(load_example("notes-example-2"))
    >>> cert.verdict.value, cert["sparse_observability"].fields["breaking_set"]
    ('fails', [0, 2])
    """
    spec = as_spec(spec, max_attacked=max_attacked, horizon=horizon, observer=observer)
    tol = Tolerances.check(tolerances)
    system = spec.system
    clock = _Clock()
    clock.begin("eigenvalues")
    # shared by the structural checks, which decide in power-of-two units
    units = balanced_units(system)
    eig = eigen_clusters(units.system.A, tolerances=tol, unit=units.alpha)
    clock.lap("eigenvalues", None)
    sparse_timing: dict[str, Any] = {}
    observer_timings: dict[str, float] = {}
    steps = [
        Step("observability", lambda: observability(system, tolerances=tol, eigen=eig)),
        Step("sparse_observability", lambda observable: _against_observability(sparse_observability(
            system,
            spec.max_attacked,
            method=method,
            max_sets=max_sets,
            horizon=spec.horizon,
            seed=seed,
            tolerances=tol,
            progress=_relay(progress, "sparse_observability"),
            eigen=eig,
            time_budget=time_budget,
            client=client,
            timing=sparse_timing,
            device=device,
        ), observable), needs=("observability",)),
        Step("irrepresentable", lambda: irrepresentable(
            system,
            spec.max_attacked,
            horizon=spec.horizon,
            max_sets=max_sets,
            tolerances=tol,
            progress=_relay(progress, "irrepresentable"),
            budget=budget,
            client=client,
            time_budget=time_budget,
        )),
    ]  # fmt: skip
    bounded = _noise_of(spec, noise)
    if bounded is not None:
        steps.append(
            Step(
                "decoder_error_bound",
                lambda sparse: _decoder_bound(spec, bounded, sparse, max_sets),
                needs=("sparse_observability",),
            )
        )
        steps.append(
            Step(
                "l1_error_bound",
                lambda sparse: _l1_bound(spec, bounded, sparse),
                needs=("sparse_observability",),
            )
        )
        steps.append(
            Step(
                "lasso_error_bound",
                lambda sparse: _lasso_bound(spec, bounded, sparse, max_sets),
                needs=("sparse_observability",),
            )
        )
    if spec.observer is not None:
        from .stability.checks import observer_checks
        from .stability.constant_attack import default_attacks

        observer_section = spec.observer
        steps.append(
            Step(
                "observer_checks",
                lambda observable: observer_checks(
                    system,
                    observer_section,
                    observability=observable,
                    seed=seed,
                    budget=budget,
                    context=context,
                    tolerances=tol,
                    constant_attacks=default_attacks(system.p, spec.max_attacked, spec.scenarios),
                    timings=observer_timings,
                    noise=bounded,
                ),
                needs=("observability",),
            )
        )
    decided = decide(steps, clock)
    checks: list[Check] = [
        decided["observability"], decided["sparse_observability"], decided["irrepresentable"],
        *(
            decided[key]
            for key in ("decoder_error_bound", "l1_error_bound", "lasso_error_bound")
            if key in decided
        ),
        *decided.get("observer_checks", []),
    ]  # fmt: skip
    notes = _withdrawn_notes(checks)
    if context is not None:  # the check as reported: its witness is the one replayed
        context.put(sparse_key(spec.max_attacked), checks[1])
    notes.extend(_short_horizon_notes(spec, checks[0]))
    if bounded is not None and spec.observer is not None:
        if not any(c.id == "observer_noise_bound" for c in checks):
            notes.append("observer_noise_bound: not computed: the observer was not built")
    notes.extend(f"sparse_observability: {text}" for text in sparse_timing.get("placement", []))
    meta = _meta(spec, seed, budget, notes)
    meta["timings"] = clock.record(sparse_timing, observer_timings)
    return Certificate(system=system, checks=tuple(checks), meta=meta)


def _noise_of(spec: Spec, noise: MeasurementNoise | float | None) -> MeasurementNoise | None:
    """The noise the bounds are certified for: the argument's, else the spec's (a number
    replaces the spec's measurement bound only: its process noise stays)."""
    if noise is None:
        return spec.noise
    if isinstance(noise, MeasurementNoise):
        if noise.eta.shape != (spec.system.p,):
            raise ValueError(
                f"noise: {noise.eta.size} bounds for the plant's {spec.system.p} sensors"
            )
        if noise.process is not None and noise.process.input.shape[0] != spec.system.n:
            raise ValueError(
                f"noise: its process noise enters {noise.process.input.shape[0]} states, the "
                f"plant has {spec.system.n}"
            )
        return noise
    if spec.noise is None:
        return MeasurementNoise.read(noise, spec.system.p)
    # the measurement bound replaced, the spec's process noise and draws kept (as --noise)
    return replace(spec.noise, eta=MeasurementNoise.read(noise, spec.system.p).eta, norm="inf")


def _at_sensors(spec: Spec, noise: MeasurementNoise) -> tuple[MeasurementNoise | None, Any]:
    """The per-sensor bounds a decoder's window sees (``MeasurementNoise.at_sensors``: the
    measurement noise plus the process noise's reach; None where they leave the float range),
    and what a decoder bound records: ``sources``, the spec's noise where it has process noise
    (else None), and ``noise``, the bounds seen (the measurement noise where out of range)."""
    seen = noise.at_sensors(spec.system.A, spec.system.C, spec.horizon)
    sources = noise if noise.process is not None else None
    return seen, {"noise": noise.measurement_only() if seen is None else seen, "sources": sources}


def _decoder_bound(spec: Spec, noise: MeasurementNoise, sparse: Check, max_sets: int) -> Check:
    """The decoder_error_bound check: none exists when sparse_observability found a breaking
    set (it fails with it), else the certified bound (``decoder_error_bound``) for the noise
    the window sees at the sensors."""
    from .structure.noise import DEFAULT_MAX_SETS as BOUND_SETS
    from .structure.noise import (
        BoundCode,
        DecoderErrorBound,
        decoder_error_bound,
        with_sources,
    )
    from .structure.noise_messages import decoder_bound_check

    breaking = sparse.fields.get("breaking_set")
    seen, records = _at_sensors(spec, noise)
    tau, s = spec.horizon, spec.max_attacked
    if sparse.verdict is Verdict.FAILS and breaking is not None:
        found = DecoderErrorBound(
            BoundCode.NOT_SPARSE_OBSERVABLE, float("inf"), 0.0, horizon=tau, max_attacked=s,
            facts={"breaking_set": [int(i) for i in breaking]}, **records,
        )  # fmt: skip
    elif seen is None:
        found = DecoderErrorBound(
            BoundCode.OUT_OF_RANGE, float("inf"), 0.0, horizon=tau, max_attacked=s, **records
        )
    else:
        found = decoder_error_bound(
            spec.system,
            s,
            seen,
            horizon=tau,
            max_sets=min(max_sets, BOUND_SETS),
            sources=records["sources"],
        )
        if records["sources"] is not None:
            found = with_sources(spec.system, found, records["sources"])
    return decoder_bound_check(spec.system, found)


def _l1_bound(spec: Spec, noise: MeasurementNoise, sparse: Check) -> Check:
    """The l1_error_bound check: none exists when sparse_observability found a breaking set
    (it fails with it), else the certified bound (``l1_error_bound``) for the noise the
    window sees at the sensors."""
    from .structure.l1_bound import L1BoundCode, L1ErrorBound, l1_error_bound, with_lower_bound
    from .structure.noise_messages import l1_bound_check

    breaking = sparse.fields.get("breaking_set")
    seen, records = _at_sensors(spec, noise)
    tau, s = spec.horizon, spec.max_attacked
    if sparse.verdict is Verdict.FAILS and breaking is not None:
        found = L1ErrorBound(
            L1BoundCode.NOT_NULL_SPACE, float("inf"), horizon=tau, max_attacked=s, **records
        )
        return l1_bound_check(spec.system, found, [int(i) for i in breaking])
    if seen is None:
        found = L1ErrorBound(
            L1BoundCode.NOT_SOLVED, float("inf"), horizon=tau, max_attacked=s, **records
        )
        return l1_bound_check(spec.system, found)
    found = l1_error_bound(spec.system, s, seen, horizon=tau)
    found = with_lower_bound(spec.system, replace(found, sources=records["sources"]))
    return l1_bound_check(spec.system, found)


def _lasso_bound(spec: Spec, noise: MeasurementNoise, sparse: Check, max_sets: int) -> Check:
    """The lasso_error_bound check: none exists when sparse_observability found a breaking set
    (it fails with it), else the certified bound (``lasso_error_bound``) for the noise the
    window sees at the sensors (the worst case beside it built within the measurement noise
    alone)."""
    from .structure.lasso_bound import DEFAULT_MAX_SETS as LASSO_SETS
    from .structure.lasso_bound import LassoBoundCode, LassoErrorBound, lasso_error_bound
    from .structure.noise_messages import lasso_bound_check

    breaking = sparse.fields.get("breaking_set")
    seen, records = _at_sensors(spec, noise)
    tau, s = spec.horizon, spec.max_attacked
    if sparse.verdict is Verdict.FAILS and breaking is not None:
        found = LassoErrorBound(
            LassoBoundCode.NOT_IRREPRESENTABLE, float("inf"), horizon=tau, max_attacked=s,
            **records,
        )  # fmt: skip
        return lasso_bound_check(spec.system, found, [int(i) for i in breaking])
    if seen is None:
        found = LassoErrorBound(
            LassoBoundCode.OUT_OF_RANGE, float("inf"), horizon=tau, max_attacked=s, **records
        )
        return lasso_bound_check(spec.system, found)
    found = lasso_error_bound(spec.system, s, seen, horizon=tau, max_sets=min(max_sets, LASSO_SETS))
    return lasso_bound_check(spec.system, replace(found, sources=records["sources"]))


class _Clock(Laps):
    """``Laps`` of an analysis, and the certificate's ``meta.timings`` from them."""

    def record(self, sparse: dict[str, Any], observer: dict[str, float]) -> dict[str, float]:
        """Seconds of each step and of the whole run (``analyze``), each observer check's
        (``observer_checks.ID``), and the sparse-observability check's split into deciding the
        verdict and refining max_removable past it."""
        out = {"analyze": rounded_seconds(time.monotonic() - self.start)}
        out.update((name, rounded_seconds(t)) for name, t in self.seconds.items())
        out.update((f"observer_checks.{k}", rounded_seconds(t)) for k, t in observer.items())
        if sparse:
            out["sparse_observability.to_verdict"] = rounded_seconds(sparse["seconds_to_verdict"])
            out["sparse_observability.refinement"] = rounded_seconds(sparse["refinement_seconds"])
        return out


def _relay(
    progress: Callable[[str, int, int], None] | None, check_id: str
) -> Callable[[int, int], None] | None:
    """``progress`` for one check, as the ``progress(done, total)`` its analysis calls."""
    if progress is None:
        return None
    return lambda done, total: progress(check_id, done, total)


def _short_horizon_notes(spec: Spec, observability_check: Check) -> list[str]:
    """A note when the horizon is shorter than the observability index, else none."""
    index = observability_check.fields.get("observability_index")
    if index is None or spec.horizon >= index:
        return []
    steps = f"{spec.horizon} step{'s' if spec.horizon != 1 else ''} of output"
    verb = "do" if spec.horizon != 1 else "does"
    return [
        f"horizon = {spec.horizon} is shorter than the observability index {index}: "
        f"{steps} {verb} not determine the state even without attack, so the "
        f"irrepresentable check (on O_tau with tau = horizon) cannot hold; sparse "
        f"observability is a property of the plant and does not depend on the horizon"
    ]


def _meta(spec: Spec, seed: int, budget: Budget | None, notes: list[str]) -> dict[str, Any]:
    """The certificate's meta: the spec, the run's options, the date, the versions and notes."""
    return {
        "spec": {"source": spec.source, "sha256": spec.sha256, "name": spec.name},
        "max_attacked": spec.max_attacked,
        "horizon": spec.horizon,
        "seed": seed,
        "budget": (budget or Budget()).to_dict(),
        "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "versions": environment(),
        "notes": notes,
    }
