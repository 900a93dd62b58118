"""The documents' experiments, beside the documents' numbers (``ssecert reproduce``).

Every table, figure and worked example of the five documents has an
identifier, ``DOCUMENT.figN``, ``DOCUMENT.tableN`` or ``DOCUMENT.exampleN``
(``lasso``, ``thesis``, ``notes``, ``pruning``, ``sise``), registered by the
module of its document with where it is and what it measures.  A registered
function runs it (``Settings``: quick or the document's run counts, and a
seed) and returns the document's numbers and ours under the same keys
(``Result``); the agreement line is computed from them (``agreement``).  An
experiment ``ssecert reproduce`` cannot run says why in its entry.

Examples
--------
>>> from ssecert.experiments import run_experiments
>>> [outcome] = run_experiments(["notes.example2"])
>>> outcome.agreement.words
'reproduced: 3 values, each the same'
"""

from . import lasso, notes, pruning, sise, thesis  # noqa: F401  (each registers its experiments)
from ._registry import (
    DOCUMENTS,
    Experiment,
    Result,
    Settings,
    all_experiments,
    experiment,
    figure,
    get_experiment,
    not_run,
)
from .agreement import Agreement, Match, agreement
from .run import Outcome, agreement_table, render_reproduce, reproduce_json, run_experiments

__all__ = [
    "DOCUMENTS",
    "Agreement",
    "Experiment",
    "Match",
    "Outcome",
    "Result",
    "Settings",
    "agreement",
    "agreement_table",
    "all_experiments",
    "experiment",
    "figure",
    "get_experiment",
    "not_run",
    "render_reproduce",
    "reproduce_json",
    "run_experiments",
]
