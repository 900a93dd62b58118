"""The pruning paper's simulations (Sec. IV): Fig. 1, and Fig. 2 with Table I."""

from __future__ import annotations

from ._registry import not_run

__all__: list[str] = []

not_run(
    "pruning.fig1",
    where="Sec. IV-A, Fig. 1 (m = 20 sensors, n = 10 states)",
    measures="success rate of the l1 observer, the weighted one with the raw prior and with "
    "the pruned prior, against the attack percentage",
    why="benchmarks/exp_pruning.py runs it (python benchmarks/exp_pruning.py); it is not an "
    "experiment of ssecert reproduce yet",
)
_BUS = "ssecert has no IEEE 14-bus model yet"
not_run(
    "pruning.fig2",
    where="Sec. IV-B, Fig. 2 (IEEE 14-bus system, 30% of the meters attacked)",
    measures="the phase angles delta_1..delta_5 estimated without prior and with pruning",
    why=_BUS,
)
not_run(
    "pruning.table1",
    where="Sec. IV-B, Table I (IEEE 14-bus system)",
    measures="RMS and maximum absolute error of delta_1..delta_5 for LO, LIO and WLIP",
    why=_BUS,
)
