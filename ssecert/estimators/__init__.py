"""Estimators: shrinkage operators, static decoders and dynamic observers.

* ``shrinkage``: soft thresholding, elastic-net and weighted shrinkage;
* ``decoders``: ISTA, FISTA, IJAM, partial Lasso and elastic net (cvxpy);
* ``support_decoders``: the l1 (linear program) and l0 (support enumeration) decoders;
* ``event_triggered``: the event-triggered projected gradient decoder (ETPG) and projected
  Luenberger observer (ETPL) of Shoukry and Tabuada (2016);
* ``smt``: an exact decoder in the manner of Imhotep-SMT (SAT-proposed supports refuted by
  least-squares checks; needs the optional z3-solver, the ``smt`` extra);
* ``pruning``: the weighted l1 observer with pruned prior; ``pruning_attacks``: the
  (eps, alpha)-successful attack against it; ``power_grid``: the pruning paper's IEEE 14-bus
  experiment (Table I);
* the dynamic observers (Luenberger, online-gradient, SSO, D-SSO and elastic-net, batched)
  live in ``ssecert.observers`` and are re-exported here;
* ``sise``: sparse-input and state estimation (Kalman-like, Lasso support detection);
* ``localization``: RSS-fingerprint localization under sensor attacks.
"""

from ..observers import (
    DynamicObserver,
    LinearObserver,
    SparseSoftObserver,
    Trajectory,
    WindowSSO,
    observer_from_design,
)
from .decoders import (
    IterativeSolution,
    elastic_net_cvxpy,
    fista,
    ijam,
    ista,
    partial_lasso_cvxpy,
)
from .event_triggered import (
    ETPGSolution,
    ETPLObserver,
    RestrictedEigenvalue,
    etpg,
    etpg_condition,
)
from .localization import (
    LocalizationResult,
    LocalizationScenario,
    RSSDictionary,
    elastic_net_localization,
    localization_scenario,
    path_loss_rss,
    rss_dictionary,
)
from .power_grid import (
    PAPER_TABLE1,
    ErrorTable,
    GridExperiment,
    bdd_escaping_attack,
    ieee14_table1,
)
from .pruning import (
    DetectorDecision,
    PrunedSupportPrior,
    WeightedL1Estimate,
    detector,
    l1_decode,
    poisson_binomial_pmf,
    prune_support_prior,
    pruned_weighted_l1_observer,
    pruned_weighted_l1_window_observer,
    reliable_safe_count,
    weighted_l1_observer,
)
from .pruning_attacks import (
    AttackVerification,
    FalseDataInjectionAttack,
    successful_attack,
    verify_successful_attack,
)
from .shrinkage import (
    elastic_net_shrink,
    soft_threshold,
    weighted_soft_threshold,
)
from .sise import (
    SISE,
    LassoResult,
    OracleSISE,
    lasso_fista,
)
from .smt import SMTSolution, smt_decoder
from .support_decoders import L0Solution, l0_decoder, l1_decoder

__all__ = [
    "soft_threshold",
    "elastic_net_shrink",
    "weighted_soft_threshold",
    "DynamicObserver",
    "Trajectory",
    "LinearObserver",
    "SparseSoftObserver",
    "WindowSSO",
    "observer_from_design",
    "IterativeSolution",
    "L0Solution",
    "partial_lasso_cvxpy",
    "elastic_net_cvxpy",
    "ista",
    "fista",
    "ijam",
    "l1_decoder",
    "l0_decoder",
    "etpg",
    "ETPGSolution",
    "etpg_condition",
    "RestrictedEigenvalue",
    "ETPLObserver",
    "smt_decoder",
    "SMTSolution",
    "l1_decode",
    "DetectorDecision",
    "detector",
    "poisson_binomial_pmf",
    "reliable_safe_count",
    "PrunedSupportPrior",
    "prune_support_prior",
    "WeightedL1Estimate",
    "weighted_l1_observer",
    "pruned_weighted_l1_observer",
    "pruned_weighted_l1_window_observer",
    "FalseDataInjectionAttack",
    "successful_attack",
    "AttackVerification",
    "verify_successful_attack",
    "ErrorTable",
    "PAPER_TABLE1",
    "bdd_escaping_attack",
    "GridExperiment",
    "ieee14_table1",
    "LassoResult",
    "lasso_fista",
    "SISE",
    "OracleSISE",
    "path_loss_rss",
    "RSSDictionary",
    "rss_dictionary",
    "LocalizationScenario",
    "localization_scenario",
    "LocalizationResult",
    "elastic_net_localization",
]
