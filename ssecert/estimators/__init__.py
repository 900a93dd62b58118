"""Estimators: shrinkage operators, static decoders and dynamic observers.

* ``shrinkage``: soft thresholding, elastic-net and weighted shrinkage;
* ``decoders``: ISTA, FISTA, IJAM, partial Lasso and elastic net (cvxpy), l1 and l0 decoders;
* ``pruning``: the weighted l1 observer with pruned prior and successful-attack construction;
* ``observers``: Luenberger, online-gradient, SSO, D-SSO and elastic-net observers, batched;
* ``sise``: sparse-input and state estimation (Kalman-like, Lasso support detection);
* ``localization``: RSS-fingerprint localization under sensor attacks.
"""

from .shrinkage import (
    soft_threshold,
    elastic_net_shrink,
    weighted_soft_threshold,
)
from .base import (
    DynamicObserver,
    Trajectory,
)
from .observers import (
    LinearObserver,
    SparseSoftObserver,
    WindowSSO,
    observer_from_design,
)
from .decoders import (
    IterativeSolution,
    L0Solution,
    partial_lasso_cvxpy,
    elastic_net_cvxpy,
    ista,
    fista,
    ijam,
    l1_decoder,
    l0_decoder,
)
from .pruning import (
    l1_decode,
    DetectorDecision,
    detector,
    poisson_binomial_pmf,
    reliable_safe_count,
    PrunedSupportPrior,
    prune_support_prior,
    WeightedL1Estimate,
    weighted_l1_observer,
    pruned_weighted_l1_observer,
    pruned_weighted_l1_window_observer,
    FalseDataInjectionAttack,
    successful_attack,
    AttackVerification,
    verify_successful_attack,
)
from .sise import (
    LassoResult,
    lasso_fista,
    SISE,
    OracleSISE,
)
from .localization import (
    path_loss_rss,
    RSSDictionary,
    rss_dictionary,
    LocalizationScenario,
    localization_scenario,
    LocalizationResult,
    elastic_net_localization,
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
