"""``ssecert certify``: every check, the simulations and the report data of a design.

Spec -> analyze (structure, gains, certificates) -> simulations of the
spec's scenarios, plus the stealthy attack when the plant has one -> the
stealthy attack's demonstration trajectories and, for sparse observers,
the certified (shrink, step) region -> ``CertifyResult``, which renders to
JSON, HTML and the terminal.
"""

from __future__ import annotations

import shlex
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .analyze import analyze
from .base.display import html_display
from .budget import Budget, Refusal, ResourceLimitError
from .context import OBSERVER, AnalysisContext
from .inputs import as_spec
from .results import Certificate, Verdict, to_jsonable
from .simulation.engine import ScenarioResult
from .spec import SCENARIO_DEFAULTS, Spec
from .stability.noise_messages import initial_error_fading
from .structure.sparse import DEFAULT_TIME_BUDGET
from .tolerances import Tolerances

__all__ = ["CertifyResult", "certify", "REGION_LIMIT"]

REGION_LIMIT = 40  # largest Lur'e state + nonlinearity size mapped by default
STEALTHY_DEMO_STEPS = 60
STEALTHY_DEMO_MAX_STEPS = 1000  # the demonstration is a plot: longer horizons are cut here

Progress = Callable[[str], None]


@dataclass(frozen=True)
class CertifyResult:
    """Everything ``ssecert certify`` reports about one design.

    Attributes
    ----------
    spec : Spec
    certificate : Certificate
        The checks and the overall verdict (the exit status follows it).
    simulations : dict
        Scenario name -> ``ScenarioResult``, or ``{"skipped": reason}``.
    stealthy : dict or None
        Demonstration of the stealthy attack: the state trajectories from
        x0 and x0 + z and their common output.
    region : RegionMap or None
        Certified (shrink, step) region of a sparse observer.
    seed : int
    command : str
        The command that reproduces the report.
    notes : tuple of str
    comparison : dict or None
        For ``ssecert design``: the synthesised design beside the spec's own
        (``ssecert.design.search.compare_designs``).
    """

    spec: Spec
    certificate: Certificate
    simulations: dict[str, Any] = field(default_factory=dict)
    stealthy: dict[str, Any] | None = None
    region: Any | None = None
    seed: int = 0
    command: str = ""
    notes: tuple[str, ...] = ()
    comparison: dict[str, Any] | None = None

    @property
    def exit_code(self) -> int:
        return self.certificate.exit_code

    def to_dict(self) -> dict[str, Any]:
        """The JSON certificate: the fields of docs/architecture.md plus simulations and the region."""
        out = self.certificate.to_dict()
        out["simulations"] = {
            name: (res.to_dict() if hasattr(res, "to_dict") else res)
            for name, res in self.simulations.items()
        }
        if self.region is not None:
            out["certified_region"] = to_jsonable(self.region.to_dict())
        out["reproduce"] = self.command
        out["seed"] = self.seed
        if self.notes:
            out["notes"] = list(self.notes)
        if self.comparison is not None:
            out["design_comparison"] = self.comparison
        return to_jsonable(out)


def _stealthy_demo(spec: Spec, witness: Mapping[str, Any], seed: int) -> dict[str, Any]:
    """Long enough trajectories of the stealthy attack for a plot."""
    from .structure.attacks import stealthy_attack

    system = spec.system
    breaking = sorted(set(witness["sensors_a"]) | set(witness["sensors_b"]))
    z = np.asarray(witness["z"], dtype=float)
    steps = max(STEALTHY_DEMO_STEPS, min(spec.horizon, STEALTHY_DEMO_MAX_STEPS))
    demo = stealthy_attack(system, breaking, z, spec.max_attacked, horizon=steps, seed=seed)
    steps = demo.attack_a.shape[0]
    xa = np.empty((steps, system.n))
    xb = np.empty((steps, system.n))
    a, b = demo.x0.copy(), demo.x0 + demo.z
    A = demo.time_scale * system.A  # the plant itself when its witness fits in floats
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(steps):
            xa[k], xb[k] = a, b
            a, b = A @ a, A @ b
    attacked = list(demo.sensors_a) or list(range(system.p))
    return {
        "states_a": xa,
        "states_b": xb,
        "outputs": demo.outputs_a,
        "outputs_b": demo.outputs_b,
        "residual": demo.residual,
        "component": int(np.argmax(np.abs(demo.z))),
        "sensor": int(attacked[0]),
        "sensors_a": list(demo.sensors_a),
        "sensors_b": list(demo.sensors_b),
        "z": demo.z,
        "time_scale_log2": (int(np.log2(demo.time_scale)) if demo.time_scale != 1.0 else None),
    }


