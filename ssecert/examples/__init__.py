"""Packaged example designs.

========================  ====================================================
name                      what it is
========================  ====================================================
``ugv``                   the unmanned ground vehicle of the thesis (Sec. 6.4),
                          with its D-SSO observer and attack scenarios
``notes-example-0`` ..    Examples 0-3 of the lecture notes (Sec. 2.3.1):
``notes-example-3``       static plants (A = I) with 3 states, h = 1
``lasso-example-1``       Example 1 of the Lasso paper: one state, three equal
                          sensors, one attacked
``random-n15-p30``        a random plant like the thesis's simulations: n = 15,
                          p = 30, one eigenvalue at 1, s = 3
``ieee14``                the IEEE 14-bus system of the pruning paper's Table I:
                          five machines (rotor angles and speeds, n = 10), 19
                          meters (speeds and bus injections), s = 6
========================  ====================================================
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["example_path", "list_examples", "load_example"]


def list_examples() -> list[str]:
    """Names of the packaged examples, sorted."""
    folder = resources.files(__name__)
    return sorted(p.name[: -len(".toml")] for p in folder.iterdir() if p.name.endswith(".toml"))


def example_path(name: str) -> Path:
    """Path of a packaged example spec.

    Raises
    ------
    ValueError
        If there is no example of that name (the message lists them).

    Examples
    --------
    >>> example_path("ugv").name
    'ugv.toml'
    """
    names = list_examples()
    if name not in names:
        raise ValueError(f"no packaged example named {name!r}; available: {', '.join(names)}")
    return Path(str(resources.files(__name__).joinpath(f"{name}.toml")))


def load_example(name: str):
    """Load a packaged example as a validated Spec, named by ``name`` in reports."""
    from ..spec import load_spec

    return load_spec(example_path(name), source=name)
