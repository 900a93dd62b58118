"""Plots for the HTML report, rendered by matplotlib to inline SVG.

No pyplot global state is used (figures are built with ``matplotlib.figure``),
text stays text (``svg.fonttype = "none"``) so a browser can search it, and
the artists a reader looks for carry stable SVG ids (``gid``).
"""

from __future__ import annotations

import io
import re
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = [
    "svg_figure",
    "simulation_plot",
    "stealthy_plot",
    "region_plot",
    "sensor_plot",
    "tradeoff_plot",
    "hardening_plot",
]

PALETTE = {
    "holds": "#1b7f3b",
    "fails": "#b3261e",
    "inconclusive": "#a36b00",
    "a": "#1f5fa8",
    "b": "#c2410c",
    "output": "#333333",
    "band": "#9ec5ee",
}


def plain(text: str, limit: int = 40) -> str:
    """User text (sensor and scenario names) as matplotlib shows it: literally.

    Matplotlib reads text between two ``$`` as mathematics, and a name such
    as ``$\\frac{$`` would make it raise; long names are shortened (the full
    names are in the report's tables).
    """
    if len(text) > limit:
        text = text[: limit - 1] + "\u2026"
    return text.replace("$", r"\$")


def svg_figure(fig: Any, *, title: str = "") -> str:
    """The SVG text of a matplotlib Figure, ready to inline in HTML.

    The ids matplotlib gives clip paths come from ``svg.hashsalt``, random by
    default; a salt from the title makes the same figure give the same SVG.
    """
    import matplotlib

    buf = io.StringIO()
    with (
        matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": f"ssecert {title}"}),
        warnings.catch_warnings(),
    ):
        # text stays text in the SVG and the browser draws it with its own fonts
        warnings.filterwarnings("ignore", message="Glyph .* missing from font")
        fig.savefig(buf, format="svg", bbox_inches="tight")
    text = buf.getvalue()
    text = re.sub(r"<\?xml[^>]*\?>\s*", "", text)
    text = re.sub(r"<!DOCTYPE[^>]*>\s*", "", text)
    text = re.sub(r"<metadata>.*?</metadata>\s*", "", text, flags=re.S)  # RDF, creation date
    if title:
        label = title.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")
        text = text.replace("<svg ", f'<svg role="img" aria-label="{label}" ', 1)
    return text


def _figure(width: float, height: float, rows: int = 1, cols: int = 1) -> tuple[Any, Any]:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False)
    return fig, axes


def simulation_plot(name: str, result: Any, *, gid: str) -> str:
    """The estimation error over time, relative to its initial value (what is left of it,
    meaningful whether the state decays or grows) and relative to the present state, and
    the support error: Monte Carlo mean and 10-90% band."""
    from ..simulation.metrics import nanquantile

    has_support = result.support_error is not None
    panels = []
    if getattr(result, "initial_relative_error", None) is not None:
        panels.append(("error / initial error", "initial", result.initial_relative_error, True))
    panels.append(("error / state, ||x_hat - x|| / ||x||", "error", result.relative_error, True))
    if has_support:
        panels.append(("support error (Jaccard)", "support", result.support_error, False))
    fig, axes = _figure(2.6 * len(panels) + 0.4, 2.8, 1, len(panels))
    k = np.arange(result.relative_error.shape[0])
    for ax, (label, key, data, log) in zip(axes[0], panels):
        with warnings.catch_warnings(), np.errstate(invalid="ignore", over="ignore"):
            # steps where every run diverged: NaN, drawn as a gap; runs at inf (a noise of 1e200)
            # make the quantiles' interpolation inf - inf
            warnings.filterwarnings("ignore", "Mean of empty slice", RuntimeWarning)
            warnings.filterwarnings("ignore", "All-NaN slice encountered", RuntimeWarning)
            mean = np.nanmean(data, axis=1)
            lo, hi = nanquantile(data, 0.1, axis=1), nanquantile(data, 0.9, axis=1)
        if log:
            floor = 1e-17
            mean, lo, hi = (np.maximum(v, floor) for v in (mean, lo, hi))
            ax.set_yscale("log")
        band = ax.fill_between(
            k, lo, hi, color=PALETTE["band"], alpha=0.6, linewidth=0, label="10-90% of runs"
        )
        band.set_gid(f"{gid}-{key}-band")
        (line,) = ax.plot(k, mean, color=PALETTE["a"], linewidth=1.5, label="mean")
        line.set_gid(f"{gid}-{key}-mean")
        ax.set_xlabel("step k")
        ax.set_title(label, fontsize=10)
        ax.grid(True, alpha=0.3)
    axes[0][0].legend(fontsize=8, loc="best")
    fig.suptitle(f"{plain(name)}: {result.runs} runs, {result.attack} attack", fontsize=10)
    return svg_figure(fig, title=f"simulation {name}")


