"""Running the experiments and writing ``reproduce.json`` and ``reproduce.html``."""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..base.format import readable
from ..results import to_jsonable
from ._registry import DOCUMENTS, Experiment, Result, Settings, all_experiments, get_experiment
from .agreement import Agreement, Match, agreement

__all__ = ["Outcome", "agreement_table", "run_experiments", "reproduce_json", "render_reproduce"]


@dataclass(frozen=True)
class Outcome:
    """An experiment's run: its result (None when not run) and the agreement line."""

    experiment: Experiment
    result: Result | None
    agreement: Agreement
    seconds: float
    settings: Settings

    @property
    def command(self) -> str:
        s = self.settings
        runs = f" --runs {s.runs}" if s.runs is not None else ""
        seed = f" --seed {s.seed}" if s.seed else ""
        return f"{self.experiment.command}{runs}{seed}"

    def to_dict(self) -> dict[str, Any]:
        e, r = self.experiment, self.result
        return {
            "document": DOCUMENTS[e.document],
            "where": e.where,
            "measures": e.measures,
            "paper": dict(r.paper) if r is not None else {},
            "ours": dict(r.ours) if r is not None else {},
            "agreement": self.agreement.words,
            "match": self.agreement.match.value,
            "unstated": dict(r.unstated) if r is not None else {},
            "table": to_jsonable(r.table) if r is not None else [],
            "note": (r.note if r is not None else e.why_not),
            "why": r.why if r is not None else "",
            "figure": to_jsonable(dict(r.figure)) if r is not None and r.figure else None,
            "command": self.command,
            "seconds": round(self.seconds, 3),
        }


def run_experiments(
    ids: Sequence[str] | None = None,
    settings: Settings | None = None,
    progress: Callable[[str], None] | None = None,
) -> list[Outcome]:
    """Run the experiments named (all by default), in the registry's order."""
    settings = settings or Settings()
    chosen = list(all_experiments().values()) if not ids else [get_experiment(i) for i in ids]
    out = []
    for entry in chosen:
        if progress is not None:
            progress(entry.id)
        began = time.monotonic()
        if entry.run is None:
            result = None
            line = Agreement(Match.NOT_RUN, f"not run: {entry.why_not}")
        else:
            result = entry.run(settings)
            line = agreement(result.paper, result.ours, rtol=entry.rtol, close=entry.close)
        out.append(Outcome(entry, result, line, time.monotonic() - began, settings))
    return out


def reproduce_json(outcomes: Sequence[Outcome]) -> str:
    """``{"experiments": {ID: {...}}}`` as JSON text."""
    data = {"experiments": {o.experiment.id: o.to_dict() for o in outcomes}}
    return json.dumps(to_jsonable(data), indent=2, allow_nan=False) + "\n"


