"""Discrete Lyapunov certificates for linear error dynamics e(k+1) = F e(k).

``scipy.linalg.solve_discrete_lyapunov(A, Q)`` (what ``control.dlyap`` calls without
Slycot) solves A X A^T - X + Q = 0, so F^T is passed to get F^T P F - P + Q = 0.  It
returns an indefinite X for an unstable F without complaint, so nothing is taken on trust:
the certificate holds only when the recomputed P - F^T P F and P itself are positive
definite by Cholesky with a margin above a floating-point error bound.
"""

from __future__ import annotations

import enum
import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from ..base.validation import as_real_matrix
from ..numerics.exact_powers import ExactMatrix
from ..numerics.linalg import matrix_norm
from ..results import Verdict
from ..tolerances import EPS
from . import lyapunov_messages
from .outcomes import LyapunovCode, SchurCode, SchurState

if TYPE_CHECKING:
    from .spectral import SchurDecision

__all__ = [
    "LyapunovCode",
    "LyapunovMethod",
    "LyapunovCertificate",
    "lyapunov_certificate",
    "instability_witness",
    "verified_decrease",
]


class LyapunovMethod(enum.StrEnum):
    """What a ``LyapunovCertificate`` rests on: the value is the word written in evidence."""

    LYAPUNOV = "lyapunov"  # a Lyapunov matrix P verified in floating point with a margin
    EXACT_POWERS = "exact powers"  # the exact decision on F (``schur_decision``)
    # the exact decision on F by the Schur-Cohn test of its characteristic polynomial
    SCHUR_COHN = "exact Schur-Cohn test"


@dataclass(frozen=True)
class LyapunovCertificate:
    """Outcome of ``lyapunov_certificate``.

    Attributes
    ----------
    P : ndarray or None
        Symmetric solution of F^T P F - P + Q = 0.
    decrease : ndarray or None
        The recomputed P - F^T P F.
    margin : float or None
        Smallest eigenvalue of the recomputed decrease, relative to
        ``||P||``; the certificate holds when it beats ``error_bound``.
    error_bound : float
        Floating-point error bound on that eigenvalue, also relative.
    contraction : float or None
        Factor c < 1 with V(e+) <= c^2 V(e), V = e^T P e: the error decays at
        least like c^k in the P-norm.
    condition : float or None
        Condition number of P.
    residual : float or None
        ||F^T P F - P + Q|| / ||Q||.
    spectral_radius : float
        Of F (reported, not used to decide).
    code : LyapunovCode
        What came of the Lyapunov solution; anything but ``VERIFIED`` leaves the verdict
        to ``decision``.
    facts : mapping
        The numbers the words of ``code`` need (the solver's error, the margins); not
        written to JSON.
    witness : dict or None
    decision : SchurDecision or None
        The exact decision on F when no P verified.
    proof : dict or None
        The exact decision as the JSON writes it (``SchurDecision.to_dict``), or how a P
        found in balanced coordinates was written back.
    """

    P: np.ndarray | None
    decrease: np.ndarray | None
    margin: float | None
    error_bound: float
    contraction: float | None
    condition: float | None
    residual: float | None
    spectral_radius: float
    code: LyapunovCode = LyapunovCode.VERIFIED
    facts: Mapping[str, Any] = field(default_factory=dict)
    witness: dict[str, Any] | None = field(default=None)
    decision: SchurDecision | None = field(default=None)
    proof: dict[str, Any] | None = field(default=None)

    def __post_init__(self) -> None:
        if (self.code is LyapunovCode.VERIFIED) != (self.decision is None):
            raise ValueError("a Lyapunov certificate has a verified P or an exact decision")

    @property
    def verdict(self) -> Verdict:
        """``HOLDS`` (F is Schur, proven by P or by exact powers), ``FAILS`` (an eigenvalue of
        modulus >= 1, with a growing trajectory as witness) or ``INCONCLUSIVE``."""
        if self.decision is None:
            return Verdict.HOLDS
        return {
            SchurState.STABLE: Verdict.HOLDS,
            SchurState.UNSTABLE: Verdict.FAILS,
        }.get(self.decision.state, Verdict.INCONCLUSIVE)

    @property
    def decided_by(self) -> LyapunovCode | SchurCode:
        """The code that decided the verdict: ``LyapunovCode.VERIFIED`` for a verified P, else
        the ``SchurCode`` of the exact decision on F."""
        return self.code if self.decision is None else self.decision.code

    @property
    def method(self) -> LyapunovMethod:
        """``LYAPUNOV`` (P verified in floating point with a margin, an instability not proved
        exactly, or nothing decided) or ``EXACT_POWERS`` (no verified P, but rho(F) <= ||F^m||^(1/m) < 1 on
        the exact F, ``contraction`` then that bound on the asymptotic rate, not a per-step
        factor; or instability proved on the exact F), ``SCHUR_COHN`` (the same, decided by the
        Schur-Cohn test of the exact characteristic polynomial)."""
        d = self.decision
        if d is not None and (
            d.state is SchurState.STABLE or (d.rigorous and d.state is SchurState.UNSTABLE)
        ):
            if d.code in (SchurCode.SCHUR_COHN_STABLE, SchurCode.SCHUR_COHN_FAILS):
                return LyapunovMethod.SCHUR_COHN
            return LyapunovMethod.EXACT_POWERS
        return LyapunovMethod.LYAPUNOV

    @property
    def reason(self) -> str:
        """Why the verdict is what it is, in words (``lyapunov_messages``; empty for a
        verified P)."""
        d = self.decision
        if d is None:
            return lyapunov_messages.reason(self.code, self.facts, None, "")
        return lyapunov_messages.reason(self.code, self.facts, d.state, d.reason)