def certify(
    spec: Any,
    *,
    max_attacked: int | None = None,
    horizon: int | None = None,
    observer: Mapping[str, Any] | None = None,
    scenarios: Sequence[Mapping[str, Any]] | None = None,
    seed: int | None = None,
    simulate: bool = True,
    runs: int | None = None,
    steps: int | None = None,
    region: bool = True,
    method: str = "auto",
    max_sets: int | None = None,
    client: Any | None = None,
    progress: Progress | None = None,
    command: str | None = None,
    budget: Budget | None = None,
    time_budget: float | None = DEFAULT_TIME_BUDGET,
    tolerances: Tolerances | None = None,
    set_progress: Callable[[str, int, int], None] | None = None,
    device: str | None = None,
) -> CertifyResult:
    """Certify a design: every check, the simulations and the report data.

    Parameters
    ----------
    spec : Spec, System, control.StateSpace, scipy.signal.dlti, str or path
        The design, or what ``ssecert.inputs.as_spec`` makes one of (a plant
        with ``max_attacked``, a discrete-time python-control or SciPy system,
        a spec file, a packaged example's name).
    max_attacked, horizon : int, optional
        s and tau, overriding the spec's.
    observer : mapping, optional
        An ``[observer]`` section, replacing the spec's.
    scenarios : sequence of mappings, optional
        ``[[scenario]]`` sections, replacing the spec's.
    seed : int, optional
        Replaces every scenario's seed (and seeds the stealthy-attack check).
    simulate : bool, default True
        Run the scenarios (``--no-sim`` turns this off).
    runs, steps : int, optional
        Override the scenarios' values.
    region : bool, default True
        Map the certified (shrink, step) region of a sparse observer when its
        Lur'e model is small enough (state plus nonlinearities <= 40).
    method : str, default "auto"
        Sparse-observability method.
    max_sets : int, optional
        Enumeration budget.
    client : dask.distributed.Client, optional
        Spread the sparse-observability enumeration and the simulation runs
        over Dask workers (the same answers as in-process).
    progress : callable, optional
        ``progress(message)`` before each long stage.
    command : str, optional
        The command line to show in the report's reproduce section.
    budget : Budget, optional
        Memory and work allowed for each analysis step, each simulated
        scenario and each LMI of the region map (default ``Budget()``: 2 GiB,
        1e12 operations).  What does not fit is inconclusive (checks) or
        skipped (simulations, region), with the estimate in the reason.
    time_budget : float or None, default 5
        Seconds spent refining max_removable once the verdict is decided;
        None for the exact value (``analyze``).  The certified region's map
        starts no grid point after ``region_time_limit(time_budget)`` seconds
        (the budget, at least 30 s; no limit with None).
    tolerances : Tolerances, optional
        The tolerances of every check and of the observer's gain (default
        ``Tolerances()``); each check reports those its verdict rests on.
    set_progress : callable, optional
        ``set_progress(check_id, done, total)`` during long enumerations
        (``analyze``'s ``progress``).
    device : {"cpu", "cuda", "numpy"}, optional
        Screen the sparse-observability enumeration's sensor sets on an
        accelerator, with the same answers (``analyze``).

    Returns
    -------
    CertifyResult

    Examples
    --------
    >>> from ssecert.examples import load_example
    >>> result = certify(load_example("notes-example-1"), simulate=False)
    >>> result.certificate.verdict.value, result.stealthy["sensors_a"]
    ('fails', [2])
    """
    overridden = any(v is not None for v in (max_attacked, horizon, observer, scenarios))
    spec = as_spec(
        spec, max_attacked=max_attacked, horizon=horizon, observer=observer, scenarios=scenarios
    )
    say = progress or (lambda message: None)
    base_seed = 0 if seed is None else int(seed)
    budget = budget or Budget()
    tol = Tolerances.check(tolerances)
    kwargs: dict[str, Any] = {
        "tolerances": tol,
        "client": client,
        "progress": set_progress,
        "method": method,
        "seed": base_seed,
        "budget": budget,
        "time_budget": time_budget,
        "device": device,
    }
    if max_sets is not None:
        kwargs["max_sets"] = max_sets
    say("structural checks and certificates")
    context = AnalysisContext()
    cert = analyze(spec, context=context, **kwargs)
    notes: list[str] = []
    stealthy = _stealthy_of(spec, cert, base_seed)
    design = _observer_design(spec, context, budget, tol, notes)
    simulations: dict[str, Any] = {}
    if simulate and spec.observer is not None:
        simulations = _simulations(
            design,
            _scenarios(spec, design, stealthy),
            say,
            runs=runs,
            steps=steps,
            seed=seed,
            max_attacked=spec.max_attacked,
            client=client,
            budget=budget,
            context=context,
        )
        noise_check = cert.get("observer_noise_bound")
        if noise_check is not None and noise_check.verdict is Verdict.HOLDS and design is not None:
            radius = noise_check.fields.get("region_radius")
            if radius is None:
                simulations = _beside_noise_bound(spec, design, noise_check, simulations)
            else:  # a bound from near zero error: not for the scenarios' initial errors
                notes.append(
                    "observer_noise_bound: holds only from initial errors within "
                    f"{radius:.4g}, so the simulations are not compared with it"
                )
    elif simulate and spec.observer is None:
        notes.append("no simulations: the spec has no [observer] section")
    elif not simulate:
        notes.append("simulations skipped (--no-sim)")
    region_map = None
    family = design.observer_kind.region_family(design) if region and design is not None else None
    if family is not None:
        region_map = _region(family, notes, say, budget, region_time_limit(time_budget))
    return CertifyResult(
        spec=spec,
        certificate=cert,
        simulations=simulations,
        stealthy=stealthy,
        region=region_map,
        seed=base_seed,
        command=command or _command(spec, seed, simulate, overridden=overridden),
        notes=tuple(notes),
    )


