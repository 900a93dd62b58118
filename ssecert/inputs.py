"""What the top-level functions take as a design: a spec, a plant, a python-control or SciPy
system, a spec file or the name of a packaged example.

``ssecert.analyze``, ``ssecert.certify`` and ``ssecert.design`` accept any of these
(``as_spec``, ``as_system``), with the attack bound and the observer as keywords, so that a
user working in python-control writes ``ssecert.certify(sys, max_attacked=1,
observer={...})`` without a spec file.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from .system import System

__all__ = ["as_spec", "as_system"]


def as_system(design: Any) -> System:
    """The plant of a design: a ``System``, a ``Spec`` (its system), a discrete-time
    python-control ``StateSpace`` or ``scipy.signal.dlti``, or a spec file or packaged
    example (``as_spec``)."""
    if isinstance(design, System):
        return design
    from .spec import Spec

    if isinstance(design, Spec):
        return design.system
    converted = _from_library(design)
    if converted is not None:
        return converted
    return as_spec(design).system


def _from_library(design: Any) -> System | None:
    """A python-control or SciPy system as a ``System`` (None for anything else)."""
    module = type(design).__module__
    if module.startswith("control"):
        return System.from_control(design)
    if module.startswith("scipy.signal"):
        return System.from_scipy(design)
    return None


def as_spec(
    design: Any,
    *,
    max_attacked: int | None = None,
    horizon: int | None = None,
    observer: Mapping[str, Any] | None = None,
    scenarios: Sequence[Mapping[str, Any]] | None = None,
    name: str | None = None,
) -> Any:
    """A validated ``Spec`` from a design and the keywords that complete or override it.

    Parameters
    ----------
    design : Spec, System, control.StateSpace, scipy.signal.dlti, str or path
        A spec; a plant (then ``max_attacked`` is required); a discrete-time
        python-control or SciPy system (``System.from_control``,
        ``System.from_scipy``: B and D are not used); a spec file (.toml,
        .json, .npz, .mat) or the name of a packaged example.
    max_attacked, horizon : int, optional
        s and tau, overriding the spec's.
    observer : mapping, optional
        An ``[observer]`` section (``{"kind": "sso", "step": 0.2}``, ...),
        replacing the spec's.
    scenarios : sequence of mappings, optional
        ``[[scenario]]`` sections, replacing the spec's.
    name : str, optional
        The design's name (report file names).  A plant's own name (a python-control
        system's ``name``, ``System.name``) is used otherwise, written for file names: each
        run of characters other than letters, digits, '.', '_' and '-' becomes '-' ("UGV
        plant" is "UGV-plant"; "system" when nothing is left).

    Raises
    ------
    SpecError
        For a section that does not validate, naming it.
    TypeError
        For a design of another type, or a plant without ``max_attacked``.
    """
    from .base.validation import as_int_option, describe
    from .spec import Spec, spec_from_dict
    from .spec.write import spec_document

    if max_attacked is not None:
        max_attacked = as_int_option(max_attacked, "max_attacked", min_value=0)
    if horizon is not None:
        horizon = as_int_option(horizon, "horizon", min_value=1)
    if observer is not None and not isinstance(observer, Mapping):
        raise TypeError(
            "observer: expected an [observer] section as a mapping, for example "
            f'{{"kind": "luenberger", "gain": "deadbeat"}}, got {describe(observer)}'
        )
    if scenarios is not None and not isinstance(scenarios, (str, Mapping)):
        scenarios = list(scenarios)
    if scenarios is not None and (
        isinstance(scenarios, (str, Mapping))
        or not all(isinstance(scenario, Mapping) for scenario in scenarios)
    ):
        raise TypeError(
            "scenarios: expected a sequence of [[scenario]] sections, each a mapping, got "
            f"{describe(scenarios)}"
        )
    if isinstance(design, (str, os.PathLike)):
        spec = _load(os.fspath(design), max_attacked=max_attacked, horizon=horizon)
        if observer is None and scenarios is None and name is None:
            return spec
        design = spec
    if isinstance(design, Spec):
        if all(v is None for v in (max_attacked, horizon, observer, scenarios, name)):
            return design
        document = spec_document(design)
        source, sha256 = design.source, design.sha256
    else:
        system = design if isinstance(design, System) else _from_library(design)
        if system is None:
            raise TypeError(
                "design: expected a Spec, a System, a discrete-time python-control StateSpace "
                "or scipy.signal.dlti, a spec file or a packaged example name, got "
                f"{type(design).__name__}"
            )
        if max_attacked is None:
            raise TypeError(
                "max_attacked is required when the design is a plant (the number of sensors "
                "the adversary may control, s)"
            )
        document = {
            "name": _file_name(system.name),
            "system": {
                "A": system.A.tolist(),
                "C": system.C.tolist(),
                "sensors": list(system.sensors),
            },
            "attack": {"max_attacked": int(max_attacked)},
        }
        source, sha256 = "<python>", None
    if name is not None:
        document["name"] = name
    if observer is not None:
        document["observer"] = dict(observer)
    if scenarios is not None:
        document["scenario"] = [dict(scenario) for scenario in scenarios]
    spec = spec_from_dict(
        document, source=source, max_attacked=max_attacked, horizon=horizon, sha256=sha256
    )
    return spec


def _load(text: str, **overrides: Any) -> Any:
    """A spec file, or a packaged example by its name."""
    from .examples import example_path, list_examples
    from .spec import load_spec

    if not Path(text).exists() and not Path(text).suffix and text in list_examples():
        return load_spec(example_path(text), source=text, **overrides)
    return load_spec(text, **overrides)


def _file_name(name: str) -> str:
    """A plant's display name written as a spec's name, which names report files: each run of
    other characters than letters, digits, '.', '_' and '-' replaced by '-', and a first
    character a letter or a digit ("system" when none is left), at most as long as a spec's
    name may be."""
    from .spec.table import MAX_NAME_LENGTH

    written = re.sub(r"[^A-Za-z0-9._-]+", "-", name).lstrip("._-")[:MAX_NAME_LENGTH]
    return written.rstrip("-") or "system"
