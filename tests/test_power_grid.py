"""Tests of ssecert.estimators.power_grid (Table I of the pruning paper on the IEEE 14-bus system)."""

import numpy as np
import pytest

from ssecert.estimators.power_grid import (
    ANGLES,
    METHODS,
    PAPER_TABLE1,
    ErrorTable,
    bdd_escaping_attack,
    ieee14_table1,
)
from ssecert.examples import load_example

# a short run: 12-step window, the estimators and the attack from step 20, 26 steps
SHORT = {"steps": 26, "window": 12, "estimator_start": 20, "attack_start": 20}


@pytest.fixture(scope="module")
def attacked():
    return ieee14_table1(seed=3, **SHORT)


def test_the_papers_table_is_copied_in_table_is_layout():
    assert PAPER_TABLE1.angles == ANGLES == ("delta_1", "delta_2", "delta_3", "delta_4", "delta_5")
    assert PAPER_TABLE1.methods == METHODS == ("LO", "LIO", "WLIP")
    assert PAPER_TABLE1.rms.shape == PAPER_TABLE1.max_abs.shape == (5, 3)
    table = PAPER_TABLE1.to_dict()
    assert table["rms"]["LO"] == [2.5359, 2.3917, 2.6353, 2.3685, 2.6638]
    assert table["rms"]["WLIP"] == [0.00004, 0.0001, 0.0001, 0.0005, 0.0001]
    assert table["max_abs"]["LIO"] == [0.0034, 0.0016, 0.0215, 0.0063, 0.0085]
    assert table["max_abs"]["WLIP"][3] == 0.0052


def test_a_run_has_table_is_layout(attacked):
    assert isinstance(attacked.table, ErrorTable)
    assert attacked.table.rms.shape == attacked.table.max_abs.shape == (5, 3)
    assert attacked.table.methods == METHODS and attacked.table.angles == ANGLES
    assert attacked.errors.shape == (3, SHORT["steps"] + 1, 10)
    assert set(attacked.table.to_dict()) == {"rms", "max_abs"}
    # the table is the errors' metrics over every step
    angles = attacked.errors[:, :, :5]
    np.testing.assert_array_equal(attacked.table.max_abs, np.abs(angles).max(axis=1).T)
    np.testing.assert_allclose(attacked.table.rms, np.sqrt((angles**2).mean(axis=1)).T)
    assert np.all(attacked.table.rms <= attacked.table.max_abs)


def test_the_same_seed_gives_the_same_run_bit_for_bit(attacked):
    again = ieee14_table1(seed=3, **SHORT)
    np.testing.assert_array_equal(again.errors, attacked.errors)
    np.testing.assert_array_equal(again.table.rms, attacked.table.rms)
    np.testing.assert_array_equal(again.gain, attacked.gain)
    assert again.attacked == attacked.attacked
    other = ieee14_table1(seed=4, **SHORT)
    assert other.attacked != attacked.attacked
    assert not np.array_equal(other.errors, attacked.errors)


def test_with_no_attack_every_observer_is_exact():
    run = ieee14_table1(seed=1, attacked_fraction=0.0, **SHORT)
    assert all(rows == () for rows in run.attacked)
    assert run.table.max_abs[:, 0].max() <= 1e-14  # the LO starts at x(0)
    assert run.table.max_abs[:, 1:].max() <= 1e-9  # the LPs recover x to their tolerance
    # while the states they recover are not small: x(0) has entries up to 0.05
    start = SHORT["estimator_start"]
    assert np.abs(run.states[start:, :5]).max() > 1e-3


def test_under_attack_the_luenberger_observer_is_misled_and_the_l1_observers_are_not(attacked):
    lo, lio, wlip = attacked.table.max_abs.T
    assert lo.min() > 0.1
    assert lio.max() < 1e-2 * lo.min() and wlip.max() < 1e-2 * lo.min()
    # six meters a step (drawn with replacement), from the attack's start on
    counts = [len(rows) for rows in attacked.attacked]
    assert counts == [0] * SHORT["attack_start"] + [6] * (
        SHORT["steps"] + 1 - SHORT["attack_start"]
    )
    # the attack stays under the bad-data detector's threshold (0.05)
    assert attacked.detector_residual.max() <= 0.0375 * (1 + 1e-12)
    # with the code's oracle the pruned prior is right: it keeps rows with p_i > 1/2 only
    active = slice(SHORT["estimator_start"], None)
    assert np.all(attacked.pruned_precision[active] == 1.0)
    assert np.all(attacked.trusted[active] >= 10)


def test_before_the_estimators_start_their_errors_count_as_zero(attacked):
    start = SHORT["estimator_start"]
    assert not np.any(attacked.errors[1:, :start])
    assert np.any(attacked.errors[0, :start] != 0) or start == 0


