"""Readable terminal summary of a certificate."""

from __future__ import annotations

import textwrap
from typing import Any

import numpy as np

from ..results import Certificate, Check, Verdict
from .cells import margin_text, named, number, value_text, verdict_label

__all__ = ["render_table"]

_MARK = {Verdict.HOLDS: "holds", Verdict.FAILS: "FAILS", Verdict.INCONCLUSIVE: "inconclusive"}


def _fmt(value: Any) -> str:
    return number(value)


def _mark(check: Check) -> str:
    """The verdict column: FAILS in capitals, "does not apply" for a check that does not."""
    return _MARK[check.verdict] if check.applies else verdict_label(check)


def _sensor_list(check: Check, names: tuple[str, ...], key: str) -> str:
    indices = check.fields.get(key)
    if not indices:
        return "[]" if indices == [] else "-"
    return ", ".join(f"{names[i]} ({i})" for i in indices)


def render_table(certificate: Certificate, *, width: int = 100, compact: bool = False) -> str:
    """Plain-text table of checks, with each check's finding underneath.

    Parameters
    ----------
    certificate : Certificate
    width : int, default 100
        Line width for wrapped sentences.
    compact : bool, default False
        Only the table and the findings of required checks that do not hold.

    Returns
    -------
    str
    """
    meta = certificate.meta or {}
    lines = _header(certificate) + _check_rows(certificate)
    if compact:
        for check in certificate.checks:
            if check.required and check.verdict is not Verdict.HOLDS:
                lines.append(
                    textwrap.fill(
                        f"{check.id}: {check.summary}", width=width, subsequent_indent="  "
                    )
                )
        lines.append(f"verdict: {_MARK[certificate.verdict]} (exit status {certificate.exit_code})")
        return "\n".join(lines) + "\n"
    for check in certificate.checks:
        lines.extend(_finding(check, certificate.system.sensors, width))
    for note in meta.get("notes", []):
        lines.append("")
        lines.append(textwrap.fill("note: " + note, width=width))
    lines.append("")
    code = certificate.exit_code
    lines.append(f"verdict: {_MARK[certificate.verdict]} (exit status {code})")
    return "\n".join(lines) + "\n"


def _header(certificate: Certificate) -> list[str]:
    """The plant's name and sizes, the spec file with its hash, and a blank line."""
    system = certificate.system
    meta = certificate.meta or {}
    header = f"ssecert: {system.name}  (n = {system.n}, p = {system.p}"
    if "max_attacked" in meta:
        header += f", s = {meta['max_attacked']}, horizon = {meta.get('horizon')}"
    header += ")"
    lines = [header]
    spec = meta.get("spec") or {}
    if spec.get("source"):
        digest = (spec.get("sha256") or "")[:12]
        lines.append(f"spec: {spec['source']}" + (f"  sha256 {digest}" if digest else ""))
    lines.append("")
    return lines


def _check_rows(certificate: Certificate) -> list[str]:
    """The aligned table of checks (advisory ones starred), its legend and a blank line.

    The value and margin cells name their quantity ("max_removable = 2").
    """
    rows = [("check", "verdict", "value", "margin", "method")]
    for check in certificate.checks:
        name = check.id + ("" if check.required else " *")
        rows.append(
            (
                name,
                _mark(check),
                named(check.value_name, value_text(check)),
                named(check.margin_name, margin_text(check)),
                check.method,
            )
        )
    widths = [max(len(r[i]) for r in rows) for i in range(5)]
    lines = []
    for j, row in enumerate(rows):
        lines.append("  ".join(cell.ljust(widths[i]) for i, cell in enumerate(row)).rstrip())
        if j == 0:
            lines.append("  ".join("-" * w for w in widths))
    lines.append("* advisory: reported, does not change the exit status")
    lines.append("")
    return lines


def _finding(check: Check, sensors: tuple[str, ...], width: int) -> list[str]:
    """A check's verdict, its wrapped summary and the details its kind adds."""
    lines = [f"{check.id}: {_mark(check)}"]
    lines.append(
        textwrap.fill(check.summary, width=width - 2, initial_indent="  ", subsequent_indent="  ")
    )
    if check.id == "sparse_observability":
        lines.extend(_sparse_details(check, sensors))
    if check.id == "observer_gain" and check.fields.get("L") is not None:
        L = np.asarray(check.fields["L"], dtype=float)
        line = f"  L ({L.shape[0]} x {L.shape[1]}, {check.fields.get('gain_method')})"
        if check.fields.get("nilpotency_index") is not None:
            line += f", nilpotency index {check.fields['nilpotency_index']}"
        lines.append(line)
    if check.id == "iss_gain" and check.fields.get("gamma") is not None:
        alpha = check.fields.get("alpha")
        decay = "" if alpha is None else f", alpha = {number(alpha)}"
        lines.append(f"  gamma = {number(check.fields['gamma'])}{decay}")
    if check.id == "thesis_assumptions":
        items = check.fields.get("items", {})
        lines.append("  " + ", ".join(f"{k}: {v}" for k, v in items.items()))
    if check.id == "irrepresentable" and check.fields.get("worst_support") is not None:
        names = check.fields.get("worst_support_names") or check.fields["worst_support"]
        lines.append(f"  worst support: {', '.join(map(str, names))}")
    return lines


def _sparse_details(check: Check, sensors: tuple[str, ...]) -> list[str]:
    """max_removable with its bound, max_correctable, the breaking set and the stealthy attack."""
    f = check.fields
    lower = " (lower bound)" if f.get("max_removable_is_lower_bound") else ""
    upper = (
        f" (upper bound; at least {f.get('max_removable_at_least')})"
        if f.get("max_removable_is_upper_bound")
        else ""
    )
    lines = [
        f"  max_removable = {_fmt(f.get('max_removable'))}{lower}{upper}"
        f", max_correctable = {_fmt(f.get('max_correctable'))}"
        f", breaking set: {_sensor_list(check, sensors, 'breaking_set')}"
    ]
    if check.witness:
        w = check.witness
        a = ", ".join(sensors[i] for i in w.get("sensors_a", [])) or "none"
        b = ", ".join(sensors[i] for i in w.get("sensors_b", [])) or "none"
        scaled = (
            f"; shown for 2^{w['time_scale_log2']} A (beyond the float range on A itself)"
            if w.get("time_scale_log2") is not None
            else ""
        )
        lines.append(
            f"  stealthy attack: sensors {a} / {b}; simulated output mismatch "
            f"{_fmt(w.get('residual'))} (verified: {w.get('verified')}){scaled}"
        )
    return lines
