"""The spec itself: ``Spec``, ``load_spec`` and ``spec_from_dict``.

A file's bytes are read and parsed by ``ssecert.spec.files``, each table is
validated here (the plant, the attack bound, the observer through its kind)
and the scenarios by ``ssecert.spec.scenarios``; ``ssecert.spec`` documents
the format and re-exports the public names.
"""

from __future__ import annotations

import hashlib
import math
import os
import re
import stat
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..base.validation import (
    as_choice,
    as_float_option,
    as_real_matrix,
    describe,
)
from ..noise import DEFAULT_TRUNCATION, DISTRIBUTIONS, NORMS, MeasurementNoise, ProcessNoise
from ..observers import BUILTIN_KINDS, get_kind, observer_kinds
from ..system import System
from .files import (
    _SYSTEM_KEYS,
    MAX_BINARY_BYTES,
    MAX_TEXT_BYTES,
    _check_document,
    _parse_text,
    _read_arrays,
    unused_variables,
)
from .scenarios import read_scenarios
from .table import (
    INT64_MAX,
    MATRIX_LIMITS,
    MAX_NAME_LENGTH,
    SpecError,
    SpecTable,
    check_keys,
    check_name,
    convert,
    one_line,
    require,
    spec_error,
    spec_int,
)

__all__ = ["Spec", "load_spec", "spec_from_dict", "OBSERVER_KINDS", "MAX_HORIZON"]

MAX_HORIZON = 10_000

OBSERVER_KINDS = BUILTIN_KINDS
_TOP_KEYS = ("name", "system", "attack", "noise", "observer", "scenario")
_ATTACK_KEYS = ("max_attacked", "horizon")
_NOISE_KEYS = ("measurement", "norm", "process", "input", "distribution", "truncation")
_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")


@dataclass(frozen=True)
class Spec:
    """A validated design: plant, attack bound, optional observer and scenarios.

    Attributes
    ----------
    name : str
        Design name, used for report file names.
    system : System
    max_attacked : int
        s, the number of sensors the adversary may control.
    horizon : int
        tau, the stacked window (default n).
    observer : mapping or None
        Validated ``[observer]`` section (keys as in docs/architecture.md, "Spec files").
    scenarios : tuple of mapping
        Validated ``[[scenario]]`` sections with defaults filled in.
    noise : MeasurementNoise or None
        The ``[noise]`` section: each sensor's bound of its measurement noise.
    source : str
        File path or ``"<dict>"``.
    sha256 : str or None
        Hash of the file's bytes.
    """

    name: str
    system: System
    max_attacked: int
    horizon: int
    observer: Mapping[str, Any] | None = None
    scenarios: tuple[Mapping[str, Any], ...] = field(default=())
    noise: MeasurementNoise | None = None
    source: str = "<dict>"
    sha256: str | None = None

    def to_toml(self) -> str:
        """The spec file of this design (TOML): ``load_spec`` of it gives the same spec back
        (a design made in Python has no file of its own).

        Examples
        --------
        >>> import tomllib
        >>> from ssecert.examples import load_example
        >>> spec = load_example("ugv")
        >>> again = spec_from_dict(tomllib.loads(spec.to_toml()))
        >>> bool((again.system.C == spec.system.C).all()), again.observer == spec.observer
        (True, True)
        """
        from .write import dumps, spec_document

        return dumps(spec_document(self))