def _stealthy_of(spec: Spec, cert: Certificate, seed: int) -> dict[str, Any] | None:
    """The stealthy attack's demonstration when sparse observability fails with a verified witness."""
    sparse = cert["sparse_observability"]
    witness = sparse.witness if sparse.verdict is Verdict.FAILS else None
    if witness is not None and witness.get("verified"):
        return _stealthy_demo(spec, witness, seed)
    return None


def _observer_design(
    spec: Spec, context: AnalysisContext, budget: Budget, tol: Tolerances, notes: list[str]
) -> Any | None:
    """The spec's observer (built once in ``context``), or None with a note saying why not."""
    if spec.observer is None:
        return None
    from .design.gains import GainError
    from .observers import build_observer

    observer = spec.observer
    try:
        return context.once(
            OBSERVER,
            lambda: build_observer(spec.system, observer, budget=budget, tolerances=tol),
        )
    except GainError as exc:
        notes.append(f"no simulation or region: the observer gain cannot be computed ({exc})")
    except ResourceLimitError as exc:
        notes.append(f"no simulation or region: the observer was not built ({exc})")
    return None


def _scenarios(
    spec: Spec, design: Any | None, stealthy: dict[str, Any] | None
) -> list[Mapping[str, Any]]:
    """The spec's scenarios, plus the stealthy attack when the plant has one and none replays it."""
    scenarios = list(spec.scenarios)
    if (
        design is not None
        and stealthy is not None
        and not any(sc["attack"] == "stealthy" for sc in scenarios)
    ):
        scenarios.append(
            {**SCENARIO_DEFAULTS, "name": "stealthy (automatic)", "attack": "stealthy"}
        )
    return scenarios


def _process_within(spec: Spec, scenario: Mapping[str, Any]) -> bool:
    """Whether the scenario's process noise is within the spec's (the same input matrix, each
    bound at most the spec's; none at all where the spec has none)."""
    omega = np.asarray(scenario.get("process") or [0.0], dtype=float)
    process = spec.noise.process if spec.noise is not None else None
    if process is None:
        return not np.any(omega > 0)
    G = np.asarray(scenario.get("process_input", process.input), dtype=float)
    return (
        G.shape == process.input.shape
        and bool(np.array_equal(G, process.input))
        and bool(np.all(omega <= process.omega))
    )


def _beside_noise_bound(
    spec: Spec, design: Any, check: Any, simulations: dict[str, Any]
) -> dict[str, Any]:
    """Each attack-free simulation whose noise is within the spec's bounds, beside the
    certified ultimate bound (``ScenarioResult.with_certified_bound``)."""
    bounds = spec.noise.eta if spec.noise is not None else None
    by_name = {sc["name"]: sc for sc in spec.scenarios}
    fading = initial_error_fading(design, check)
    out = dict(simulations)
    for name, res in simulations.items():
        scenario = by_name.get(name)
        if not isinstance(res, ScenarioResult) or res.attack != "none" or scenario is None:
            continue
        noise = np.broadcast_to(
            np.asarray(scenario.get("noise", 0.0), dtype=float), (spec.system.p,)
        )
        if bounds is None or np.any(noise > bounds):  # not the noise the bound is for
            continue
        if not _process_within(spec, scenario):
            continue
        out[name] = res.with_certified_bound(float(check.value), fading, "observer_noise_bound")
    return out


