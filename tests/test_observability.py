"""Observability: PBH and staircase agree; unobservable plants carry a verified direction."""

import control
import numpy as np
import pytest
from planted import planted
from scipy.linalg import block_diag

from ssecert import System, observability, observability_index
from ssecert.structure.observability import pbh_margins, unobservable_residual
from ssecert.structure.outcomes import ObservabilityCode


def test_issue_example_is_observable_though_numpy_rank_says_18():
    A = np.diag(np.linspace(0.1, 0.95, 20))
    system = System(A, np.ones((1, 20)))
    assert np.linalg.matrix_rank(system.observability_matrix()) == 18
    check = observability(system)
    assert check.verdict.value == "holds"
    assert check.fields["observability_index"] == 20
    # the margin is measured in power-of-two units (here A is doubled), see unit_normalized
    An = 2 * A
    assert check.margin == pytest.approx(
        min(
            np.linalg.svd(np.vstack([An - lam * np.eye(20), np.ones((1, 20))]), compute_uv=False)[
                -1
            ]
            for lam in np.diag(An)
        )
        / np.linalg.norm(np.vstack([An, np.ones((1, 20))]), 2),
        rel=1e-6,
    )


def test_observability_matrix_matches_python_control():
    rng = np.random.default_rng(0)
    A, C = rng.standard_normal((4, 4)), rng.standard_normal((2, 4))
    np.testing.assert_allclose(System(A, C).observability_matrix(), control.obsv(A, C))


@pytest.mark.parametrize("seed", range(40))
def test_verdict_matches_planted_truth(seed):
    pl = planted(
        np.random.default_rng(seed),
        ("distinct", "jordan", "identity", "mixed")[seed % 4],
        integer=seed % 2 == 0,
    )
    check = observability(System(pl.A, pl.C))
    assert check.verdict is check.code.verdict
    if pl.max_removable < 0 and seed % 2 == 1:
        # an orthogonal similarity rounds the planted structure away: the exact data are
        # observable within rounding of an unobservable plant, which floats cannot decide
        assert check.verdict.value in ("fails", "inconclusive")
        if check.verdict.value == "inconclusive":
            assert check.code is ObservabilityCode.WITHIN_PRECISION
            assert check.evidence["exact"]["state"] == "observable"
            assert check.evidence["distance_to_unobservability"] == check.margin
    elif pl.max_removable < 0:
        assert check.verdict.value == "fails"
        assert check.evidence["exact"]["state"] == "unobservable"
        z = np.array(check.witness["z"])
        assert unobservable_residual(pl.A, pl.C, z) < 1e-8
        assert check.fields["unobservable_dimension"] >= 1
    else:
        assert check.verdict.value == "holds"
        assert 1 <= check.fields["observability_index"] <= pl.A.shape[0]


def test_index_of_a_chain():
    A = np.diag(np.ones(3), 1)  # 4-state shift register
    assert observability_index(System(A, [[0.0, 0.0, 0.0, 1.0]])) is None  # reads a dead end
    system = System(A, np.array([[1.0, 0.0, 0.0, 0.0]]))
    assert observability_index(system) == 4
    assert observability(system).fields["observability_index"] == 4


def test_unobservable_mode_is_named():
    A = block_diag([[0.9]], [[0.5]])
    check = observability(System(A, [[1.0, 0.0]]))
    assert check.verdict.value == "fails"
    eigs = [e["eigenvalue"] for e in check.witness["unobservable_eigenvalues"]]
    assert eigs and abs(eigs[0] - 0.5) < 1e-12


def test_pbh_margins_zero_at_unobservable_eigenvalue():
    A = np.diag([0.2, 0.7])
    margins, codes = pbh_margins(A, np.array([[1.0, 0.0]]), np.array([0.2, 0.7]))
    assert codes.tolist() == [2, 0]
    assert margins[1] < 1e-15


def test_zero_output_matrix_rows_are_allowed():
    check = observability(System(np.eye(2), [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]))
    assert check.verdict.value == "holds"


def test_every_observability_code_gives_its_verdict():
    verdicts = {code: code.verdict.value for code in ObservabilityCode}
    assert verdicts == {
        ObservabilityCode.OBSERVABLE: "holds",
        ObservabilityCode.UNOBSERVABLE: "fails",
        ObservabilityCode.EXACTLY_UNOBSERVABLE: "fails",
        ObservabilityCode.WITHIN_PRECISION: "inconclusive",
        ObservabilityCode.UNDECIDED: "inconclusive",
    }
