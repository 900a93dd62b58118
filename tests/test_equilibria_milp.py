"""Nonzero equilibria of observers with more channels than the enumeration covers (3^m > 3^10
patterns): a mixed-integer search (HiGHS) finds them, and exact arithmetic confirms them."""

import numpy as np
import pytest

from ssecert import analyze, spec_from_dict
from ssecert.observers import build_observer
from ssecert.observers.lure import LureModel
from ssecert.stability import equilibria
from ssecert.stability.outcomes import SearchCode, Searched
from ssecert.stability.search_messages import searched_text


def _planted(extra: int) -> dict:
    # the n = 1, p = 2 D-SSO that keeps a wrong estimate (tests/test_divergence.py), and `extra`
    # decoupled stable states with one sensor each: the planted equilibrium with the extra
    # states at zero (their channels in the dead zone) is an equilibrium of the whole
    n, p = 1 + extra, 2 + extra
    A = np.diag([0.9] + [0.5] * extra)
    C = np.zeros((p, n))
    C[0, 0], C[1, 0] = -0.2, 1.2
    L = np.zeros((n, p))
    L[0, 0], L[0, 1] = 1.8, 0.9
    for j in range(extra):
        C[2 + j, 1 + j] = 1.0
        L[1 + j, 2 + j] = 0.3
    return {
        "name": "planted-equilibrium",
        "system": {"A": A.tolist(), "C": C.tolist()},
        "attack": {"max_attacked": 0, "horizon": 1},
        "observer": {"kind": "dsso", "gain": L.tolist(), "step": 1.1, "threshold": 0.1},
    }


@pytest.mark.slow
def test_a_planted_equilibrium_among_3_to_the_14_patterns_is_found_and_replayed():
    cert = analyze(spec_from_dict(_planted(12)))
    check = cert["observer_stability"]
    assert check.verdict.value == "fails" and check.witness["kind"] == "nonzero equilibrium"
    assert check.witness["exact"] and check.witness["observer_replay"]["agrees"]
    assert equilibria.MAX_PATTERNS < 3**14
    signs = check.witness["active_signs"]
    assert np.count_nonzero(signs) == 1 and signs[1] != 0  # the planted channel alone
    e = np.asarray(check.witness["initial_error"])
    assert abs(abs(e[0]) - 0.31468531468531) < 1e-12 and not np.any(e[1:])


def _random_model(rng):
    n, p = rng.integers(1, 3), rng.integers(2, 5)
    A = np.round(rng.uniform(-1.2, 1.2, (n, n)), 1)
    C = rng.integers(-2, 3, (p, n)).astype(float)
    L = np.round(rng.uniform(-2, 2, (n, p)), 1)
    if max(abs(np.linalg.eigvals(A - L @ C))) >= 1:
        return None
    data = {
        "name": "r",
        "system": {"A": A.tolist(), "C": C.tolist()},
        "attack": {"max_attacked": 0, "horizon": 1},
        "observer": {"kind": "dsso", "gain": L.tolist(),
                     "step": float(np.round(rng.uniform(0.1, 2), 1)), "threshold": 0.1},
    }  # fmt: skip
    spec = spec_from_dict(data)
    return LureModel.from_design(build_observer(spec.system, spec.observer))


@pytest.mark.slow
def test_the_mixed_integer_search_agrees_with_the_enumeration():
    rng = np.random.default_rng(0)
    compared = found = 0
    while compared < 60:
        model = _random_model(rng)
        if model is None:
            continue
        enumerated = equilibria._search(model, None, first=True)[0]
        witness, note = equilibria._milp_search(model)
        assert bool(enumerated) == (witness is not None), note
        if witness is not None:
            found += 1
            point = np.concatenate([witness["initial_error"], witness["initial_attack_estimate"]])
            assert np.linalg.norm(model.simulate(point, 1)[-1] - point) <= 1e-12 * np.linalg.norm(
                point
            )
        compared += 1
    assert found >= 2


def test_the_mixed_integer_search_works_in_units_of_the_threshold():
    # the equilibria scale with the threshold (soft_threshold(c w, c lam) = c soft_threshold(w,
    # lam), the rest is linear): a threshold of 1e8 must not hide the planted equilibrium
    # behind big-M constants of 1e12
    for threshold in (1e-6, 1e8):
        data = _planted(12)
        data["observer"]["threshold"] = threshold
        spec = spec_from_dict(data)
        model = LureModel.from_design(build_observer(spec.system, spec.observer))
        witness, note = equilibria._milp_search(model)
        assert witness is not None, note
        e = np.asarray(witness["initial_error"])
        assert abs(abs(e[0]) / threshold - 3.1468531468531) < 1e-9 and not np.any(e[1:])


def test_the_mixed_integer_search_keeps_one_time_limit_for_all_its_solves(monkeypatch):
    # every candidate refused by exact arithmetic: the search goes on with what time is left,
    # and ends at its limit with the reason
    import scipy.optimize

    rng = np.random.default_rng(0)
    model = None
    while model is None:
        model = _random_model(rng)
    limits, clock = [], [0.0]

    class _Result:
        status, message = 0, "Optimal"

        def __init__(self, nv):
            self.x = np.zeros(nv)

    def solve(c, constraints, integrality, bounds, options):
        limits.append(options["time_limit"])
        clock[0] += 4.0  # each solve takes 4 s
        return _Result(c.size)

    monkeypatch.setattr(scipy.optimize, "milp", solve)
    monkeypatch.setattr(equilibria, "_confirm", lambda model, signs: None)
    monkeypatch.setattr(equilibria.time, "monotonic", lambda: clock[0])
    witness, note = equilibria._milp_search(model)
    assert witness is None
    assert limits == [10.0, 6.0, 2.0]  # 10 s in all (MILP_SECONDS), not 10 s each
    assert note.code is SearchCode.MILP_REFUSED
    assert note.facts["refused"] == 3 and note.facts["timed_out"]
    words = searched_text(note)
    assert "found 3 candidate patterns that exact arithmetic refused" in words
    assert words.endswith("refused; its time limit of 10 s ended it")


def test_every_search_record_has_words():
    facts = {
        "refusal": "R", "m": 12, "count": 531441, "most": 59049, "tried": 5, "found": 0,
        "nonzero": True, "singular": 2, "status": 1, "message": "M", "box": 1e4,
        "seconds": 10.0, "refused": 1, "timed_out": False, "samples": 64, "steps": 500,
        "period": 3, "alive": 2,
    }  # fmt: skip
    for code in SearchCode:
        for balanced in (False, True):
            words = searched_text(Searched(code, facts, balanced))
            assert words and words.endswith("(in balanced state coordinates)") is balanced
    none = searched_text(Searched(SearchCode.PATTERNS_TRIED, facts))
    assert none.startswith("none among the 531,441") and "(2 with a singular" in none
    attacked = searched_text(Searched(SearchCode.PATTERNS_TRIED, {**facts, "nonzero": False}))
    assert attacked.startswith("0 equilibria among")