def _simulations(
    design: Any | None,
    scenarios: list[Mapping[str, Any]],
    say: Progress,
    *,
    runs: int | None,
    steps: int | None,
    seed: int | None,
    max_attacked: int,
    client: Any | None,
    budget: Budget,
    context: AnalysisContext,
) -> dict[str, Any]:
    """Scenario name -> its ``ScenarioResult``, or ``{"skipped": reason}``; none without a design."""
    from .simulation.engine import simulate_scenario

    simulations: dict[str, Any] = {}
    if design is None:
        return simulations
    for scenario in scenarios:
        say(f"simulating scenario {scenario['name']}")
        try:
            simulations[scenario["name"]] = simulate_scenario(
                design,
                scenario,
                runs=runs,
                steps=steps,
                seed=seed,
                max_attacked=max_attacked,
                client=client,
                budget=budget,
                context=context,
            )
        except ValueError as exc:  # no stealthy attack to replay, or over the budget
            simulations[scenario["name"]] = {"skipped": str(exc)}
    return simulations


def region_time_limit(time_budget: float | None) -> float | None:
    """Seconds after which the certified region's map starts no grid point: the time budget,
    at least ``REGION_SECONDS`` (a map is a few seconds on the examples; a D-SSO whose
    points need Zames-Falb multipliers took minutes), none without a budget."""
    return None if time_budget is None else max(float(time_budget), REGION_SECONDS)


REGION_SECONDS = 30.0


def _region(
    design: Any, notes: list[str], say: Progress, budget: Budget, time_limit: float | None = None
) -> Any | None:
    """The certified (shrink, step) map of ``design``, its kind's region family."""
    from .stability.region import region_map

    m = design.sensing.shape[0]
    n = design.system.n
    if n + 2 * m > REGION_LIMIT:
        notes.append(
            f"certified region not mapped: the LMI has {n + 2 * m} rows "
            f"(the report maps up to {REGION_LIMIT}; use ssecert.stability.lmi."
            f"region_map for larger plants)"
        )
        return None
    say("mapping the certified (shrink, step) region")
    shrinks, steps = _region_grid(design)
    refusal = _region_refusal(design, shrinks, steps, budget)
    if refusal is not None:
        notes.append(f"certified region not mapped: {refusal}")
        return None
    found = region_map(design, shrinks, steps, budget=budget, time_limit=time_limit)
    if found.not_reached:
        notes.append(
            f"certified region map stopped at its time limit of {time_limit:g} s: "
            f"{found.not_reached} of {found.verdicts.size} grid points not reached "
            "(inconclusive); --time-budget raises the limit"
        )
    return found


def _region_grid(design: Any) -> tuple[np.ndarray, np.ndarray]:
    """The (shrinks, steps) of the certified region map around ``design``'s own."""
    step = float(design.step)
    steps = np.unique(np.round(step * np.geomspace(0.1, 2.0, 6), 12))
    shrinks = np.array([0.2, 0.4, 0.6, 0.8, 0.9, 1.0])
    if not np.any(np.isclose(shrinks, design.shrink)):
        shrinks = np.sort(np.append(shrinks, design.shrink))
    if not np.any(np.isclose(steps, step)):
        steps = np.sort(np.append(steps, step))
    return shrinks, steps


def _region_refusal(
    design: Any, shrinks: np.ndarray, steps: np.ndarray, budget: Budget
) -> Refusal | None:
    """Why ``budget`` refuses the region map over ``shrinks`` x ``steps`` (None when it fits):
    every grid point may need a block-diagonal and a cross-term solve."""
    from .stability.lmi import lmi_cost

    n, m = design.system.n, design.sensing.shape[0]
    model = design.observer_kind.lure_model(design)
    costs = [lmi_cost(model, "circle", st) for st in ("block-diagonal", "cross")]
    return budget.check(
        f"the {shrinks.size} x {steps.size} region map ({n + 2 * m} LMI rows per point)",
        nbytes=max(c[0] for c in costs),
        flops=shrinks.size * steps.size * sum(c[1] for c in costs),
    )


def _command(spec: Spec, seed: int | None, simulate: bool, *, overridden: bool = False) -> str:
    """The command that reproduces the report: ``ssecert certify`` of the spec's file, or, for
    a design made or changed in Python (``overridden``), of the file ``Spec.to_toml`` writes."""
    from .examples import example_path, list_examples

    target = spec.source
    for name in list_examples():
        if str(example_path(name)) == spec.source:
            target = name
    # ("<python>", "<dict>": a design made in Python; a file's changed by keywords)
    made = overridden or target.startswith("<")
    if made:
        target = f"{spec.name}.toml"
    parts = ["ssecert", "certify", target]
    if seed is not None:
        parts += ["--seed", str(seed)]
    if not simulate:
        parts.append("--no-sim")
    command = " ".join(shlex.quote(p) for p in parts)
    if made:
        command += (
            f"  # the design was made or changed in Python: write {target} first, "
            f"open({target!r}, 'w').write(result.spec.to_toml()), result what certify returned"
        )
    return command


# notebooks show a certify result as its report
CertifyResult._repr_html_ = html_display("render_fragment")  # type: ignore[attr-defined]
