"""The registry of the documents' experiments (``ssecert reproduce``)."""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

__all__ = [
    "DOCUMENTS",
    "figure",
    "Experiment",
    "Result",
    "Settings",
    "all_experiments",
    "experiment",
    "get_experiment",
    "not_run",
]

#: the five documents, by the prefix of their experiments' identifiers
DOCUMENTS = {
    "lasso": "Cerone, Fosson, Regruto, Ripa, Lasso-based state estimation for cyber-physical "
    "systems under sensor attacks (IFAC SYSID 2024)",
    "thesis": "Cilia, Observer-based secure state estimation for multi-agent systems subjected "
    "to adversarial sensor attacks (MSc thesis, Politecnico di Torino)",
    "notes": "Migliaccio, Modeling and control of cyber-physical systems (lecture notes 2023/24)",
    "pruning": "Zheng, Anubi, Attack-resilient weighted l1 observer with prior pruning",
    "sise": "Fosson, Garin, Gracy, Kibangou, Swart, Input and state estimation exploiting "
    "input sparsity (ECC 2019)",
}

_ID = re.compile(r"^(lasso|thesis|notes|pruning|sise)\.(fig|table|example)[0-9][0-9_]*$")

Value = float | int | bool | None


@dataclass(frozen=True)
class Settings:
    """How to run an experiment: ``quick`` (a few runs each), ``runs`` (the document's count
    or the user's, overriding quick) and the ``seed`` every random draw starts from."""

    quick: bool = True
    runs: int | None = None
    seed: int = 0

    def count(self, quick: int, paper: int) -> int:
        """The runs to make: ``runs`` when given, else ``quick`` or the document's ``paper``."""
        if self.runs is not None:
            return self.runs
        return quick if self.quick else paper


@dataclass(frozen=True)
class Result:
    """What an experiment measured, beside what the document reports.

    Attributes
    ----------
    paper : mapping
        The document's numbers or claims (True: the document states it), by key.
    ours : mapping
        Ours under the same keys.
    unstated : mapping
        The settings the document leaves open, and the value chosen for each.
    table : list of dict
        Rows for the report (the document's layout), optional.
    note : str
        What else a reader needs (whose fault a difference is, as far as it can be shown).
    figure : mapping, optional
        The document's figure redrawn with its axes (``figure``): ``title``, ``x`` and ``y``
        (axis labels), ``log`` (a logarithmic y axis) and ``lines``, ``{label: {"x": [...],
        "y": [...]}}``.
    why : str
        Why ours differs, in a sentence computed from the numbers, as far as they show it
        (the README's table gives it beside the agreement line).
    """

    paper: Mapping[str, Value]
    ours: Mapping[str, Value]
    unstated: Mapping[str, str] = field(default_factory=dict)
    table: list[dict[str, Any]] = field(default_factory=list)
    note: str = ""
    figure: Mapping[str, Any] | None = None
    why: str = ""


@dataclass(frozen=True)
class Experiment:
    """One table, figure or worked example of a document.

    Attributes
    ----------
    id : str
        ``DOCUMENT.figN``, ``DOCUMENT.tableN`` or ``DOCUMENT.exampleN``.
    where : str
        Section and figure or table in the document.
    measures : str
        What it measures, in a sentence.
    run : callable or None
        ``run(settings) -> Result``; None when ``ssecert reproduce`` cannot run it.
    why_not : str
        Why it is not run (with ``run`` None).
    rtol : float
        Relative difference within which a number is reproduced.
    close : float
        Relative difference within which a number is close.
    """

    id: str
    where: str
    measures: str
    run: Callable[[Settings], Result] | None = None
    why_not: str = ""
    rtol: float = 0.05
    close: float = 0.5

    @property
    def document(self) -> str:
        return self.id.split(".", 1)[0]

    @property
    def command(self) -> str:
        return f"ssecert reproduce {self.id}"


_EXPERIMENTS: dict[str, Experiment] = {}


def _register(entry: Experiment) -> None:
    if not _ID.match(entry.id):
        raise ValueError(
            f"experiment id {entry.id!r}: expected DOCUMENT.figN, DOCUMENT.tableN or "
            f"DOCUMENT.exampleN with DOCUMENT one of {', '.join(DOCUMENTS)}"
        )
    if entry.id in _EXPERIMENTS:
        raise ValueError(f"experiment {entry.id!r} is registered twice")
    _EXPERIMENTS[entry.id] = entry


def experiment(
    id: str, *, where: str, measures: str, rtol: float = 0.05, close: float = 0.5
) -> Callable[[Callable[[Settings], Result]], Callable[[Settings], Result]]:
    """Register ``run(settings) -> Result`` as the experiment ``id``."""

    def wrap(run: Callable[[Settings], Result]) -> Callable[[Settings], Result]:
        _register(Experiment(id, where, measures, run, rtol=rtol, close=close))
        return run

    return wrap


def not_run(id: str, *, where: str, measures: str, why: str) -> None:
    """Register the experiment ``id`` as one ``ssecert reproduce`` does not run, and why."""
    _register(Experiment(id, where, measures, None, why_not=why))


def _order(key: str) -> tuple[int, list[Any]]:
    document, rest = key.split(".", 1)
    parts = [int(p) if p.isdigit() else p for p in re.split(r"(\d+)", rest) if p]
    return list(DOCUMENTS).index(document), parts


def all_experiments() -> dict[str, Experiment]:
    """Every registered experiment, by id, document by document."""
    return {k: _EXPERIMENTS[k] for k in sorted(_EXPERIMENTS, key=_order)}


def get_experiment(id: str) -> Experiment:
    """The experiment ``id``; ValueError naming the registered ones otherwise."""
    try:
        return _EXPERIMENTS[id]
    except KeyError:
        raise ValueError(
            f"no experiment {id!r}; registered: {', '.join(all_experiments())}"
        ) from None


def figure(
    title: str, x: str, y: str, lines: Mapping[str, tuple[Any, Any]], *, log: bool = False
) -> dict[str, Any]:
    """A figure of a ``Result``: ``lines`` maps each curve's label to its (x, y) values."""
    return {
        "title": title,
        "x": x,
        "y": y,
        "log": log,
        "lines": {
            label: {"x": [float(v) for v in xs], "y": [float(v) for v in ys]}
            for label, (xs, ys) in lines.items()
        },
    }
