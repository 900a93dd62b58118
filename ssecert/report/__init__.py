"""Renderers: terminal table and JSON (HTML comes with ``ssecert certify``)."""

from .json import certificate_json, write_json
from .table import render_table

__all__ = ["certificate_json", "write_json", "render_table"]
