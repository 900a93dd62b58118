"""The Lasso paper's experiments (Sec. 5): Figs. 1-4."""

from __future__ import annotations

from ._registry import not_run

__all__: list[str] = []

_STATIC = "the paper's baselines ETPG and Imhotep-SMT are not in ssecert yet"
_DYNAMIC = "the paper's baseline ETPL is not in ssecert yet"

not_run(
    "lasso.fig1",
    where="Sec. 5.1, Fig. 1 (n = 20, s = p/5, tau = n, noise-free and ||eta||_inf <= 1e-4)",
    measures="relative state error and run time of Lasso, ETPG and Imhotep-SMT against p",
    why=f"{_STATIC}; benchmarks/exp_lasso_sec51.py measures Lasso, the l1 decoder and an "
    "exhaustive l0 decoder in this setting (python benchmarks/exp_lasso_sec51.py)",
)
not_run(
    "lasso.fig2",
    where="Sec. 5.1, Fig. 2 (n = 20, p = 30, s varying, noise-free and ||eta||_inf <= 1e-4)",
    measures="relative state error and run time of Lasso, ETPG and Imhotep-SMT against s",
    why=f"{_STATIC}, and no script runs the varying-s setting yet",
)
not_run(
    "lasso.fig3",
    where="Sec. 5.2, Fig. 3 (the SSO with tau = n; n = 10, p = 15, s = 3)",
    measures="relative state error and support error of the sparse soft observer and ETPL "
    "against time (100 runs, 300 steps)",
    why=f"{_DYNAMIC}; benchmarks/exp_sso_sec52.py runs the SSO alone in this setting "
    "(python benchmarks/exp_sso_sec52.py)",
)
not_run(
    "lasso.fig4",
    where="Sec. 5.2, Fig. 4 (the SSO with tau = 1)",
    measures="relative state error and support error of the online sparse soft observer and "
    "ETPL against time, and their run times per step (7e-5 s and 4e-6 s in the paper)",
    why=f"{_DYNAMIC}; benchmarks/exp_sso_sec52.py runs the SSO alone in this setting",
)
