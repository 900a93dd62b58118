"""The thesis's simulations (Ch. 6): Figs. 6.1-6.7."""

from __future__ import annotations

from ._registry import not_run

__all__: list[str] = []

_SCRIPT = (
    "benchmarks/exp_thesis_observers.py runs the D-SSO against the elastic-net observer on the "
    "packaged random-n15-p30 plant with the thesis's grid search (python "
    "benchmarks/exp_thesis_observers.py); it is not an experiment of ssecert reproduce yet"
)

not_run(
    "thesis.fig6_1",
    where="Sec. 6.1, Fig. 6.1 (D-SSO, marginally stable plant)",
    measures="MASE and MSE of the D-SSO against time",
    why=_SCRIPT,
)
for _n, _case in (
    (2, "no attack"),
    (3, "a constant attack"),
    (4, "an attack whose support switches every 400 steps"),
    (5, "a sinusoidal attack"),
):
    not_run(
        f"thesis.fig6_{_n}",
        where=f"Sec. 6.2, Fig. 6.{_n} ({_case})",
        measures=f"MASE and MSE of the D-SSO and the elastic-net observer under {_case}",
        why=_SCRIPT,
    )
not_run(
    "thesis.fig6_6",
    where="Sec. 6.3, Fig. 6.6 (RSS localization, 100 cells, 20 sensors)",
    measures="the target's cell and the attacked sensors found by the elastic net",
    why="benchmarks/exp_localization.py runs it over many deployments (the thesis gives no "
    "path-loss parameters or positions); it is not an experiment of ssecert reproduce yet",
)
not_run(
    "thesis.fig6_7",
    where="Sec. 6.4, Fig. 6.7 (the UGV)",
    measures="MASE and MSE of the D-SSO and the elastic-net observer on the UGV",
    why="the packaged ugv example and `ssecert simulate` run the UGV's observer; the D-SSO "
    "comparison of Fig. 6.7 is not an experiment of ssecert reproduce yet",
)
