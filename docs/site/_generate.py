"""The reference pages written from the code: the command line (argparse), the spec file
(``ssecert.schemas.spec_schema``) and the certificate (``certificate_schema``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any


def _title(text: str, mark: str = "=") -> str:
    return f"{text}\n{mark * len(text)}\n\n"


def _literal(text: str) -> str:
    body = "\n".join(f"   {line}" if line else "" for line in text.rstrip().splitlines())
    return f"::\n\n{body}\n\n"


def cli_page() -> str:
    """Every command's ``--help``, as argparse prints it."""
    from ssecert.cli import _build_parser

    parser = _build_parser()
    out = _title("Command line")
    out += (
        "Generated from the command line's own parser: each section is what "
        "``ssecert COMMAND --help`` prints.\n\n"
    )
    out += _literal(parser.format_help())
    actions = [a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction"]
    for action in actions:
        for name, sub in action.choices.items():
            out += _title(f"ssecert {name}", "-") + _literal(sub.format_help())
    return out


def _type(schema: dict[str, Any]) -> str:
    """A short description of a schema's type for a table cell."""
    if "const" in schema:
        return f"``{json.dumps(schema['const'])}``"
    if "enum" in schema:
        return "one of " + ", ".join(f"``{json.dumps(v)}``" for v in schema["enum"])
    if "oneOf" in schema:
        kinds = list(dict.fromkeys(_type(s) for s in schema["oneOf"]))  # each once
        return " or ".join(kinds)
    kind = schema.get("type", "any")
    if kind == "array":
        items = schema.get("items", {})
        if items.get("type") == "array":
            return "matrix (list of rows of numbers)"
        if not items:
            return "list of values"
        if " or " in _type(items):
            return f"list, each {_type(items)}"
        word, _, rest = _type(items).partition(" (")
        return f"list of {word}s" + (f" ({rest}" if rest else "")
    if kind == "object":
        return "table"
    text = " or ".join(kind) if isinstance(kind, list) else str(kind)
    bounds = []
    for key, sign in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="),
                      ("exclusiveMaximum", "<")):  # fmt: skip
        if key in schema:
            bounds.append(f"{sign} {schema[key]}")
    return text + (f" ({', '.join(bounds)})" if bounds else "")


def _escape(text: str) -> str:
    """Plain text in a reST table cell (no substitutions or emphasis)."""
    return text.replace("\\", "\\\\").replace("|", "\\|").replace("*", "\\*")


def _table(properties: dict[str, Any], required: list[str]) -> str:
    rows = [("key", "type", "required", "default", "description")]
    for key, schema in properties.items():
        default = json.dumps(schema["default"]) if "default" in schema else ""
        rows.append(
            (
                f"``{key}``",
                _type(schema),
                "yes" if key in required else "",
                f"``{default}``" if default else "",
                _escape(schema.get("description", "")),
            )
        )
    out = ".. list-table::\n   :header-rows: 1\n\n"
    for row in rows:
        out += "   * - " + "\n     - ".join(cell or " " for cell in row) + "\n"
    return out + "\n"


def spec_page() -> str:
    """Every table and key of a spec file, from its JSON Schema."""
    from ssecert.schemas import spec_schema

    schema = spec_schema()
    top = schema["properties"]
    out = _title("Spec files")
    out += (
        "Generated from ``ssecert.schemas.spec_schema()``, which is built from the keys the "
        "spec reader accepts (``ssecert schema spec`` prints it). A spec is TOML or JSON with "
        "the tables below; unknown keys are refused. What a schema cannot say (finite numbers, "
        "matrix shapes that agree, poles in conjugate pairs, sensors below p) ssecert checks "
        "when it reads the spec, naming the key.\n\n"
    )
    out += _title("Top level", "-") + _table(top, schema.get("required", []))
    for name in ("system", "attack", "noise"):
        table = top[name]
        out += _title(f"[{name}]", "-") + _table(table["properties"], table.get("required", []))
    out += _title("[observer]", "-")
    out += "One table, whose ``kind`` chooses the observer and the keys it takes.\n\n"
    for branch in top["observer"]["oneOf"]:
        kind = branch["properties"]["kind"]["const"]
        properties = {k: v for k, v in branch["properties"].items() if k != "kind"}
        out += _title(f'kind = "{kind}"', "~")
        out += _table(properties, branch.get("required", [])) if properties else "No other key.\n\n"
    scenario = top["scenario"]["oneOf"][0]
    out += _title("[[scenario]]", "-")
    out += (
        "Repeatable. ``period`` is required by (and only used by) switching and sinusoidal "
        "attacks; ``none`` and ``stealthy`` take neither ``sensors`` nor ``count``.\n\n"
    )
    out += _table(scenario["properties"], scenario.get("required", []))
    return out


def certificate_page() -> str:
    """The certificate's fields, from its JSON Schema."""
    from ssecert.schemas import certificate_schema

    schema = certificate_schema()
    out = _title("Certificate JSON")
    out += (
        "Generated from ``ssecert.schemas.certificate_schema()`` (``ssecert schema "
        'certificate`` prints it). Non-finite numbers are the strings ``"Infinity"``, '
        '``"-Infinity"`` and ``"NaN"`` (strict JSON).\n\n'
    )
    properties = {k: v for k, v in schema["properties"].items() if k != "checks"}
    out += _title("The document", "-") + _table(properties, schema["required"])
    checks = schema["properties"]["checks"]
    common = checks["additionalProperties"]
    out += _title("Every check", "-") + _table(common["properties"], common["required"])
    for name, check in checks["properties"].items():
        fields = {k: v for k, v in check["properties"].items() if k not in common["properties"]}
        out += _title(name, "~") + _table(fields, check["required"])
    return out


def write_all(folder: Path) -> None:
    """Write the generated pages into ``folder`` (only those whose text changed)."""
    folder.mkdir(exist_ok=True)
    pages = {"cli.rst": cli_page(), "spec.rst": spec_page(), "certificate.rst": certificate_page()}
    for name, text in pages.items():
        path = folder / name
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