def spec_from_dict(
    data: Mapping[str, Any],
    *,
    source: str = "<dict>",
    max_attacked: int | None = None,
    horizon: int | None = None,
    sha256: str | None = None,
    default_name: str | None = None,
    noise: float | None = None,
) -> Spec:
    """Validate a spec given as a dictionary (the parsed TOML/JSON document).

    Parameters
    ----------
    data : mapping
        Top-level keys ``name``, ``system``, ``attack``, ``observer``,
        ``scenario``.
    source : str
        Name used in error messages.
    max_attacked, horizon : int, optional
        Override ``attack.max_attacked`` and ``attack.horizon``.
    noise : float, optional
        Replaces the ``[noise]`` section's measurement bound (and norm) by this bound on every
        sample of every sensor, before the scenarios without a noise of their own take it
        (``--noise``); its process noise and distribution stay.
    sha256 : str, optional
        Hash recorded in the Spec.
    default_name : str, optional
        Name used when ``name`` is absent.

    Returns
    -------
    Spec

    Raises
    ------
    SpecError
        If anything is missing, unknown, of the wrong kind or out of range.

    Examples
    --------
    >>> spec = spec_from_dict({"name": "demo", "system": {"A": [[1.0]], "C": [[1.0], [2.0]]},
    ...                        "attack": {"max_attacked": 0}})
    >>> spec.system.p, spec.horizon
    (2, 1)
    """
    check_keys(source, "", data, _TOP_KEYS)
    _check_document(source, data)
    if noise is not None:  # the measurement bound replaced, the process noise and draws kept
        kept = data.get("noise")
        others = (
            {k: v for k, v in kept.items() if k not in ("measurement", "norm")}
            if isinstance(kept, Mapping)
            else {}
        )
        data = {**data, "noise": {**others, "measurement": noise}}
    name = _spec_name(source, data.get("name", default_name))
    system = _system(source, require(source, data, "system", ""), name)
    attack_table = data.get("attack", {})
    check_keys(source, "attack", attack_table, _ATTACK_KEYS)
    s = _max_attacked(source, attack_table, max_attacked)
    tau = _horizon(source, attack_table, horizon, system.n)
    observer = None
    if "observer" in data:
        observer = _observer(source, data["observer"], system.n, system.p)
    bounds = _noise(source, data["noise"], system.n, system.p) if "noise" in data else None
    return Spec(
        name=name,
        system=system,
        max_attacked=s,
        horizon=tau,
        observer=observer,
        scenarios=read_scenarios(
            source,
            data.get("scenario", []),
            system.p,
            system.sensors,
            None if bounds is None else _per_sample(bounds, tau),
            model=bounds,
            n=system.n,
            process_input=_process_input(data.get("noise"), system.n),
        ),
        noise=bounds,
        source=source,
        sha256=sha256,
    )


def _spec_name(source: str, name: Any) -> str:
    """The spec's name, checked: it names the report files."""
    if name is None:
        raise spec_error(source, "name", "missing (required)")
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise spec_error(
            source,
            "name",
            f"expected a name of letters, digits, '.', '_' or '-' (it names the report files), "
            f"got {describe(name)}",
        )
    return check_name(source, "name", name, "the name")


def _system(source: str, table: Any, name: str) -> System:
    """The ``[system]`` table as a System: A square, C with n columns, sensors named."""
    check_keys(source, "system", table, _SYSTEM_KEYS)
    A = convert(
        source,
        "system.A",
        as_real_matrix,
        require(source, table, "A", "system"),
        "A",
        **MATRIX_LIMITS,
    )
    if A.shape[0] != A.shape[1]:
        raise spec_error(source, "system.A", f"expected a square matrix, got shape {A.shape}")
    C = convert(
        source,
        "system.C",
        as_real_matrix,
        require(source, table, "C", "system"),
        "C",
        shape=(None, A.shape[0]),
        shape_hint="the number of states, from A",
        **MATRIX_LIMITS,
    )
    sensors = table.get("sensors")
    _check_sensor_names(source, sensors, C.shape[0])
    try:
        return System(A, C, sensors=sensors, name=name)
    except (TypeError, ValueError) as exc:
        raise spec_error(source, "system.sensors", str(exc)) from None


def _check_sensor_names(source: str, sensors: Any, p: int) -> None:
    """Refuse a sensor name over ``MAX_NAME_LENGTH`` in a list of the right length.

    Lists of another length, and names that are not strings, are left to
    ``System``, which says what is wrong with them.
    """
    if isinstance(sensors, (list, tuple)) and len(sensors) == p:
        for i, label in enumerate(sensors):
            if isinstance(label, str) and len(label) > MAX_NAME_LENGTH:
                raise spec_error(
                    source,
                    "system.sensors",
                    f"sensors[{i}] has {len(label):,} characters; the limit is {MAX_NAME_LENGTH}",
                )


def _max_attacked(source: str, attack_table: Any, max_attacked: int | None) -> int:
    """s: from ``--max-attacked`` when given, else the required ``attack.max_attacked``."""
    if max_attacked is not None:
        return convert(
            source,
            "--max-attacked",
            spec_int,
            max_attacked,
            "max_attacked",
            min_value=0,
            max_value=INT64_MAX,
        )
    if "max_attacked" in attack_table:
        return convert(
            source,
            "attack.max_attacked",
            spec_int,
            attack_table["max_attacked"],
            "max_attacked",
            min_value=0,
        )
    raise spec_error(
        source,
        "attack.max_attacked",
        "missing (required): the number of attacked sensors s; or pass --max-attacked",
    )


