"""Estimators: shrinkage operators, static decoders and dynamic observers.

* ``shrinkage``: soft thresholding, elastic-net and weighted shrinkage;
* ``decoders``: ISTA, FISTA, IJAM, partial Lasso and elastic net (cvxpy), l1 and l0 decoders;
* ``pruning``: the weighted l1 observer with pruned prior and successful-attack construction;
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
    L0Solution,
    elastic_net_cvxpy,
    fista,
    ijam,
    ista,
    l0_decoder,
    l1_decoder,
    partial_lasso_cvxpy,
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
from .pruning import (
    AttackVerification,
    DetectorDecision,
    FalseDataInjectionAttack,
    PrunedSupportPrior,
    WeightedL1Estimate,
    detector,
    l1_decode,
    poisson_binomial_pmf,
    prune_support_prior,
    pruned_weighted_l1_observer,
    pruned_weighted_l1_window_observer,
    reliable_safe_count,
    successful_attack,
    verify_successful_attack,
    weighted_l1_observer,
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
