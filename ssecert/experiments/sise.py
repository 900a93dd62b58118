"""The SISE paper's experiments (Sec. IV): Figs. 1-4."""

from __future__ import annotations

from ._registry import not_run

__all__: list[str] = []

_SCRIPT = (
    "benchmarks/exp_sise.py runs it with ssecert's SISE (python benchmarks/exp_sise.py); it is "
    "not an experiment of ssecert reproduce yet"
)
for _n, _setting in ((1, "p = 40, m = 20, n = 50"), (2, "p = 40, m = 30, n = 50"),
                     (3, "p = 40, m = 20, n = 70")):  # fmt: skip
    not_run(
        f"sise.fig{_n}",
        where=f"Sec. IV, Fig. {_n} (Experiment {_n}: {_setting})",
        measures="state and input estimation error of SISE against the oracle benchmark",
        why=_SCRIPT,
    )
not_run(
    "sise.fig4",
    where="Sec. IV, Fig. 4 (Experiment 4: p = 40, m = 20, n = 50, against [14])",
    measures="estimation error of SISE and of the method of [14] against time, under noise",
    why=_SCRIPT,
)
