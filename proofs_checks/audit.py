"""Run the audit and render it: audit.json and a single-file audit.html."""

from __future__ import annotations

import datetime as _dt
import json
from collections.abc import Callable, Iterable
from importlib import resources
from pathlib import Path
from typing import Any

from ssecert.base.atomic import write_files

from ._core import DOCUMENTS, Outcome, all_claims, rounded, run_claim

__all__ = ["run_audit", "audit_json", "render_audit", "write_audit"]


def run_audit(
    claim_ids: Iterable[str] | None = None,
    *,
    progress: Callable[[str], None] | None = None,
) -> list[Outcome]:
    """Run the checks of the given claims (default: every claim), in the registry's order."""
    ids = list(all_claims()) if claim_ids is None else list(dict.fromkeys(claim_ids))
    outcomes = []
    for claim_id in ids:
        if progress is not None:
            progress(claim_id)
        outcomes.append(run_claim(claim_id))
    return outcomes


def _document(outcomes: list[Outcome]) -> dict[str, Any]:
    from ssecert.analyze import environment

    counts = {v: sum(o.finding.verdict == v for o in outcomes) for v in ("holds", "fails")}
    counts["conditional"] = sum(o.finding.verdict == "conditional" for o in outcomes)
    return {
        "ssecert_version": environment()["ssecert"],
        "claims": {o.claim.id: o.to_dict() for o in outcomes},
        "summary": counts,
        "meta": {
            "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
            "versions": environment(),
            # measured durations: with the date, the only fields that change between runs
            "timings": {o.claim.id: rounded(o.seconds) for o in outcomes},
        },
    }


def audit_json(outcomes: list[Outcome], *, indent: int | None = 2) -> str:
    """audit.json: ``{"claims": {ID: {"verdict", "statement", "where", "evidence"}}, ...}``."""
    return json.dumps(_document(outcomes), indent=indent, allow_nan=False) + "\n"


def render_audit(outcomes: list[Outcome]) -> str:
    """audit.html: one page, the claims of each document with their verdicts and evidence."""
    import jinja2

    doc = _document(outcomes)
    sections = []
    for prefix, title in DOCUMENTS.items():
        rows = [
            {
                "id": o.claim.id,
                "entry": doc["claims"][o.claim.id],
                "counterexample": _pretty(
                    doc["claims"][o.claim.id]["evidence"].get("counterexample")
                ),
                "evidence": _pretty(
                    {
                        k: v
                        for k, v in doc["claims"][o.claim.id]["evidence"].items()
                        if k not in ("explanation", "condition", "counterexample", "reproduce")
                    }
                ),
            }
            for o in outcomes
            if o.claim.id.split(".", 1)[0] == prefix
        ]
        if rows:
            sections.append({"title": title, "rows": rows})
    template = (resources.files("proofs_checks") / "templates" / "audit.html.j2").read_text(
        encoding="utf-8"
    )
    env = jinja2.Environment(autoescape=True, undefined=jinja2.StrictUndefined)
    return env.from_string(template).render(
        sections=sections, summary=doc["summary"], meta=doc["meta"], total=len(outcomes)
    )


def _pretty(value: Any) -> str | None:
    """A mapping as JSON with one key per line (matrices stay on their line, as in the file)."""
    if value is None:
        return None
    if not isinstance(value, dict):
        return json.dumps(value, allow_nan=False)
    lines = [f"  {json.dumps(k)}: {json.dumps(v, allow_nan=False)}" for k, v in value.items()]
    return "{\n" + ",\n".join(lines) + "\n}"


def write_audit(outcomes: list[Outcome], out: str | Path) -> tuple[Path, Path]:
    """Write DIR/audit.html and DIR/audit.json, both or neither."""
    folder = Path(out)
    html, js = folder / "audit.html", folder / "audit.json"
    write_files({html: render_audit(outcomes), js: audit_json(outcomes)})
    return html, js