def instability_witness(
    F: np.ndarray,
    *,
    steps: int = 2000,
    parts: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    decision: Any = None,
    exact: ExactMatrix | None = None,
) -> dict[str, Any] | None:
    """A real initial error that does not decay under F, when F is not shown stable.

    ``verified`` is True only when ``schur_decision`` proves F unstable on
    its exact value (exact traces of powers, an exact eigenvalue on the unit
    circle) or the dominant eigenvalue exceeds 1 by more than its
    first-order error bound.  The trajectory from the dominant eigenvector is
    simulated with renormalisation (log-norms, so nothing overflows) and
    reported so the witness can be replayed; growth alone proves nothing,
    since a stable non-normal F can amplify an error for many steps first.
    Returns None when F is proven stable.

    Parameters
    ----------
    F : ndarray, shape (n, n)
    steps : int, default 2000
        Length of the replayed trajectory (it stops once the error doubled).
    parts : (A, L, C), optional
        Decide on F = A - L C formed exactly from these floats.
    decision : SchurDecision, optional
        A decision already made for this F.
    exact : ExactMatrix, optional
        Decide on the exact value F stands for (instead of ``parts``).
    """
    from .spectral import schur_decision

    if decision is None:
        decision = schur_decision(F, parts=parts, exact=exact)
    if decision.state is SchurState.STABLE:
        return None
    n = F.shape[0]
    lam, vr = np.linalg.eig(F)
    j = int(np.argmax(np.abs(lam)))
    v = vr[:, j]
    z = v.real if np.linalg.norm(v.real) >= np.linalg.norm(v.imag) else v.imag
    norm_z = float(np.linalg.norm(z))
    z = np.real(z) / norm_z if norm_z > 0 else np.eye(n)[0]
    log_norms = [0.0]
    w = z.copy()
    total = 0.0
    for _ in range(steps):
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow ends the walk
            w = F @ w
            size = float(np.linalg.norm(w))
        if size == 0.0 or not np.isfinite(size):
            break
        total += np.log(size)
        w /= size
        log_norms.append(total)
        if total >= np.log(2.0):
            break
    return {
        "eigenvalue": complex(lam[j]),
        "eigenvalue_error_bound": decision.details.get("first_order_error_bound"),
        "initial_error": z,
        "log_norms": log_norms[:: max(1, len(log_norms) // 200)],
        "grows_by_factor_2": bool(max(log_norms) >= np.log(2.0)),
        "verified": decision.state is SchurState.UNSTABLE,
        "proof": decision.to_dict(),
    }


def lyapunov_certificate(
    F: np.ndarray,
    Q: np.ndarray | None = None,
    *,
    clear: float = 100.0,
    parts: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    exact: ExactMatrix | None = None,
) -> LyapunovCertificate:
    """Certify that e(k+1) = F e(k) is asymptotically stable, or show it is not.

    A Lyapunov matrix P (``solve_discrete_lyapunov``) is the certificate when it
    verifies in floating point with a margin.  Otherwise the exact F decides
    (``schur_decision``): stable by exact powers, unstable by exact traces or
    an exact eigenvalue on the unit circle (with the dominant direction as a
    replayable witness), or inconclusive.

    Parameters
    ----------
    F : ndarray, shape (n, n)
    Q : ndarray, shape (n, n), optional
        Positive definite right-hand side (default identity); symmetrised.
    clear : float, default 100
        The decrease must exceed ``clear`` times the error bound.
    parts : (A, L, C), optional
        The floats F was formed from (F = A - L C); exact decisions are then
        made on the matrix of the printed gain.
    exact : ExactMatrix, optional
        The exact matrix F stands for when it is a rounded product (instead of ``parts``):
        exact decisions are made on it, and a verified P must also absorb the distance
        between F and it.

    Returns
    -------
    LyapunovCertificate

    Examples
    --------
    >>> import numpy as np
    >>> cert = lyapunov_certificate(np.array([[0.5, 1.0], [0.0, 0.2]]))
    >>> cert.verdict.value, cert.contraction < 1
    ('holds', True)
    >>> lyapunov_certificate(np.array([[1.1]])).verdict.value
    'fails'
    """
    F = np.asarray(as_real_matrix(F, "F"), dtype=float)
    n = F.shape[0]
    Q = np.eye(n) if Q is None else np.asarray(as_real_matrix(Q, "Q", shape=(n, n)))
    Q = 0.5 * (Q + Q.T)
    if exact is None and parts is not None:
        exact = ExactMatrix.error_matrix(*parts)
    cert = _certificate_in_units(F, Q, clear, exact)
    assert cert is not None  # (decided exactly where no P verifies)
    if cert.verdict is Verdict.FAILS or (
        cert.verdict is Verdict.HOLDS and cert.method is not LyapunovMethod.SCHUR_COHN
    ):
        return cert
    # a P verified in balanced coordinates also bounds the contraction per step, which the
    # Schur-Cohn test's radius bound does not
    balanced = _in_balanced_units(F, clear, exact)
    return cert if balanced is None else balanced


def _in_balanced_units(
    F: np.ndarray, clear: float, exact: ExactMatrix | None
) -> LyapunovCertificate | None:
    """A Lyapunov certificate found in balanced state coordinates F_b = S^-1 F S (S powers of
    two from LAPACK's balancing, exact), written back as P = S^-1 P_b S^-1; None when there
    is no balancing or it certifies nothing.  A matrix whose states are in very different
    units has a P that floating point cannot verify in those units."""
    from ..numerics.exact_powers import dyadic
    from ..numerics.linalg import state_balancing

    s = state_balancing(F, np.zeros((0, F.shape[0])))
    if s is None:
        return None
    k = np.round(np.log2(s)).astype(np.int64)
    F_b = F * (s[None, :] / s[:, None])
    base = exact if exact is not None else ExactMatrix(lambda: dyadic(F), None, "F")
    exact_b = base.similar(k, f"{base.source}, in balanced state coordinates")
    cert = _certificate_in_units(F_b, np.eye(F.shape[0]), clear, exact_b, decide_exactly=False)
    if cert is None or cert.verdict is not Verdict.HOLDS or cert.P is None:
        return None
    # any positive multiple of P is a Lyapunov matrix: c = max(s) min(s) centres the entries
    # c / (s_i s_j) on 1, so states 2^900 apart give a P of entries within 2^+-900
    exponents = int(k.max() + k.min()) - k[:, None] - k[None, :]  # of c / (s_i s_j)
    with np.errstate(all="ignore"):
        P = np.ldexp(cert.P, exponents)
        if not (np.all(np.isfinite(P)) and np.array_equal(np.ldexp(P, -exponents), cert.P)):
            return None  # not exactly representable in the user's coordinates
    c = float(np.ldexp(1.0, int(k.max() + k.min())))
    proof = {
        "state_scaling": s,
        "balanced_P": cert.P,
        "P_factor": c,
        "note": "P was verified in the coordinates e = diag(state_scaling) e_b (with F_b = "
        "S^-1 F S, Q = I there) and written back exactly as P = c S^-1 P_b S^-1, c = "
        "P_factor = max(s) min(s) (a power of two); margin, error bound and decrease are "
        "those of the balanced coordinates",
    }
    return replace(cert, P=P, proof=proof)


def _certificate_in_units(
    F: np.ndarray,
    Q: np.ndarray,
    clear: float,
    exact: ExactMatrix | None,
    *,
    decide_exactly: bool = True,
) -> LyapunovCertificate | None:
    """``lyapunov_certificate`` in the coordinates F is written in; where no P verifies, the
    exact decision on F, or None without ``decide_exactly``."""
    n = F.shape[0]
    rho = float(np.abs(np.linalg.eigvals(F)).max()) if n else 0.0
    P, code, facts = _lyapunov_solution(F, Q)
    if P is None:
        return _exact_fallback(F, exact, rho, code, facts) if decide_exactly else None
    c = _check_solution(F, Q, P, 0.0 if exact is None else exact.rounding(F))
    contraction = _verified_contraction(c, clear)
    if contraction is not None:
        return LyapunovCertificate(
            c.P,
            c.decrease,
            c.dec_min,
            c.bound,
            contraction,
            c.condition,
            c.residual,
            rho,
        )
    margins = {"decrease": c.dec_min, "p_min": c.p_min, "bound": c.bound}
    margin = min(c.dec_min, c.p_min)  # negative when P or the decrease is indefinite
    unverified = _Unverified(c.P, c.decrease, margin, c.bound, c.condition, c.residual)
    if not decide_exactly:
        return None
    return _exact_fallback(F, exact, rho, LyapunovCode.NOT_VERIFIED, margins, unverified)


def _lyapunov_solution(
    F: np.ndarray, Q: np.ndarray
) -> tuple[np.ndarray | None, LyapunovCode, dict[str, str]]:
    """P solving F^T P F - P + Q = 0 (``scipy.linalg.solve_discrete_lyapunov``, which
    ``control.dlyap`` calls without Slycot), or None, why there is none and the solver's
    error."""
    from scipy.linalg import solve_discrete_lyapunov

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # an ill-conditioned solve is judged below, not trusted
        try:
            P = np.asarray(solve_discrete_lyapunov(F.T, Q), dtype=float)
        except Exception as exc:  # singular Lyapunov operator (lambda_i lambda_j = 1)
            return None, LyapunovCode.NO_UNIQUE_SOLUTION, {"error": str(exc)}
    if not np.all(np.isfinite(P)):
        return None, LyapunovCode.NOT_FINITE, {}
    return P, LyapunovCode.VERIFIED, {}


class _Checked(NamedTuple):
    """A symmetrised Lyapunov solution and the margins its verification rests on."""

    P: np.ndarray
    decrease: np.ndarray  # P - F^T P F, symmetrised
    dec_min: float  # smallest eigenvalue of the decrease, relative to ||P||
    p_min: float  # smallest eigenvalue of P, relative to ||P||
    p_eigs: np.ndarray
    normP: float
    bound: float  # rounding error bound on those eigenvalues, relative to ||P||
    condition: float
    residual: float


def _check_solution(
    F: np.ndarray, Q: np.ndarray | None, P: np.ndarray, rounding: float = 0.0
) -> _Checked:
    """P symmetrised, its decrease, their smallest eigenvalues and the error bound (and the
    residual of the Lyapunov equation P solves for Q, NaN without Q).  ``rounding`` bounds
    ||F - F_exact||_2 for the exact matrix F stands for: ||F'PF - F_e'PF_e|| is at most
    (2 ||F|| + rounding) rounding ||P||, which the bound takes in."""
    n = F.shape[0]
    normF = matrix_norm(F)
    with np.errstate(all="ignore"):
        P = 0.5 * (P + P.T)
        normP = max(matrix_norm(P), np.finfo(float).tiny)
        residual = math.nan
        if Q is not None:
            residual = matrix_norm(F.T @ P @ F - P + Q) / max(matrix_norm(Q), np.finfo(float).tiny)
        decrease = P - F.T @ P @ F
    decrease = 0.5 * (decrease + decrease.T)
    # rounding in forming F^T P F and in eigvalsh, relative to ||P||
    bound = 10 * n * EPS * (normF * normF + 1.0) + (2.0 * normF + rounding) * rounding * (1 + 1e-12)
    if not (np.all(np.isfinite(decrease)) and np.all(np.isfinite(P)) and math.isfinite(bound)):
        # F or P beyond the float range (a step of 1e308): nothing is verified
        nan = np.full(n, math.nan)
        return _Checked(P, decrease, -math.inf, -math.inf, nan, normP, math.inf, math.inf, residual)
    dec_min = float(np.linalg.eigvalsh(decrease)[0]) / normP if n else 1.0
    p_eigs = np.linalg.eigvalsh(P)
    p_min = float(p_eigs[0]) / normP
    condition = float(p_eigs[-1] / p_eigs[0]) if p_eigs[0] > 0 else np.inf
    return _Checked(P, decrease, dec_min, p_min, p_eigs, normP, bound, condition, residual)


def _verified_contraction(c: _Checked, clear: float) -> float | None:
    """The contraction factor when P and the decrease are positive definite with a margin.

    Both smallest eigenvalues must exceed ``clear`` times the error bound
    and survive a Cholesky factorisation shifted by half of them; None
    otherwise.
    """
    if not (c.dec_min > clear * c.bound and c.p_min > clear * c.bound):
        return None
    n = c.P.shape[0]
    try:
        np.linalg.cholesky(c.P - 0.5 * c.p_min * c.normP * np.eye(n))
        np.linalg.cholesky(c.decrease - 0.5 * c.dec_min * c.normP * np.eye(n))
    except np.linalg.LinAlgError:
        return None
    # the decrease the exact F is sure of: the computed one less its error bound
    return float(np.sqrt(max(0.0, 1.0 - (c.dec_min - c.bound) * c.normP / c.p_eigs[-1])))


def verified_decrease(
    F: np.ndarray, P: np.ndarray, *, clear: float = 100.0, rounding: float = 0.0
) -> tuple[float, float] | None:
    """(margin, error bound) when V = e' P e is verified to decrease along e+ = F e, as
    ``lyapunov_certificate`` verifies its own P (both P and P - F' P F positive definite by
    more than ``clear`` times a rounding-error bound, relative to ||P||); None otherwise.
    ``rounding`` bounds the distance of F from the exact matrix it stands for."""
    c = _check_solution(np.asarray(F, float), None, np.asarray(P, float), rounding)
    if _verified_contraction(c, clear) is None:
        return None
    return c.dec_min, c.bound


class _Unverified(NamedTuple):
    """What a Lyapunov solution that did not verify reports (nothing when there is none)."""

    P: np.ndarray | None = None
    decrease: np.ndarray | None = None
    margin: float | None = None
    bound: float = 0.0
    condition: float | None = None
    residual: float | None = None


def _exact_fallback(
    F: np.ndarray,
    exact: ExactMatrix | None,
    rho: float,
    code: LyapunovCode,
    facts: Mapping[str, Any],
    unverified: _Unverified | None = None,
) -> LyapunovCertificate:
    """The certificate the exact F decides (``schur_decision``) when no P verifies (``code``
    and ``facts`` say why)."""
    from .spectral import schur_decision

    decision = schur_decision(F, exact=exact)
    proof = decision.to_dict()
    if decision.state is SchurState.STABLE:
        if decision.radius_upper is None:  # pragma: no cover - set whenever stable
            raise RuntimeError("a stable Schur decision carries its radius bound")
        upper = float(decision.radius_upper)
        return LyapunovCertificate(
            None,
            None,
            float(decision.details.get("spectral_radius_gap", 1.0 - upper)),
            0.0,
            upper,
            None,
            None,
            rho,
            code,
            facts,
            None,
            decision,
            proof,
        )
    witness = instability_witness(F, exact=exact, decision=decision)
    u = _Unverified() if unverified is None else unverified
    return LyapunovCertificate(
        u.P,
        u.decrease,
        u.margin,
        u.bound,
        None,
        u.condition,
        u.residual,
        rho,
        code,
        facts,
        witness,
        decision,
        proof,
    )
