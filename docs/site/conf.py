"""Sphinx configuration of ssecert's documentation site.

    python -m pip install ".[docs]"
    sphinx-build -W --keep-going -b html docs/site docs/site/_build/html

The CLI, spec-file and certificate references are written from the code before each build
(``_generate.py``): the argparse parser, ``ssecert.schemas.spec_schema()`` and
``certificate_schema()``.
"""

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parents[1]))  # this tree's ssecert, whatever is installed

import _generate  # noqa: E402

import ssecert  # noqa: E402

_generate.write_all(HERE / "generated")

project = "ssecert"
author = "the ssecert developers"
release = version = ssecert.__version__
extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "myst_parser",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build"]
html_theme = "pydata_sphinx_theme"
html_title = f"ssecert {version}"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}
autodoc_typehints = "description"
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True}
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
myst_heading_anchors = 3
suppress_warnings = ["myst.xref_missing"]
nitpicky = False
