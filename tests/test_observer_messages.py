"""The words of the observer checks (``ssecert.stability.observer_messages``): each sentence
from the outcome or the numbers it is written from.

The checks' tests read codes and numbers (``Check.code``, ``value``, ``fields``,
``evidence``); the sentences those stand for are checked here, once.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from ssecert.stability import observer_messages, spectral_messages
from ssecert.stability.lyapunov import lyapunov_certificate
from ssecert.stability.outcomes import WitnessKind


def test_a_gain_s_summary_names_the_error_matrix_it_decides_on():
    cert = lyapunov_certificate(np.array([[0.5, 0.1], [0.0, 0.25]]))
    words = observer_messages.linear_gain_summary(cert, "A (I - step S' S)^100", zero=False)
    assert words.startswith("The linear error dynamics e+ = (A (I - step S' S)^100) e are stable")
    assert "certified by a Lyapunov matrix P" in words
    zero = observer_messages.linear_gain_summary(cert, "A - L C", zero=True)
    assert "its floats are the zero matrix, computed spectral radius 0" in zero
    unstable = lyapunov_certificate(np.array([[2.0]]))
    words = observer_messages.linear_gain_summary(unstable, "A - L C", zero=False)
    assert words.startswith("A - L C is not stable: ")
    assert words.endswith("With this gain the error does not vanish even without attack.")


def test_an_exact_bound_below_one_is_written_with_its_gap():
    # F = 1 - 1e-17 exactly: its float is 1.0, the words keep the gap
    assert spectral_messages.below_one(1.0, 1e-17) == "1 - 1e-17 < 1"


def test_certificates_found_in_balanced_coordinates_say_so():
    scaling = [2.0**47, 2.0**-23]
    lyapunov = observer_messages.balanced_lyapunov_note({"state_scaling": scaling})
    assert lyapunov == (
        " P was found and verified in balanced state coordinates e = diag(2^47, 2^-23) e_b "
        "(the states' units differ widely) and written back exactly."
    )
    assert observer_messages.balanced_lyapunov_note({}) == ""
    assert observer_messages.balanced_lyapunov_note(None) == ""
    lmi = observer_messages.balanced_lmi_note(scaling)
    assert lmi.startswith(" The LMI was solved and verified in balanced coordinates xi = diag(")
    assert observer_messages.balanced_lmi_note(None) == ""
    sensors = observer_messages.balanced_lmi_note(scaling, -29)
    assert "sensors' units" in sensors and "states' units" not in sensors


def test_a_deadbeat_gain_s_words_give_its_exact_index():
    details = {
        "nilpotency_index": 1,
        "spectral_radius_upper_bound": 0.0,
        "relative_power_norms": [2.2e-16, 0.0],
        "exactly_nilpotent": True,
        "exact_nilpotency_index": 2,
    }
    assert observer_messages.nilpotent_summary(details) == (
        "A - L C with the printed L is exactly nilpotent with index 2: the error vanishes in 2 "
        "steps without attack (to rounding already in 1: ||(A - L C)^1|| <= 2.2e-16 ||A||^1)."
    )
    rounded = {**details, "exactly_nilpotent": False, "observability_index": 1, "minimal": True}
    words = observer_messages.nilpotent_summary(rounded)
    assert "the error vanishes to rounding in 1 step without attack, the observability index" in (
        words
    )
    failure = observer_messages.deadbeat_failure("|tr F^3| / 3 > 1 exactly")
    assert failure.startswith("The deadbeat construction's printed gain is not deadbeat: ")
    assert "Rounding L to floats destroys the nilpotency" in failure
    assert observer_messages.exact_deadbeat_note(3) == (
        " In exact arithmetic the rational gain L_exact (evidence) is nilpotent with index 3."
    )
    assert observer_messages.exact_deadbeat_note(None) == ""


@pytest.mark.parametrize("replayed", [False, True])
def test_a_repelling_equilibrium_says_so_and_why_its_replay_drifts(replayed):
    witness = {
        "kind": WitnessKind.NONZERO_EQUILIBRIUM,
        "initial_error": np.array([0.25]),
        "active_signs": np.array([1, 0, -1]),
        "repelling": True,
        "local_loop_moduli": [1.76, 0.3],
        "observer_replay": {
            "replayed": replayed,
            "agrees": False,
            "largest_drift": 0.00123,
            "steps": 50,
        },
    }
    words = observer_messages.failure_summary(witness)
    assert "it has a nonzero equilibrium, confirmed in exact arithmetic" in words
    assert "(active soft-threshold channels [0, 2])" in words
    assert " It is repelling: the linear part of the error's map near it has eigenvalues of " in (
        words
    )
    assert "modulus 1.76 > 1" in words
    drifted = "drifted off it by 0.0012 in 50 steps."
    assert words.endswith(drifted) == replayed
    quiet = observer_messages.failure_summary({**witness, "repelling": False})
    assert quiet.endswith("the equilibrium is shown in exact arithmetic only.") == replayed


def test_constant_attacks_are_named_with_their_outcome():
    records = [
        {"attack": "a", "outcome": "converges to a bias", "bias_norm": 1.234, "proved": True},
        {"attack": "b", "outcome": "converges to zero", "proved": False},
        {"attack": "c", "outcome": "converges to zero", "proved": True},
        {"attack": "d", "outcome": "converges to zero", "proved": True},
    ]
    assert observer_messages.constant_attack_text(records[:1]) == (
        "Under a constant attack, from zero error: a: converges to a bias of norm 1.23 (proved)."
    )
    assert observer_messages.constant_attack_text(records) == (
        "Under a constant attack, from zero error: a: converges to a bias of norm 1.23 "
        "(proved); b: converges to zero (observed); c: converges to zero (proved); 1 more in "
        "the evidence."
    )


def test_a_noise_search_says_how_its_gradient_ascent_took_part():
    from ssecert.stability import noise_messages

    search = {"gradient_ascent": {"starts": 8, "iterations": 1, "largest_error": 9.98}}
    assert noise_messages.ascent_text(search) == (
        "; the 8 that went furthest then moved by 1 step of projected gradient ascent"
    )
    search["gradient_ascent"]["iterations"] = 3
    assert noise_messages.ascent_text(search).endswith("by 3 steps of projected gradient ascent")
    assert noise_messages.ascent_text({"largest_error": 1.0}) == ""


def test_words_a_deadbeat_gain_beyond_the_float_range_says_so():
    # C of order 1e-310: the gain's entries scale as 1 / C; the observer_gain check's summary
    # gives this sentence ("The requested gain cannot be computed: ...")
    from ssecert.design.gains import GainError, deadbeat_gain
    from ssecert.system import System

    C = np.array([[0.9, -0.2], [0.7, 0.5], [0.8, 0.7]]) * 1e-310
    with pytest.raises(GainError, match=r"^the deadbeat gain overflows the float range \("):
        deadbeat_gain(System(np.array([[-0.4, -0.9], [1.1, -0.4]]), C))


def test_zames_falb_words_say_whether_the_certificate_holds_for_increments():
    words = observer_messages.zames_falb_summary(
        2, incremental=True, sum_bound_factor=12.5, margin=1e-3, error_bound=1e-9
    )
    assert "with a Zames-Falb multiplier of order 2 (the soft threshold is slope-restricted " in (
        words
    )
    assert "nonnegative coefficients, so the certificate also holds for increments)" in words
    assert "sum_k |xi(k)|^2 <= 12.5 |xi(0)|^2 (verified margin 0.001 against an error bound " in (
        words
    )
    odd = observer_messages.zames_falb_summary(
        1, incremental=False, sum_bound_factor=3.0, margin=1e-3, error_bound=1e-9
    )
    assert "(the soft threshold is odd and slope-restricted in [0, shrink])" in odd


def test_a_thesis_check_that_fails_says_it_does_not_apply():
    # a D-SSO with a placed gain: Assumption 3 fails by a factor above 1e300, said by its power
    # of ten
    from ssecert.observers import build_observer
    from ssecert.results import Verdict
    from ssecert.stability.thesis import thesis_assumptions
    from ssecert.system import System

    system = System(np.array([[0.9]]), np.array([[1.0], [1.0], [1.0]]))
    design = build_observer(
        system,
        {"kind": "dsso", "gain": "place", "poles": [0.5], "step": 0.5, "threshold": 0.1},
    )
    verdict, items = thesis_assumptions(design, observability_holds=True)
    words = observer_messages.thesis_summary(Verdict(verdict), items)
    assert Verdict(verdict) is Verdict.FAILS
    assert "The thesis's stability theorem therefore does not apply to this design." in words
    assert words.endswith(" Advisory: no verdict of this certificate relies on it.")
    assert re.search(r"by a factor above 1e\d{3}", words) and "e+" not in words
    held = observer_messages.thesis_summary(Verdict.HOLDS, items)
    assert held == "Every assumption of the thesis's stability proof holds on this design."


def test_words_a_window_too_large_to_build_names_its_key_and_size():
    # the observer_gain check and certify's notes give this refusal as it is
    from ssecert.budget import ResourceLimitError
    from ssecert.observers import build_observer
    from ssecert.system import System

    system = System(np.diag([0.9, 0.8]), np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]))
    observer = {"kind": "sso", "step": 0.01, "threshold": 0.1, "window": 10**6}
    with pytest.raises(ResourceLimitError) as refused:
        build_observer(system, observer)
    words = str(refused.value)
    assert words.startswith("observer.window = 1,000,000: the SSO's stacked O_tau (3,000,000 x 2)")
    assert re.search(r"needs about [\d.]+ TiB of memory, over the memory budget of 2 GiB", words)


def test_words_of_the_region_an_undecided_stability_check_reports():
    words = observer_messages.region_proved_text(1234.5678)
    assert words.startswith("What is proved: the error converges from every initial error")
    assert "||e(0)|| <= 1.23e+03 and a_hat(0) = 0 (region_of_attraction)." in words
