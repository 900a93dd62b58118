"""Design specifications: TOML (primary), JSON, NumPy .npz and MATLAB .mat.

A TOML spec (JSON has the same structure)::

    name = "ugv"
    [system]
    A = [[1.0, 0.0099], [0.0, 0.9876]]
    C = [[1, 0], [0, 1], [0, 1]]
    sensors = ["position", "velocity-a", "velocity-b"]   # optional
    [attack]
    max_attacked = 1        # s
    horizon = 2             # tau, default n
    [observer]              # optional
    kind = "dsso"
    ...
    [[scenario]]            # optional, repeatable
    name = "constant"
    attack = "constant"
    ...

``.npz`` and ``.mat`` files hold the variables ``A`` and ``C`` (and
optionally ``sensors``); s comes from ``max_attacked=`` (``--max-attacked``)
and tau from ``horizon=`` (``--horizon``, default n).  Every key is
validated and unknown keys are refused; errors name the file and the key.

Limits, checked before a file is parsed or an array is built, so that a
wrong or hostile file costs a message and not a frozen machine:

- TOML and JSON files: at most ``MAX_TEXT_BYTES`` (16 MiB: an 800 x 800
  matrix at full precision; TOML is parsed at a few MB/s and every number
  becomes a Python object), .npz and .mat files ``MAX_BINARY_BYTES``
  (256 MiB), the place for larger plants;
- every matrix: at most ``MAX_MATRIX_DIM`` (10,000) rows and columns and
  ``MAX_MATRIX_ENTRIES`` (10,000,000) entries; every list at most
  ``MAX_MATRIX_DIM`` items;
- the horizon: at most ``MAX_HORIZON`` (10,000) steps;
- integers: the 64-bit range TOML allows (-2^63 to 2^63 - 1), also in JSON;
- nesting: ``MAX_NESTING`` (16) levels of tables and lists (a spec needs 4);
- names (the spec's, sensors', scenarios'): at most ``MAX_NAME_LENGTH``
  (128) characters; no text may hold control characters or invalid Unicode.

The package's modules: ``core`` (``Spec``, ``load_spec``, ``spec_from_dict``),
``files`` (the bytes of a file and its format), ``scenarios`` (the
``[[scenario]]`` tables), ``table`` (one table's keys and values, shared with
the observer kinds) and ``write`` (a spec written back as TOML).
"""

from ..base.validation import MAX_MATRIX_DIM, MAX_MATRIX_ENTRIES
from . import core as _core
from . import files as _files
from . import scenarios as _scenarios
from .core import MAX_HORIZON, OBSERVER_KINDS, Spec, load_spec, spec_from_dict
from .files import MAX_BINARY_BYTES, MAX_NESTING, MAX_TEXT_BYTES
from .scenarios import ATTACK_KINDS, SCENARIO_DEFAULTS
from .scenarios import read_scenarios as read_scenarios
from .table import INT64_MAX as INT64_MAX
from .table import MATRIX_LIMITS as MATRIX_LIMITS
from .table import MAX_NAME_LENGTH, SpecError
from .table import SpecTable as SpecTable
from .table import check_keys as check_keys
from .table import check_name as check_name
from .table import convert as convert
from .table import one_line as one_line
from .table import require as require
from .table import spec_error as spec_error
from .table import spec_int as spec_int

#: the keys each table of a spec may hold, by table ("" the top level); the reader refuses any
#: other, and ``ssecert.schemas`` builds the spec's JSON Schema from these
TABLE_KEYS: dict[str, tuple[str, ...]] = {
    "": _core._TOP_KEYS,
    "system": _files._SYSTEM_KEYS,
    "attack": _core._ATTACK_KEYS,
    "noise": _core._NOISE_KEYS,
    "scenario": _scenarios._SCENARIO_KEYS,
}
#: the names of specs (they name the report files)
NAME_PATTERN: str = _core._NAME_RE.pattern

# the names above imported "as" themselves (the table helpers, read_scenarios) stay importable
# from here, as they were from the single module this package replaces; __all__ is the API
__all__ = [
    "Spec",
    "SpecError",
    "load_spec",
    "spec_from_dict",
    "OBSERVER_KINDS",
    "ATTACK_KINDS",
    "SCENARIO_DEFAULTS",
    "MAX_TEXT_BYTES",
    "MAX_BINARY_BYTES",
    "MAX_MATRIX_DIM",
    "MAX_MATRIX_ENTRIES",
    "MAX_HORIZON",
    "MAX_NESTING",
    "MAX_NAME_LENGTH",
    "TABLE_KEYS",
    "NAME_PATTERN",
]
