"""The exact Schur decision and the Lyapunov certificate: decided on codes, worded apart.

Each ``SchurCode`` is reached by a plant whose answer is known by
construction; the verdicts are read from the codes, and the words of every
code are checked once, here (``ssecert.stability.spectral_messages`` and
``ssecert.stability.lyapunov_messages``).
"""

import numpy as np
import pytest

from ssecert.numerics.schur_cohn import SCHUR_COHN_LIMIT
from ssecert.results import Verdict
from ssecert.stability import lmi_messages, lyapunov_messages, spectral_messages
from ssecert.stability.lmi import LMICertificate, LureModel, circle_certificate
from ssecert.stability.lyapunov import LyapunovMethod, lyapunov_certificate
from ssecert.stability.outcomes import (
    LMICause,
    LMICode,
    LyapunovCode,
    SchurCode,
    SchurState,
    VerifyCode,
    VerifyProblem,
)
from ssecert.stability.spectral import EXACT_SCHUR_LIMIT, schur_decision
from ssecert.stability.zames_falb import zames_falb_certificate

_NEAR_ONE = np.array([[1.0 - 2.0**-30, 1.0], [np.nextafter(2.0**-60, 0.0), 1.0 - 2.0**-30]])

# (plant, the code that decides it): each answer known by construction
PLANTS = {
    "stable diagonal": (np.diag([0.5, 0.2]), SchurCode.POWERS_STABLE),
    "rotation, rho = 1": (np.array([[0.0, 1.0], [-1.0, 0.0]]), SchurCode.TRACE_REACHES_N),
    # F^2 = -(1 + 2^-53 - 2^-105) I: rho = 1 + 2^-54, above 1 by less than a float resolves
    "rho 1 + 2^-54": (
        np.array([[0.0, 1.0 + 2.0**-52], [-(1.0 - 2.0**-53), 0.0]]),
        SchurCode.TRACE_EXCESS,
    ),
    "eigenvalue 2": (np.diag([2.0, 0.5]), SchurCode.TRACES_BELOW),
    "identity": (np.eye(2), SchurCode.EIGENVALUE_ON_CIRCLE),
    "eigenvalue 1 + 2^-40": (np.diag([1.0 + 2.0**-40, 0.5]), SchurCode.EIGENVALUE_ON_CIRCLE),
    # beyond the exact limit: only the first-order bound speaks
    "too large for exact powers": (
        np.diag([1.5] + [0.1] * EXACT_SCHUR_LIMIT),
        SchurCode.FIRST_ORDER,
    ),
    # eigenvalues 1 - 2^-30 +- (slightly less than 2^-30): rho < 1 by ~1e-25, where no power
    # up to 2^8 has a norm below 1; the exact characteristic polynomial decides it
    "rho 1 - 1e-25": (_NEAR_ONE, SchurCode.SCHUR_COHN_STABLE),
    # eigenvalues +-i and 1/2: |tr F^m| stays below n = 3, no eigenvalue is +-1
    "rotation and a stable mode": (
        np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.5]]),
        SchurCode.SCHUR_COHN_FAILS,
    ),
    # copies of it beyond the Schur-Cohn limit: nothing decides it
    "rho 1 - 1e-25, n beyond the Schur-Cohn limit": (
        np.kron(np.eye(SCHUR_COHN_LIMIT // 2 + 1), _NEAR_ONE),
        SchurCode.UNDECIDED,
    ),
    "not finite": (np.array([[np.nan]]), SchurCode.NON_FINITE),
}


@pytest.mark.parametrize("name", list(PLANTS))
def test_each_schur_code_is_reached_and_decides_state_and_rigour(name):
    F, code = PLANTS[name]
    decision = schur_decision(F)
    assert decision.code is code
    assert decision.state is code.state and decision.rigorous is code.rigorous
    # the JSON record writes the words of this module, in the same places as before
    record = decision.to_dict()
    assert record["state"] is decision.state and record["reason"] == decision.reason
    assert record["method"] == spectral_messages.method(code, decision.facts)


def test_the_codes_decide_states_as_documented():
    assert {c for c in SchurCode if c.state is SchurState.STABLE} == {
        SchurCode.POWERS_STABLE,
        SchurCode.SCHUR_COHN_STABLE,
    }
    assert {c for c in SchurCode if c.state is SchurState.UNKNOWN} == {
        SchurCode.NON_FINITE,
        SchurCode.UNDECIDED,
    }
    assert {c for c in SchurCode if not c.rigorous} == {
        SchurCode.NON_FINITE,
        SchurCode.FIRST_ORDER,
        SchurCode.UNDECIDED,
    }


def test_the_facts_of_each_code_carry_the_numbers_the_words_print():
    assert schur_decision(np.diag([1.0 + 2.0**-40, 0.5])).facts["eigenvalue"] == 1.0 + 2.0**-40
    assert schur_decision(np.eye(2)).facts["eigenvalue"] == 1.0
    rotation = schur_decision(np.array([[0.0, 1.0], [-1.0, 0.0]]))
    assert rotation.facts["power"] == 2 and rotation.facts["n"] == 2
    stable = schur_decision(np.diag([0.5, 0.2]))
    assert stable.facts["upper"] == stable.radius_upper < 1 and stable.facts["gap"] > 0


# ---- the words, checked once -------------------------------------------------------------


def test_every_schur_code_has_a_method_and_a_reason():
    facts = {
        "power": 3,
        "source": "of F",
        "upper": 0.5,
        "gap": 0.5,
        "n": 2,
        "trace_excess": 1e-17,
        "radius_excess": 1e-18,
        "lower": 1.25,
        "eigenvalue": -1.0,
        "bound": 1e-14,
        "j": 1,
    }
    for code in SchurCode:
        words = spectral_messages.reason(code, facts, 1.5 + 0j, 1.5, 0.5)
        assert words and "{" not in words
        assert spectral_messages.method(code, facts)


def test_schur_words_show_which_side_of_one_a_number_is_on():
    # the exact powers, the excess over n and over 1, the eigenvalue: none prints as "1"
    assert spectral_messages.below_one(1 - 1.65e-7, 1.65e-7) == "1 - 1.65e-07 < 1"
    assert spectral_messages.below_one(0.5, 0.5) == "0.5 < 1"
    excess = spectral_messages.reason(
        SchurCode.TRACE_EXCESS,
        {"power": 2, "source": "of F", "n": 2, "trace_excess": 2.2e-16, "radius_excess": 5.5e-17},
        1.0,
        1.0,
        1.0,
    )
    assert "|trace F^2| = 2 + 2.2e-16 > n = 2" in excess and "1 + 5.5e-17 > 1" in excess
    eigen = spectral_messages.method(SchurCode.EIGENVALUE_ON_CIRCLE, {"eigenvalue": 1 + 2**-40})
    assert eigen != "exact eigenvalue 1" and eigen.startswith("exact eigenvalue 1.0000")
    # a certified radius interval just below 1 prints on its side of 1
    undecided = schur_decision(PLANTS["rho 1 - 1e-25, n beyond the Schur-Cohn limit"][0]).reason
    assert "certified 1 <=" not in undecided and "certified 0.99999" in undecided
    # the Schur-Cohn test's radius 1 - 2^-j, and the bound it proves below 1
    stable = schur_decision(_NEAR_ONE)
    j = stable.facts["j"]
    assert stable.method == f"exact Schur-Cohn test: rho < 1 - 2^-{j}" and j > 53
    assert stable.radius_upper == 1.0 and stable.details["spectral_radius_gap"] == 2.0**-j
    assert f"radius 1 - 2^-{j}" in stable.reason and "below 1 - " in stable.reason


# ---- the Lyapunov certificate --------------------------------------------------------------


@pytest.mark.parametrize(
    ("F", "code", "verdict", "method"),
    [
        (np.diag([0.5, 0.2]), LyapunovCode.VERIFIED, Verdict.HOLDS, LyapunovMethod.LYAPUNOV),
        # nilpotent with an entry 2^60: no P verifies in floats, the exact powers prove it
        (
            np.array([[0.0, 2.0**60], [0.0, 0.0]]),
            LyapunovCode.NOT_VERIFIED,
            Verdict.HOLDS,
            LyapunovMethod.EXACT_POWERS,
        ),
        # lambda_i lambda_j = 1: the Lyapunov operator is singular; exact traces fail it
        (
            np.array([[0.0, 1.0], [-1.0, 0.0]]),
            LyapunovCode.NO_UNIQUE_SOLUTION,
            Verdict.FAILS,
            LyapunovMethod.EXACT_POWERS,
        ),
        # unstable beyond the exact limit: the first-order bound fails it, not rigorously
        (
            np.diag([1.5] + [0.1] * EXACT_SCHUR_LIMIT),
            LyapunovCode.NOT_VERIFIED,
            Verdict.FAILS,
            LyapunovMethod.LYAPUNOV,
        ),
        (
            PLANTS["rho 1 - 1e-25, n beyond the Schur-Cohn limit"][0],
            LyapunovCode.NOT_VERIFIED,
            Verdict.INCONCLUSIVE,
            LyapunovMethod.LYAPUNOV,
        ),
        # within the Schur-Cohn limit the exact characteristic polynomial proves it
        (
            _NEAR_ONE,
            LyapunovCode.NOT_VERIFIED,
            Verdict.HOLDS,
            LyapunovMethod.SCHUR_COHN,
        ),
    ],
)
def test_a_lyapunov_certificate_is_decided_by_its_codes(F, code, verdict, method):
    cert = lyapunov_certificate(F)
    assert cert.code is code and cert.verdict is verdict and cert.method is method
    assert (cert.decision is None) == (code is LyapunovCode.VERIFIED)
    if cert.decision is not None:
        assert cert.proof == cert.decision.to_dict()
        if verdict is Verdict.FAILS:
            assert cert.witness is not None


def test_a_certificate_needs_a_verified_p_or_an_exact_decision():
    cert = lyapunov_certificate(np.diag([0.5, 0.2]))
    with pytest.raises(ValueError, match="verified P or an exact decision"):
        type(cert)(cert.P, None, None, 0.0, None, None, None, 0.5, LyapunovCode.NOT_VERIFIED)


def test_every_lyapunov_code_has_words_beside_the_decision():
    facts = {"error": "singular operator", "decrease": -1e-3, "p_min": 2e-3, "bound": 1e-15}
    for code in LyapunovCode:
        why = lyapunov_messages.unverified(code, facts)
        assert bool(why) is (code is not LyapunovCode.VERIFIED)
        assert lyapunov_messages.reason(code, facts, None, "") == ""
        # an exact instability is the whole reason; otherwise why no P, then the exact F
        assert lyapunov_messages.reason(code, facts, SchurState.UNSTABLE, "EXACT") == "EXACT"
        stable = lyapunov_messages.reason(code, facts, SchurState.STABLE, "EXACT")
        assert stable == f"{why}; instead, EXACT"
        assert lyapunov_messages.reason(code, facts, SchurState.UNKNOWN, "EXACT") == f"{why}; EXACT"
    assert "singular operator" in lyapunov_messages.unverified(
        LyapunovCode.NO_UNIQUE_SOLUTION, facts
    )
    assert "-1.00e-03" in lyapunov_messages.unverified(LyapunovCode.NOT_VERIFIED, facts)


# ---- the LMI certificates ------------------------------------------------------------------


def test_lmi_causes_decided_before_any_solve():
    # no nonlinearity: nothing for a multiplier to act on
    linear = LureModel.linear(np.array([[0.5]]), np.zeros((1, 1)))
    assert zames_falb_certificate(linear).cause is LMICause.NO_NONLINEARITY
    # F = A - L C with an eigenvalue 1.2: proved unstable before any LMI
    unstable = LureModel.linear(np.array([[1.2]]), np.zeros((1, 1)))
    cert = circle_certificate(unstable)
    assert cert.code is LMICode.DECIDED_BEFORE and cert.cause is LMICause.ERROR_MATRIX_UNSTABLE
    assert cert.verdict is Verdict.FAILS and cert.facts["channels"] == 0
    assert cert.facts["decision"] == cert.details["exact_decision"]["reason"]


def test_every_lmi_cause_has_words_and_notes_follow_them():
    facts = {
        "refusal": "the full LMI needs about 3 GiB",
        "decision": "DECISION",
        "channels": 2,
        "radius": 1.0 + 1e-13,
        "q": 0.5,
        "corner": {
            "gains": [0.0, 0.5],
            "spectral_radius": 1.25,
            "corners": 4,
            "unstable_corners": 1,
        },
        "attempts": [{"structure": "full", "status": "infeasible", "order": 1}],
        "order": 2,
        "status": "infeasible",
        "problem": VerifyProblem(VerifyCode.CHOLESKY_FAILED),
    }
    for cause in LMICause:
        words = lmi_messages.reason(cause, facts)
        assert bool(words) is (cause is not LMICause.CERTIFIED), cause
    assert (
        lmi_messages.reason(LMICause.REFUSED, facts)
        == "not attempted: the full LMI needs about 3 GiB"
    )
    assert "0, 0.5" in lmi_messages.reason(LMICause.CORNER_UNSTABLE, facts)
    assert "full: infeasible" in lmi_messages.reason(LMICause.CIRCLE_NOT_VERIFIED, facts)
    assert "order 1: infeasible" in lmi_messages.reason(LMICause.ZAMES_FALB_NOT_VERIFIED, facts)
    assert lmi_messages.reason(LMICause.GAIN_NOT_VERIFIED, facts).endswith(
        "gain not verified: P fails the Cholesky test"
    )
    assert "dead zone" in lmi_messages.reason(LMICause.ERROR_MATRIX_UNSTABLE, facts)
    # a loop whose computed radius is below 1 is said to be unstable by its exact decision,
    # never by a number below 1
    below = lmi_messages.reason(
        LMICause.IDENTITY_IN_SECTOR, {**facts, "radius": 0.9999999999999998}
    )
    assert "not asymptotically stable, proved in exact arithmetic" in below
    assert "(that loop as F: DECISION)" in below and "> 1" not in below
    estimated = lmi_messages.reason(
        LMICause.IDENTITY_IN_SECTOR, {**facts, "radius": 1.0 + 1e-9, "rigorous": False}
    )
    assert "by a floating-point estimate, not proved" in estimated
    assert "exact arithmetic" not in estimated
    assert "dead zone" not in lmi_messages.reason(
        LMICause.ERROR_MATRIX_UNSTABLE, {**facts, "channels": 0}
    )
    # a certificate's notes come after its own words, in the order they were added
    cert = LMICertificate(
        Verdict.INCONCLUSIVE,
        "circle",
        code=LMICode.NOT_VERIFIED,
        cause=LMICause.NO_BASE,
    )
    noted = cert.noted(lmi_messages.balanced_note("diag(2^3, 1)", "WHY")).noted("; LAST")
    assert noted.reason == (
        "no circle certificate to build on; in balanced state coordinates "
        "(xi = diag(2^3, 1) xi_b): WHY; LAST"
    )
    assert cert.reason == "no circle certificate to build on"