def test_the_luenberger_gain_places_the_drawn_poles(attacked):
    system = load_example("ieee14").system
    F = system.A - attacked.gain @ system.C
    got = np.sort(np.linalg.eigvals(F).real)
    np.testing.assert_allclose(got, np.sort(attacked.poles), atol=1e-8)
    assert np.all((attacked.poles >= 0.1) & (attacked.poles <= 0.5))


def test_a_given_gain_replaces_the_placed_one(attacked):
    run = ieee14_table1(seed=3, gain=attacked.gain, **SHORT)
    np.testing.assert_array_equal(run.errors, attacked.errors)
    halved = ieee14_table1(seed=3, gain=attacked.gain / 2, **SHORT)
    np.testing.assert_array_equal(halved.errors[1:], attacked.errors[1:])
    assert not np.array_equal(halved.errors[0], attacked.errors[0])
    with pytest.raises(ValueError, match="gain has the wrong number of columns"):
        ieee14_table1(gain=np.zeros((10, 5)), **SHORT)


def test_the_attack_maximises_the_state_shift_within_the_detector_bound():
    C = load_example("ieee14").system.C
    U = np.linalg.svd(C)[0]
    rows = [2, 7, 11, 15]
    a = bdd_escaping_attack(C, rows, escape=0.0375, max_attack=100.0)
    assert np.all(a[np.setdiff1d(np.arange(19), rows)] == 0)
    leak = np.linalg.norm(U[:, 10:].T @ a)
    assert leak == pytest.approx(0.0375, rel=1e-12) or np.abs(a).max() == pytest.approx(100.0)
    # no other attack on those rows with the same leak shifts the estimate more
    rng = np.random.default_rng(0)
    for _ in range(50):
        b = np.zeros(19)
        b[rows] = rng.standard_normal(len(rows))
        b *= np.linalg.norm(U[:, 10:].T @ a) / np.linalg.norm(U[:, 10:].T @ b)
        shift_b = np.linalg.norm(U[:, :10].T @ b)
        if np.linalg.norm(b) <= np.linalg.norm(a):
            assert shift_b <= np.linalg.norm(U[:, :10].T @ a) * (1 + 1e-9)


def test_a_meter_drawn_twice_is_attacked_once():
    C = load_example("ieee14").system.C
    a = bdd_escaping_attack(C, [4, 4, 9], escape=0.0375, max_attack=100.0)
    assert np.count_nonzero(a) == 2
    with pytest.raises(ValueError, match="more rows than columns"):
        bdd_escaping_attack(C[:5], [0], escape=0.1, max_attack=1.0)
    with pytest.raises(ValueError, match=r"sensors\[0\] must be <= 18"):
        bdd_escaping_attack(C, [19], escape=0.1, max_attack=1.0)


def test_bad_options_are_refused():
    with pytest.raises(ValueError, match="estimator_start must be >= 19"):
        ieee14_table1(estimator_start=10)
    with pytest.raises(ValueError, match="attacked_fraction must be <= 1.0"):
        ieee14_table1(attacked_fraction=1.5)
    with pytest.raises(ValueError, match="true_rate must be < 1.0"):
        ieee14_table1(true_rate=1.0)
    with pytest.raises(TypeError, match="with_replacement must be True or False"):
        ieee14_table1(with_replacement=1)
    with pytest.raises(TypeError, match="steps must be an integer"):
        ieee14_table1(steps=10.5)


@pytest.mark.slow
def test_the_default_run_reproduces_the_luenberger_and_l1_columns():
    # seed 0, the set-up's 800 steps (about 25 s): what README's comparison reports
    run = ieee14_table1()
    paper, ours = PAPER_TABLE1, run.table
    ratio_lo = ours.rms[:, 0] / paper.rms[:, 0]
    assert np.all((ratio_lo > 0.5) & (ratio_lo < 2.0))
    assert np.all(ours.max_abs[:, 1] > 1e-4)  # the l1 observer's spikes
    assert np.argmax(ours.max_abs[:, 1]) == np.argmax(paper.max_abs[:, 1]) == 2  # at delta_3
    assert np.all(ours.max_abs[:, 2] < 1e-8)  # with omega = 0.01 and a right prior: exact


def test_table1_s_gaps_are_computed_for_both_metrics():
    # RMS LIO 3.7e-5 against the paper's 2e-4 is 82% off: the gaps the sentence gives are
    # computed for the RMS rows too, not only for the largest errors
    from dataclasses import replace

    from ssecert.estimators.power_grid import PAPER_TABLE1
    from ssecert.experiments.pruning import table1_gaps

    rms = PAPER_TABLE1.rms.copy()
    rms[1, 1] *= 0.18
    gaps = table1_gaps(replace(PAPER_TABLE1, rms=rms), PAPER_TABLE1)
    assert gaps["LIO"] == (pytest.approx(0.82), 0.0)
    assert gaps["LO"] == gaps["WLIP"] == (0.0, 0.0)