def tradeoff_plot(tradeoff: dict[str, Any], *, gid: str = "tradeoff") -> str:
    """The certified trade-off of ``ssecert design``: certified l2 gain from attack to error
    against the certified error contraction per step, the plant's own rho(A) (and rho(A)^2,
    "clearly faster"), the chosen design and the spec's design (at its linear loop's
    spectral radius: it has no decay certificate); where the front's points have a certified
    ultimate error bound under noise, a second panel with that bound on the same axis."""
    front = tradeoff.get("front", [])
    # (a noise of 0 bounds the error by 0: nothing to plot on a log axis)
    noisy = [p for p in front if p.get("verified") and (p.get("noise_bound") or 0) > 0]
    fig, axes = _figure(8.0, 5.6 if noisy else 3.2, 2 if noisy else 1, 1)
    chosen, spec = tradeoff.get("chosen") or {}, tradeoff.get("spec") or {}
    gains = [p for p in front if p.get("verified") and p.get("gamma") is not None]
    _front_panel(
        axes[0][0], gains, "gamma", chosen, spec, gid,
        front_label="certified trade-off (synthesis)", chosen_label="chosen design",
        color=PALETTE["a"], ylabel="certified l2 gain, attack to error",
        plant=tradeoff.get("plant_radius"),
    )  # fmt: skip
    if not noisy:
        return svg_figure(fig, title="certified trade-off between decay and gain")
    axes[1][0].sharex(axes[0][0])
    _front_panel(
        axes[1][0], noisy, "noise_bound", chosen, spec, f"{gid}-noise",
        front_label="certified ultimate error under noise (front)",
        chosen_label="chosen design (its certificate)", color=PALETTE["b"],
        ylabel="certified ultimate error bound under noise",
    )  # fmt: skip
    return svg_figure(fig, title="certified trade-off between decay, gain and noise")


def _front_panel(
    ax: Any,
    points: list[dict[str, Any]],
    key: str,
    chosen: dict[str, Any],
    spec: dict[str, Any],
    gid: str,
    *,
    front_label: str,
    chosen_label: str,
    color: str,
    ylabel: str,
    plant: float | None = None,
) -> None:
    """One panel of ``tradeoff_plot``: ``key`` of the front's points, the chosen design's and
    the spec's design's against the contraction (and the plant's own rho(A) where given)."""
    if points:
        (line,) = ax.plot(
            [p["contraction"] for p in points], [p[key] for p in points], "o-", color=color,
            linewidth=1.2, markersize=4, label=front_label,
        )  # fmt: skip
        line.set_gid(f"{gid}-front")
    if plant is not None and plant < 1.5:
        ax.axvline(plant, color=PALETTE["output"], linestyle="--", linewidth=1,
                   label=f"plant's own, rho(A) = {plant:.3g}").set_gid(f"{gid}-plant")  # fmt: skip
        if plant < 1:
            ax.axvline(plant**2, color=PALETTE["output"], linestyle=":", linewidth=1,
                       label=f"twice as fast, rho(A)^2 = {plant**2:.3g}")  # fmt: skip
    if chosen.get("contraction") is not None and chosen.get(key) is not None:
        (mark,) = ax.plot(
            [chosen["contraction"]], [chosen[key]], "*", color=PALETTE["holds"],
            markersize=12, label=chosen_label,
        )  # fmt: skip
        mark.set_gid(f"{gid}-chosen")
    if spec.get("linear_radius") is not None and spec.get(key) is not None:
        (mark,) = ax.plot(
            [spec["linear_radius"]], [spec[key]], "D", color=PALETTE["b"],
            markerfacecolor="none", label="the spec's design (x: rho(A - L S))",
        )  # fmt: skip
        mark.set_gid(f"{gid}-spec")
    ax.set_yscale("log")
    ax.set_xlabel("error contraction per step, sqrt(1 - alpha) (smaller is faster)")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0)


def stealthy_plot(system: Any, demo: dict[str, Any], *, gid: str = "stealthy") -> str:
    """Two state trajectories (from x0 and x0 + z) that give one and the same output."""
    xa, xb, y = demo["states_a"], demo["states_b"], demo["outputs"]
    k = np.arange(xa.shape[0])
    comp = int(demo["component"])
    sensor = int(demo["sensor"])
    fig, axes = _figure(7.5, 2.8, 1, 2)
    ax = axes[0][0]
    (la,) = ax.plot(
        k, xa[:, comp], color=PALETTE["a"], linewidth=1.8, label="plant from x0, attacked"
    )
    (lb,) = ax.plot(
        k, xb[:, comp], color=PALETTE["b"], linewidth=1.8, linestyle="--", label="plant from x0 + z"
    )
    la.set_gid(f"{gid}-trajectory-a")
    lb.set_gid(f"{gid}-trajectory-b")
    ax.set_title(f"two state trajectories (state {comp + 1})", fontsize=10)
    ax.set_xlabel("step k")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    ax = axes[0][1]
    (lo,) = ax.plot(
        k,
        y[:, sensor],
        color=PALETTE["output"],
        linewidth=1.8,
        label=f"output of {plain(system.sensors[sensor])} (both plants)",
    )
    lo.set_gid(f"{gid}-output")
    ax.set_title("one output: the sensors cannot tell them apart", fontsize=10)
    ax.set_xlabel("step k")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return svg_figure(fig, title="stealthy attack")


