"""Claims, findings and the registry of the audit.

A claim is a statement of one of the reference documents, with where it is
and the check that decides it.  A check returns a ``Finding``: ``holds``
(with the evidence: a symbolic proof, an exhaustive enumeration, or
randomised instances and the property tested on each), ``fails`` (with a
minimal counterexample) or ``conditional`` (the statement holds under an
extra condition, which is stated, and fails without it: the counterexample
shows where).  A verdict is decided by the check, never by the document's
own argument: a claim whose proof has a gap but whose statement survives
every test holds.

A counterexample is a mapping from the document's own symbols (``A``,
``C``, ``L``, ``tau``, ``Q``, ...) to numbers and nested lists, so that it
can be re-checked without ssecert; ``ssecert audit --claim ID`` re-runs the
check that found it.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from ssecert.results import to_jsonable

__all__ = [
    "DOCUMENTS",
    "VERDICTS",
    "Claim",
    "Finding",
    "claim",
    "all_claims",
    "get_claim",
    "Outcome",
    "run_claim",
]

VERDICTS = ("holds", "fails", "conditional")

#: the reference documents, by the prefix of their claims' identifiers
DOCUMENTS = {
    "lasso": "000: Cerone, Fosson, Regruto, Ripa, Lasso-based state estimation for "
    "cyber-physical systems under sensor attacks (IFAC SYSID 2024)",
    "thesis": "001: Cilia, Observer-based secure state estimation for multi-agent systems "
    "subjected to adversarial sensor attacks (MSc thesis, Politecnico di Torino)",
    "notes": "002: Migliaccio, Modeling and control of cyber-physical systems (lecture notes "
    "2023/24)",
    "pruning": "003: Zheng, Anubi, Attack-resilient weighted l1 observer with prior pruning",
    "sise": "004: Fosson, Garin, Gracy, Kibangou, Swart, Input and state estimation exploiting "
    "input sparsity (ECC 2019)",
}


@dataclass(frozen=True)
class Finding:
    """What a check found.

    Attributes
    ----------
    verdict : {"holds", "fails", "conditional"}
    explanation : str
        What was found and why, for a reader of the document (a few sentences).
    evidence : mapping
        How it was decided: ``method`` (``"symbolic"``, ``"exhaustive"``,
        ``"randomised"``, ``"certificate"`` or a combination) and what anyone
        needs to re-check it (instances, seeds, margins, residuals).
    counterexample : mapping or None
        Required for ``fails`` and ``conditional``: the document's symbols to
        numbers and nested lists, plus ``"shows"``, what to compute on them.
    condition : str or None
        Required for ``conditional``: the extra condition under which the
        statement holds.
    """

    verdict: str
    explanation: str
    evidence: Mapping[str, Any] = field(default_factory=dict)
    counterexample: Mapping[str, Any] | None = None
    condition: str | None = None

    def __post_init__(self) -> None:
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict must be one of {VERDICTS}, got {self.verdict!r}")
        if not self.explanation.strip():
            raise ValueError("a finding needs an explanation")
        if "method" not in self.evidence:
            raise ValueError("the evidence must say its method ('symbolic', 'exhaustive', ...)")
        if self.verdict != "holds" and not self.counterexample:
            raise ValueError(f"a {self.verdict} finding needs a counterexample")
        if self.verdict == "conditional" and not self.condition:
            raise ValueError("a conditional finding needs its condition")
        if self.counterexample is not None:
            _check_numbers(self.counterexample, "counterexample")


def _check_numbers(value: Any, where: str) -> None:
    """The counterexample must be plain, finite JSON (numbers, lists, strings)."""
    try:
        json.dumps(to_jsonable(value), allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where} is not plain JSON: {exc}") from exc


@dataclass(frozen=True)
class Claim:
    """A numbered claim of a document and the check that decides it."""

    id: str
    where: str
    statement: str
    recorded: str  # the verdict this version of the audit found; `pytest proofs_checks` pins it
    check: Callable[[], Finding]

    @property
    def document(self) -> str:
        return DOCUMENTS[self.id.split(".", 1)[0]]


_CLAIMS: dict[str, Claim] = {}


def claim(
    id: str, *, where: str, statement: str, recorded: str
) -> Callable[[Callable[[], Finding]], Callable[[], Finding]]:
    """Register the decorated function as the check of claim ``id``."""
    prefix = id.split(".", 1)[0]
    if prefix not in DOCUMENTS or "." not in id:
        raise ValueError(f"claim id must be <document>.<name> with a document in {list(DOCUMENTS)}")
    if recorded not in VERDICTS:
        raise ValueError(f"recorded must be one of {VERDICTS}, got {recorded!r}")

    def register(check: Callable[[], Finding]) -> Callable[[], Finding]:
        if id in _CLAIMS:
            raise ValueError(f"claim {id!r} is registered twice")
        _CLAIMS[id] = Claim(id, where, statement, recorded, check)
        return check

    return register


def _load() -> None:
    from . import lasso, notes, pruning, sise, thesis  # noqa: F401  (each registers its claims)


def all_claims() -> dict[str, Claim]:
    """Every registered claim, by document (000 to 004), each in the order it is registered."""
    _load()
    order = list(DOCUMENTS)
    ids = sorted(_CLAIMS, key=lambda i: order.index(i.split(".", 1)[0]))  # stable
    return {i: _CLAIMS[i] for i in ids}


def get_claim(claim_id: str) -> Claim:
    claims = all_claims()
    if claim_id not in claims:
        raise KeyError(f"no claim {claim_id!r}; the claims are: {', '.join(sorted(claims))}")
    return claims[claim_id]


@dataclass(frozen=True)
class Outcome:
    """A claim, what its check found, and how long it took."""

    claim: Claim
    finding: Finding
    seconds: float

    def to_dict(self) -> dict[str, Any]:
        """The claim's entry of audit.json."""
        evidence = dict(to_jsonable(self.finding.evidence))
        evidence["explanation"] = self.finding.explanation
        if self.finding.condition:
            evidence["condition"] = self.finding.condition
        if self.finding.counterexample is not None:
            evidence["counterexample"] = to_jsonable(self.finding.counterexample)
        evidence["reproduce"] = f"ssecert audit --claim {self.claim.id}"
        return {
            "verdict": self.finding.verdict,
            "statement": self.claim.statement,
            "where": self.claim.where,
            "document": self.claim.document,
            "evidence": evidence,
        }


def run_claim(claim_id: str) -> Outcome:
    """Run the check of one claim."""
    c = get_claim(claim_id)
    start = time.perf_counter()
    finding = c.check()
    if not isinstance(finding, Finding):
        raise TypeError(f"the check of {claim_id} returned {type(finding).__name__}, not a Finding")
    return Outcome(c, finding, time.perf_counter() - start)


def rounded(seconds: float) -> float:
    return float(f"{seconds:.3g}") if math.isfinite(seconds) else seconds
