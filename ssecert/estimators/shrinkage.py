"""Shrinkage operators (proximal maps of the l1 and elastic-net penalties).

The operators live with the observers whose nonlinearity they are
(``ssecert.observers.shrinkage``); the documents' decoders and estimators
use them from here.
"""

from ..observers.shrinkage import elastic_net_shrink, soft_threshold, weighted_soft_threshold

__all__ = ["soft_threshold", "elastic_net_shrink", "weighted_soft_threshold"]