def region_plot(region: Any, design_point: tuple[float, float] | None = None) -> str:
    """Certified region over (shrink, step): verdict of the circle criterion per grid point."""
    fig, axes = _figure(5.0, 3.6)
    ax = axes[0][0]
    codes = {"holds": 2, "inconclusive": 1, "fails": 0}
    grid = np.vectorize(lambda v: codes.get(v, 1))(region.verdicts).astype(float)
    from matplotlib.colors import ListedColormap

    cmap = ListedColormap([PALETTE["fails"], PALETTE["inconclusive"], PALETTE["holds"]])
    mesh = ax.pcolormesh(
        np.arange(region.steps.size + 1),
        np.arange(region.shrinks.size + 1),
        grid,
        cmap=cmap,
        vmin=0,
        vmax=2,
        edgecolors="white",
        linewidth=0.5,
    )
    mesh.set_gid("region-map")
    ax.set_xticks(np.arange(region.steps.size) + 0.5)
    ax.set_xticklabels([f"{s:.3g}" for s in region.steps], rotation=45, fontsize=7)
    ax.set_yticks(np.arange(region.shrinks.size) + 0.5)
    ax.set_yticklabels([f"{q:.3g}" for q in region.shrinks], fontsize=7)
    ax.set_xlabel("step")
    ax.set_ylabel("shrink q")
    short = {
        "local instability": "loc",
        "divergent trajectory": "div",
        "nonzero equilibrium": "eq",
        "periodic orbit": "per",
    }
    for i, j in getattr(region, "zames_falb", {}):
        ax.text(j + 0.5, i + 0.5, "zf", ha="center", va="center", fontsize=7, color="white")
    for (i, j), kind in getattr(region, "witnesses", {}).items():
        ax.text(j + 0.5, i + 0.5, short.get(kind, "x"), ha="center", va="center", fontsize=7,
                color="white")  # fmt: skip
    radii = getattr(region, "radii", None)
    if radii is not None:
        for i, j in zip(*np.nonzero(np.isfinite(radii) & (radii > 0))):
            ax.text(j + 0.5, i + 0.5, f"{radii[i, j]:.2g}", ha="center", va="center", fontsize=6)
    if design_point is not None:
        q, nu = design_point
        i = int(np.argmin(np.abs(region.shrinks - q)))
        j = int(np.argmin(np.abs(region.steps - nu)))
        (mark,) = ax.plot(
            [j + 0.5],
            [i + 0.5],
            marker="*",
            markersize=14,
            color="white",
            markeredgecolor="black",
            linestyle="none",
            label="this design",
        )
        mark.set_gid("region-design")
        ax.legend(fontsize=8, loc="upper right")
    ax.set_title(
        "green: certified (circle criterion; zf: Zames-Falb multiplier); amber: radius of\n"
        "initial errors certified; red: fails (loc: dead zone unstable, div: divergent\n"
        "trajectory, eq: equilibrium, per: periodic orbit)",
        fontsize=7,
    )
    return svg_figure(fig, title="certified region")


def hardening_plot(scale: Sequence[float], bound: Sequence[float], lower: float, names: str) -> str:
    """The decoder's certified error bound against the noise of its worst sensor set (a fraction
    of the spec's bounds), with the lower bound no decoder beats at the spec's noise."""
    fig, axes = _figure(5.6, 2.6)
    ax = axes[0, 0]
    ax.plot(scale, bound, marker="o", color=PALETTE["a"], gid="hardening-bound",
            label="certified bound of ||x_hat - x||")  # fmt: skip
    if lower > 0:
        ax.axhline(lower, color=PALETTE["inconclusive"], linestyle="--", gid="hardening-lower",
                   label="no decoder does better (spec's noise)")  # fmt: skip
    ax.set_xlabel(plain(f"noise of sensors {names}, fraction of the spec's", 80))
    ax.set_ylabel("error bound")
    ax.set_ylim(bottom=0)
    ax.legend(loc="upper left", fontsize=8, frameon=False)
    return svg_figure(fig, title="hardening")


def sensor_plot(sensors: Sequence[str], breaking: Sequence[int]) -> str:
    """The sensors as a row of boxes, the breaking set highlighted."""
    fig, axes = _figure(max(3.0, 0.9 * len(sensors)), 1.1)
    ax = axes[0][0]
    broken = set(breaking)
    for i, name in enumerate(sensors):
        color = PALETTE["fails"] if i in broken else "#d9e7d9"
        box = ax.add_patch(
            __import__("matplotlib.patches", fromlist=["FancyBboxPatch"]).FancyBboxPatch(
                (i + 0.05, 0.1),
                0.9,
                0.8,
                boxstyle="round,pad=0.02",
                facecolor=color,
                edgecolor="#444",
            )
        )
        box.set_gid(f"sensor-{i}{'-breaking' if i in broken else ''}")
        ax.text(
            i + 0.5,
            0.5,
            plain(name, 14),
            ha="center",
            va="center",
            fontsize=8,
            color="white" if i in broken else "black",
        )
    ax.set_xlim(0, len(sensors))
    ax.set_ylim(0, 1)
    ax.axis("off")
    return svg_figure(fig, title="sensors and breaking set")
