"""Results of analyses: one ``Check`` per question, gathered in a ``Certificate``.

Analyses return these objects and never print; renderers (terminal table,
JSON, HTML) read them.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .base.display import html_display
from .budget import Refusal

__all__ = [
    "Verdict",
    "Check",
    "Certificate",
    "to_jsonable",
    "combine_verdicts",
    "Step",
    "decide",
    "Withdrawn",
    "withdraw",
    "QUANTITY_NAMES",
]

#: What each check's ``value`` and ``margin`` are, by check id, when the check does not say
#: otherwise (a deadbeat gain's value is its nilpotency index, not a spectral radius: the code
#: that computes such a value names it).  The margin is always compared with 0.
QUANTITY_NAMES: Mapping[str, tuple[str, str]] = {
    "observability": ("observability index", "min PBH singular value"),
    "sparse_observability": ("max_removable", "min PBH singular value"),
    "irrepresentable": ("irrepresentable constant", "1 - constant"),
    "observer_gain": ("spectral radius of A - L C", "Lyapunov margin"),
    "observer_stability": ("decay rate alpha", "LMI margin"),
    "iss_gain": ("l2 gain gamma", "LMI margin"),
    "thesis_assumptions": ("assumptions not met", ""),
    "region_of_attraction": ("radius ||e(0)||", "certificate margin"),
}


class Verdict(str, enum.Enum):
    """Outcome of a check."""

    HOLDS = "holds"
    FAILS = "fails"
    INCONCLUSIVE = "inconclusive"

    def __str__(self) -> str:
        return self.value

    @classmethod
    def of(cls, *, holds: bool, fails: bool = False) -> Verdict:
        """HOLDS where ``holds``, else FAILS where ``fails``, else INCONCLUSIVE (the verdict
        an outcome's code gives)."""
        if holds:
            return cls.HOLDS
        return cls.FAILS if fails else cls.INCONCLUSIVE


def to_jsonable(value: Any) -> Any:
    """Convert results to JSON-compatible Python objects.

    Arrays become nested lists, complex numbers ``{"re": ..., "im": ...}``,
    and non-finite floats the strings ``"Infinity"``, ``"-Infinity"`` and
    ``"NaN"`` (strict JSON has no literal for them; ``float()`` in Python
    and ``Number()`` in JavaScript read these strings back).
    """
    if isinstance(value, (Check, Certificate)):
        return value.to_dict()
    if isinstance(value, enum.Enum):
        return value.value
    if isinstance(value, Mapping):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return _array_jsonable(value)
    if isinstance(value, (list, tuple, set, frozenset)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isnan(v):
            return "NaN"
        if math.isinf(v):
            return "Infinity" if v > 0 else "-Infinity"
        return v
    if isinstance(value, (complex, np.complexfloating)):
        return {"re": to_jsonable(value.real), "im": to_jsonable(value.imag)}
    if value is None or isinstance(value, str):
        return value
    if isinstance(value, Refusal):  # a step not attempted: its sentence
        return str(value)
    raise TypeError(f"cannot convert {type(value).__name__} to JSON")


# Largest array written to JSON entry by entry: a model of thousands of states (an SSO window
# of hundreds of steps) has matrices of millions of entries, which would take gigabytes as
# Python lists; beyond it the array is described (shape, norm and a hash of its bytes).
MAX_JSON_ENTRIES = 1_000_000


def _array_jsonable(value: np.ndarray) -> Any:
    """An array as nested lists (real finite floats without a Python loop), or its summary."""
    if value.size > MAX_JSON_ENTRIES:
        import hashlib

        data = np.ascontiguousarray(value)
        with np.errstate(all="ignore"):
            norm = float(np.sqrt(np.sum(np.abs(data.astype(complex)) ** 2)))
        return {
            "omitted": f"an array of {value.size:,} entries, more than the {MAX_JSON_ENTRIES:,} "
            f"written to JSON",
            "shape": list(value.shape),
            "dtype": str(value.dtype),
            "frobenius_norm": to_jsonable(norm),
            "sha256_of_bytes": hashlib.sha256(data.tobytes()).hexdigest(),
        }
    if value.dtype.kind in "fiu" and (value.dtype.kind != "f" or np.all(np.isfinite(value))):
        return value.tolist()
    return to_jsonable(value.tolist())


@dataclass(frozen=True)
class Check:
    """The answer to one question about a design.

    Attributes
    ----------
    id : str
        Snake-case identifier used in JSON (``"sparse_observability"``).
    title : str
        Human-readable title.
    verdict : Verdict
        ``holds``, ``fails`` or ``inconclusive``.
    summary : str
        One sentence saying what was found and why.
    value : object
        Headline value (an index, a count, a constant).
    margin : float or None
        How far the decision is from its threshold, in the units stated in
        ``evidence``; ``None`` when not meaningful.
    method : str
        How the answer was computed.
    required : bool
        Whether the check decides the exit status.
    fields : mapping
        Check-specific JSON fields (``max_removable``, ``breaking_set``...).
    evidence : mapping
        Data that lets anyone re-check the verdict.
    witness : mapping or None
        Counterexample when the check fails.
    tolerances : mapping
        Tolerances used.
    value_name, margin_name : str
        What ``value`` and ``margin`` are ("spectral radius of A - L C",
        "LMI margin"); by default those of ``QUANTITY_NAMES`` for the id.
    applies : bool, default True
        False for an advisory check whose failure means only that a
        sufficient condition it tests is not met: the result it would support
        does not apply to this design, and no verdict of the certificate
        relies on it.  Reports show "does not apply" instead of fails;
        ``verdict`` keeps the answer to the check's own question.
    value_text : str, default ""
        ``value`` in words where its float cannot say what the verdict rests on: an exact
        spectral radius bound 1 - 2^-60 is the float 1.0, and reads "1 - 8.67e-19".  Reports
        show it instead of the rounded float; the JSON keeps ``value`` (and ``margin``, the
        exact distance).  Empty: the float, rounded.
    code : Enum or None, default None
        The reason code that says why the check has its verdict, where its analysis has one
        (the irrepresentable check's ``IrrepresentableCode``, observability's
        ``ObservabilityCode``, sparse observability's ``SparseCode``, the region of
        attraction's ``RegionCode``; observer_gain's and a linear observer_stability's
        ``LyapunovCode.VERIFIED`` or the exact decision's ``SchurCode``
        (``LyapunovCertificate.decided_by``), the ``LMICause`` of an observer_stability from
        a circle or Zames-Falb certificate or refused before one, the ``WitnessKind`` of a
        failing one's witness, and iss_gain's ``LMICause``; the decoder bounds' ``BoundCode``,
        ``LassoBoundCode`` and ``L1BoundCode``; ``Withdrawn`` for a verdict that
        contradicted a check decided before it): for callers and tests that read the
        decision instead of the summary's words; not written to JSON.  None where the check
        has no typed outcome (a deadbeat gain, an observer not built).
    """

    id: str
    title: str
    verdict: Verdict
    summary: str
    value: Any = None
    margin: float | None = None
    method: str = ""
    required: bool = True
    fields: Mapping[str, Any] = field(default_factory=dict)
    evidence: Mapping[str, Any] = field(default_factory=dict)
    witness: Mapping[str, Any] | None = None
    tolerances: Mapping[str, Any] = field(default_factory=dict)
    value_name: str = ""
    margin_name: str = ""
    applies: bool = True
    value_text: str = ""
    code: enum.Enum | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "verdict", Verdict(self.verdict))
        value_name, margin_name = QUANTITY_NAMES.get(self.id, ("", ""))
        object.__setattr__(self, "value_name", self.value_name or value_name)
        object.__setattr__(self, "margin_name", self.margin_name or margin_name)
        if not self.applies and (self.required or self.verdict is not Verdict.FAILS):
            raise ValueError(
                f"check {self.id!r}: applies=False is for an advisory check that fails, got "
                f"required={self.required}, verdict {self.verdict.value}"
            )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary with the check-specific fields at top level."""
        out: dict[str, Any] = {
            "verdict": self.verdict.value,
            "title": self.title,
            "summary": self.summary,
            "required": self.required,
            "applies": self.applies,
            "value": self.value,
            "value_name": self.value_name,
            "margin": self.margin,
            "margin_name": self.margin_name,
            "method": self.method,
        }
        out.update(self.fields)
        if self.witness is not None:
            out["witness"] = self.witness
        out["evidence"] = self.evidence
        out["tolerances"] = self.tolerances
        return to_jsonable(out)


class Withdrawn(enum.Enum):
    """Why a check reports inconclusive in place of the verdict its analysis reached
    (``Check.code``, set by ``withdraw``)."""

    CONTRADICTS = "contradicts a check decided before it"


def withdraw(check: Check, other: Check, why: str) -> Check:
    """``check`` reported inconclusive: its verdict contradicts ``other``'s, a check it was
    decided after (``why``: the implication between them that fails).

    The check that sees the contradiction reports it, where it is built (a step of
    ``decide`` that needs ``other``): a defect shows as an open question with both answers,
    never as a confident one.  The original verdict, the other check and why are in the
    evidence (``withdrawn_verdict``, ``contradicts``, ``contradiction``).

    Examples
    --------
    >>> a = Check("a", "A", Verdict.HOLDS, "A holds.")
    >>> b = withdraw(Check("b", "B", Verdict.FAILS, "B fails."), a, "b implies not a")
    >>> b.verdict.value, b.code is Withdrawn.CONTRADICTS, b.evidence["contradicts"]
    ('inconclusive', True, 'a')
    """
    return replace(
        check,
        verdict=Verdict.INCONCLUSIVE,
        code=Withdrawn.CONTRADICTS,
        applies=True,
        summary=(
            f"Withdrawn: this check said {check.verdict.value} but contradicts {other.id} "
            f"({other.verdict.value}: {why}); please report this plant. Original: "
            f"{check.summary}"
        ),
        evidence={
            **check.evidence,
            "withdrawn_verdict": check.verdict.value,
            "contradicts": other.id,
            "contradiction": why,
        },
    )


def combine_verdicts(verdicts: Sequence[Verdict | str]) -> Verdict:
    """Fails if any fails, else inconclusive if any is, else holds (verdicts or their names)."""
    given = [Verdict(v) for v in verdicts]
    if Verdict.FAILS in given:
        return Verdict.FAILS
    if Verdict.INCONCLUSIVE in given:
        return Verdict.INCONCLUSIVE
    return Verdict.HOLDS


@dataclass(frozen=True)
class Certificate:
    """Ordered checks of one design and the overall verdict.

    The overall verdict follows the exit-status rule: it combines the
    required checks only (advisory checks are reported but do not count).

    Attributes
    ----------
    system : System
        The plant the checks are about.
    checks : tuple of Check
        Checks in report order, ids unique.
    meta : mapping
        Provenance: spec file and hash, versions, seed, date, notes.
    """

    system: Any
    checks: tuple[Check, ...]
    meta: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "checks", tuple(self.checks))
        ids = [c.id for c in self.checks]
        if len(set(ids)) != len(ids):
            raise ValueError(f"check ids must be unique, got {ids}")

    def __getitem__(self, check_id: str) -> Check:
        check = self.get(check_id)
        if check is None:
            raise KeyError(check_id)
        return check

    def __contains__(self, check_id: object) -> bool:
        return isinstance(check_id, str) and self.get(check_id) is not None

    def get(self, check_id: str, default: Check | None = None) -> Check | None:
        """The check with this id, or ``default`` when the certificate has none."""
        return next((c for c in self.checks if c.id == check_id), default)

    @property
    def verdict(self) -> Verdict:
        """Overall verdict over the required checks."""
        return combine_verdicts([c.verdict for c in self.checks if c.required])

    @property
    def exit_code(self) -> int:
        """0 holds, 1 fails, 3 inconclusive."""
        return {Verdict.HOLDS: 0, Verdict.FAILS: 1, Verdict.INCONCLUSIVE: 3}[self.verdict]

    def to_dict(self) -> dict[str, Any]:
        """The JSON document: version, system, verdict, checks."""
        from ._version import __version__

        out: dict[str, Any] = {
            "ssecert_version": __version__,
            "system": self.system.to_dict(),
            "verdict": self.verdict.value,
            "checks": {c.id: c.to_dict() for c in self.checks},
        }
        if self.meta:
            out["meta"] = to_jsonable(dict(self.meta))
        return out


# notebooks show checks and certificates as the report does
Check._repr_html_ = html_display("check_fragment")  # type: ignore[attr-defined]
Certificate._repr_html_ = html_display("certificate_fragment")  # type: ignore[attr-defined]


@dataclass(frozen=True)
class Step:
    """One step of a check graph (``decide``): ``build`` is called once with the outcomes of
    the steps named in ``needs``, in that order.

    Attributes
    ----------
    name : str
    build : callable
    needs : tuple of str
        Steps that come before this one, whose outcomes it reads.
    timed : bool
        Whether its seconds are recorded under its name (``meta.timings``).
    """

    name: str
    build: Callable[..., Any]
    needs: tuple[str, ...] = ()
    timed: bool = True


def decide(steps: Sequence[Step], laps: Any | None = None) -> dict[str, Any]:
    """Run a check graph: every step once, in the order given, each from the outcomes of the
    steps it needs, so that no check is edited once built and the order that decides what a
    check says is declared where the steps are.

    Parameters
    ----------
    steps : sequence of Step
        Each step after those it needs.
    laps : ssecert.budget.Laps, optional
        Records the seconds of each timed step, begun (for the stage display) as it starts.

    Returns
    -------
    dict
        Each step's outcome by name.

    Examples
    --------
    >>> out = decide([Step("a", lambda: 2), Step("b", lambda a: a + 1, needs=("a",))])
    >>> out["b"]
    3
    >>> decide([Step("b", lambda a: a, needs=("a",))])
    Traceback (most recent call last):
    ...
    ValueError: step 'b' needs 'a', which is not an earlier step
    """
    done: dict[str, Any] = {}
    for step in steps:
        if step.name in done:
            raise ValueError(f"step {step.name!r} appears twice")
        for need in step.needs:
            if need not in done:
                raise ValueError(f"step {step.name!r} needs {need!r}, which is not an earlier step")
        clock = laps if step.timed else None
        if clock is not None and getattr(clock, "begun", None) != step.name:
            clock.begin(step.name)  # the stage display shows it while it runs
        outcome = step.build(*(done[need] for need in step.needs))
        done[step.name] = clock.lap(step.name, outcome) if clock is not None else outcome
    return done