_TEMPLATE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>ssecert reproduce</title>
<style>
body{font-family:system-ui,sans-serif;max-width:70em;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:.2em .6em;
text-align:left}.reproduced{color:#176b2c}.close{color:#8a6d00}.differs{color:#a11}
.not-comparable{color:#555}section{border-top:1px solid #ddd;margin-top:1.5em}
code{background:#f4f4f4;padding:0 .2em}
</style></head><body>
<h1>The documents' experiments, reproduced</h1>
<p>{{ summary }}</p>
<table><tr><th>experiment</th><th>agreement</th></tr>
{% for o in outcomes %}<tr><td><a href="#{{ o.id }}">{{ o.id }}</a></td>
<td class="{{ o.match|replace(' ', '-') }}">{{ o.match }}</td></tr>
{% endfor %}</table>
{% for o in outcomes %}<section id="{{ o.id }}">
<h2>{{ o.id }}: {{ o.where }}</h2>
<p>{{ o.document }}. Measures {{ o.measures }}.</p>
<p class="{{ o.match|replace(' ', '-') }}"><strong>{{ o.agreement }}</strong></p>
{% if o.rows %}<table><tr><th></th><th>document</th><th>ssecert</th></tr>
{% for key, paper, ours in o.rows %}<tr><td>{{ key }}</td><td>{{ paper }}</td><td>{{ ours }}</td></tr>
{% endfor %}</table>{% endif %}
{% if o.unstated %}<p>Left unstated by the document, and chosen here:</p><ul>
{% for key, value in o.unstated %}<li>{{ key }}: {{ value }}</li>{% endfor %}</ul>{% endif %}
{% if o.svg %}<figure>{{ o.svg|safe }}</figure>{% endif %}
{% if o.why %}<p><strong>Why:</strong> {{ o.why }}</p>{% endif %}
{% if o.note %}<p>{{ o.note }}</p>{% endif %}
<p><code>{{ o.command }}</code> ({{ o.seconds }} s)</p>
</section>{% endfor %}
</body></html>
"""


def _shown(value: object) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return readable(value)
    return str(value)


def render_reproduce(outcomes: Sequence[Outcome]) -> str:
    """The single-file HTML report: a section per experiment."""
    import jinja2

    counts: dict[str, int] = {}
    for o in outcomes:
        counts[o.agreement.match.value] = counts.get(o.agreement.match.value, 0) + 1
    summary = f"{len(outcomes)} experiments: " + ", ".join(
        f"{counts[m.value]} {m.value}" for m in Match if m.value in counts
    )
    rows = []
    for o in outcomes:
        d = o.to_dict()
        keys = list(dict.fromkeys([*d["paper"], *d["ours"]]))
        rows.append(
            {
                **d,
                "id": o.experiment.id,
                "rows": [(k, _shown(d["paper"].get(k)), _shown(d["ours"].get(k))) for k in keys],
                "unstated": list(d["unstated"].items()),
                "svg": _plot(o) if o.result is not None and o.result.figure else "",
            }
        )
    env = jinja2.Environment(autoescape=True)
    return env.from_string(_TEMPLATE).render(outcomes=rows, summary=summary)


def agreement_table(report: Mapping[str, Any]) -> str:
    """A Markdown table of the agreement per document, written from ``reproduce.json``'s data:
    for each document, how many experiments each agreement word got, and those not reproduced
    with their line."""
    experiments = report["experiments"]
    lines = [
        "| document | experiments | reproduced | close | differs | not comparable | not run |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    details = []
    for prefix in DOCUMENTS:
        mine = {k: v for k, v in experiments.items() if k.split(".", 1)[0] == prefix}
        if not mine:
            continue
        count = {m.value: sum(v["match"] == m.value for v in mine.values()) for m in Match}
        lines.append(
            f"| {prefix} | {len(mine)} | " + " | ".join(str(count[m.value]) for m in Match) + " |"
        )
        for key, entry in mine.items():
            if entry["match"] in (Match.DIFFERS.value, Match.CLOSE.value):
                why = f" Why: {entry['why']}" if entry.get("why") else ""
                details.append(f"- `{key}`: {entry['agreement']}.{why}")
    return "\n".join(lines + ([""] + details if details else [])) + "\n"


def _plot(outcome: Outcome) -> str:
    """The outcome's figure as inline SVG (``ssecert.report.plots``)."""
    from matplotlib.figure import Figure

    from ..report.plots import PALETTE, plain, svg_figure

    assert outcome.result is not None and outcome.result.figure is not None
    spec = outcome.result.figure
    fig = Figure(figsize=(5.6, 3.2), layout="constrained")
    ax = fig.subplots()
    colours = [PALETTE["a"], PALETTE["b"], "#7570b3", "#1b9e77", "#e7298a",
               "#66a61e", "#a6761d", "#666666"]  # fmt: skip
    for i, (label, line) in enumerate(spec["lines"].items()):
        xs, ys = np.asarray(line["x"], dtype=float), np.asarray(line["y"], dtype=float)
        if spec.get("log"):
            ys = np.where(ys > 0, ys, np.nan)  # a zero has no place on a log axis: a gap
        dashed = "noise" in label and "noise-free" not in label
        marker = "o" if xs.size <= 30 else None  # a point per value where there are few
        ax.plot(xs, ys, color=colours[i % len(colours)], linewidth=1.4, marker=marker,
                markersize=3, linestyle="--" if dashed else "-", label=plain(label, 60))  # fmt: skip
    if spec.get("log"):
        ax.set_yscale("log")
    ax.set_xlabel(plain(spec["x"], 60))
    ax.set_ylabel(plain(spec["y"], 60))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    fig.suptitle(plain(f"{outcome.experiment.id}: {spec['title']}", 90), fontsize=10)
    return svg_figure(fig, title=outcome.experiment.id)