def _horizon(source: str, attack_table: Any, horizon: int | None, n: int) -> int:
    """tau: from ``--horizon`` when given, else ``attack.horizon``, else n."""
    if horizon is not None:
        return convert(
            source, "--horizon", spec_int, horizon, "horizon", min_value=1, max_value=MAX_HORIZON
        )
    if "horizon" in attack_table:
        return convert(
            source,
            "attack.horizon",
            spec_int,
            attack_table["horizon"],
            "horizon",
            min_value=1,
            max_value=MAX_HORIZON,
        )
    return n


def _per_sample(noise: MeasurementNoise, horizon: int) -> list[float]:
    """The bound on each sample that keeps within ``noise``: its own for a per-sample bound, a
    window's 2-norm bound over the square root of the horizon's samples."""
    eta = noise.eta if noise.per_sample else noise.eta / math.sqrt(horizon)
    return [float(v) for v in eta]


def _process_input(table: Any, n: int) -> Any:
    """The ``[noise]`` section's ``input`` (read by ``_noise`` already), for the scenarios' own
    process noise also where the section's is zero (and so none)."""
    if isinstance(table, Mapping) and "input" in table:
        return ProcessNoise.input_matrix(table["input"], n)
    return None


def _noise(source: str, table: Any, n: int, p: int) -> MeasurementNoise:
    """The ``[noise]`` table: ``measurement`` (one bound or one per sensor; 0 by default where
    ``process`` is given), ``norm``, ``process`` and ``input`` (the process noise and the
    matrix it enters the state through, the identity by default), ``distribution`` and
    ``truncation`` (how simulations draw the noise)."""
    if not isinstance(table, Mapping):
        raise spec_error(source, "noise", f"expected a table, got {describe(table)}")
    check_keys(source, "noise", table, _NOISE_KEYS)
    if "process" not in table:
        measurement = require(source, table, "measurement", "noise")
    else:
        measurement = table.get("measurement", 0.0)
    if "input" in table and "process" not in table:
        raise spec_error(source, "noise.input", "input without process: give the bound of w")
    norm = convert(source, "noise.norm", as_choice, table.get("norm", "inf"), "norm", NORMS)
    process = None
    if "process" in table:
        G = convert(source, "noise.input", ProcessNoise.input_matrix, table.get("input"), n)
        process = convert(source, "noise.process", ProcessNoise.read, table["process"], G, n)
    distribution = convert(
        source,
        "noise.distribution",
        as_choice,
        table.get("distribution", "uniform"),
        "distribution",
        DISTRIBUTIONS,
    )
    if "truncation" in table and distribution != "gaussian":
        raise spec_error(
            source, "noise.truncation", 'truncation applies to distribution = "gaussian" only'
        )
    truncation = convert(
        source,
        "noise.truncation",
        as_float_option,
        table.get("truncation", DEFAULT_TRUNCATION),
        "truncation",
        min_value=0.0,
        min_inclusive=False,
    )
    return convert(
        source,
        "noise.measurement",
        MeasurementNoise.read,
        measurement,
        p,
        norm,
        process=process,
        distribution=distribution,
        truncation=truncation,
    )


def _observer(source: str, table: Any, n: int, p: int) -> dict[str, Any]:
    """The ``[observer]`` table, read by the kind it names."""
    if not isinstance(table, Mapping):
        raise spec_error(source, "observer", f"expected a table, got {describe(table)}")
    name = convert(
        source,
        "observer.kind",
        as_choice,
        require(source, table, "kind", "observer"),
        "kind",
        observer_kinds(),
    )
    kind = get_kind(name)
    reader = SpecTable(source, "observer", table)
    reader.check_keys(kind.keys)
    return {"kind": name, **kind.parse(reader, n, p)}


