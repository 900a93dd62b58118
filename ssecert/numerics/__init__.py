"""Numerical building blocks of the analyses, in floating point and in exact arithmetic.

* ``exact``: exact decisions on the floats a user gives (observability of the
  exact data, stacked ranks, power-of-two scalings), re-exporting ``exact_powers``;
* ``exact_powers``: dyadic rationals and exact powers of float matrices;
* ``rational``: small dense linear algebra in exact rationals;
* ``eigen``: eigenvalues grouped into clusters with their eigenspaces;
* ``linalg``: observability staircases, sensor subspaces, batched Cholesky
  screening and stacked ranks (re-exporting ``eigen``).

The package imports none of its modules: import the one you need.
"""
