"""Attack scenarios, Monte Carlo simulation and metrics."""

from .engine import (
    CHUNK_RUNS,
    GridResult,
    ScenarioResult,
    grid_search,
    simulate_scenario,
    simulate_spec,
    stealthy_replay,
)
from .metrics import (
    absolute_error,
    detection_delay,
    initial_relative_error,
    mse,
    relative_error,
    summarize,
    support_error,
)
from .scenarios import ScenarioData, StealthyReplay, generate, run_rng

__all__ = [
    "CHUNK_RUNS",
    "GridResult",
    "ScenarioResult",
    "grid_search",
    "simulate_scenario",
    "simulate_spec",
    "stealthy_replay",
    "absolute_error",
    "detection_delay",
    "initial_relative_error",
    "mse",
    "relative_error",
    "summarize",
    "support_error",
    "ScenarioData",
    "StealthyReplay",
    "generate",
    "run_rng",
]