def load_spec(
    path: str | os.PathLike[str],
    *,
    max_attacked: int | None = None,
    horizon: int | None = None,
    source: str | None = None,
    noise: float | None = None,
) -> Spec:
    """Load and validate a spec file (.toml, .json, .npz or .mat).

    Parameters
    ----------
    path : str or path-like
    max_attacked : int, optional
        s; required for .npz and .mat files, overrides the spec otherwise.
    horizon : int, optional
        tau; overrides the spec (default n).
    noise : float, optional
        Replaces the spec's ``[noise]`` (``spec_from_dict``).
    source : str, optional
        How messages and reports name the file; default ``path`` exactly as
        given (a relative path stays relative).

    Returns
    -------
    Spec

    Raises
    ------
    SpecError
        If the file cannot be read, is larger than the limits (see the module
        documentation) or its content is invalid.
    TypeError
        If ``path`` is not a path.

    Examples
    --------
    >>> from ssecert.examples import example_path
    >>> spec = load_spec(example_path("ugv"))
    >>> spec.name, spec.system.sensors[0], spec.max_attacked
    ('ugv', 'position', 1)
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a file path (str or os.PathLike), got {describe(path)}")
    if source is None:
        source = path if isinstance(path, str) else os.fspath(path)
    source = one_line(str(source))
    path = Path(path)
    suffix = path.suffix.lower()
    raw = _read_file(path, source, suffix)
    digest = hashlib.sha256(raw).hexdigest()
    if suffix in (".npz", ".mat"):
        arrays = _read_arrays(raw, suffix, source)
        for key in ("A", "C"):
            if key not in arrays:
                raise spec_error(source, key, "missing (required variable)")
        if max_attacked is None:
            raise SpecError(
                f"{source}: a {suffix} file holds only the plant; give the number of attacked "
                f"sensors with --max-attacked (max_attacked=...)"
            )
        note = unused_variables(source, arrays)
        if note is not None:  # a note in the CLI's output (its warnings become notes)
            warnings.warn(note, UserWarning, stacklevel=2)
        data: Any = {"system": {k: arrays[k] for k in _SYSTEM_KEYS if k in arrays}}
        default = "system"
    else:
        data = _parse_text(raw, suffix, source)
        default = "spec"
    stem = re.sub(r"[^A-Za-z0-9._-]", "-", path.stem)[:MAX_NAME_LENGTH].lstrip("._-") or default
    return spec_from_dict(
        data,
        source=source,
        max_attacked=max_attacked,
        horizon=horizon,
        sha256=digest,
        default_name=stem,
        noise=noise,
    )


def _read_file(path: Path, source: str, suffix: str) -> bytes:
    """The file's bytes, refused before reading when it is not a spec file or too large."""
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise SpecError(f"{source}: no such file") from None
    except NotADirectoryError:
        raise SpecError(f"{source}: no such file (a part of the path is not a folder)") from None
    except ValueError:  # a NUL byte in the name
        raise SpecError(f"{source}: not a valid file name") from None
    except OSError as exc:
        raise SpecError(f"{source}: cannot read: {exc.strerror or exc}") from None
    if stat.S_ISDIR(info.st_mode):
        raise SpecError(f"{source}: is a directory, expected a spec file")
    if not stat.S_ISREG(info.st_mode):
        raise SpecError(
            f"{source}: not a regular file (a device, pipe or socket); expected a spec file"
        )
    if suffix not in (".toml", ".json", ".npz", ".mat"):
        raise SpecError(
            f"{source}: unknown file type {suffix or '(none)'!r}; expected .toml, .json, .npz "
            f"or .mat"
        )
    limit = MAX_TEXT_BYTES if suffix in (".toml", ".json") else MAX_BINARY_BYTES
    kind = "TOML and JSON specs" if suffix in (".toml", ".json") else ".npz and .mat files"
    if info.st_size > limit:
        raise SpecError(
            f"{source}: the file has {info.st_size:,} bytes "
            f"({info.st_size / 2**20:.1f} MiB); {kind} are limited to "
            f"{limit // 2**20} MiB ({limit:,} bytes)"
        )
    try:
        with open(path, "rb") as handle:
            raw = handle.read(limit + 1)
    except OSError as exc:
        raise SpecError(f"{source}: cannot read: {exc.strerror or exc}") from None
    if len(raw) > limit:  # grew since stat
        raise SpecError(
            f"{source}: the file has more than {limit:,} bytes; {kind} are "
            f"limited to {limit // 2**20} MiB"
        )
    if not raw.strip():
        raise SpecError(
            f"{source}: the file is empty; expected a spec (see 'ssecert examples ugv' for one)"
        )
    return raw
