"""The audit of the reference documents' numbered claims.

One module per document (``lasso``, ``thesis``, ``notes``, ``pruning``,
``sise``), one check per claim; ``ssecert audit`` runs them and writes
audit.html and audit.json, and ``pytest proofs_checks`` fails when a
verdict changes from the one recorded.

>>> from proofs_checks import run_claim
>>> run_claim("thesis.young").finding.verdict
'holds'
"""

from ._core import (
    DOCUMENTS,
    VERDICTS,
    Claim,
    Finding,
    Outcome,
    all_claims,
    claim,
    get_claim,
    run_claim,
)
from .audit import audit_json, render_audit, run_audit, write_audit

__all__ = [
    "DOCUMENTS",
    "VERDICTS",
    "Claim",
    "Finding",
    "Outcome",
    "all_claims",
    "claim",
    "get_claim",
    "run_claim",
    "run_audit",
    "audit_json",
    "render_audit",
    "write_audit",
]
