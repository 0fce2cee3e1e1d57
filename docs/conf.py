"""Sphinx configuration of the documentation site (MyST Markdown, Furo theme).

Build (warnings are errors)::

    sphinx-build -W --keep-going -b html docs docs/_build/html

The tables that the code defines (environment keywords, verification cases, benchmark
suite, headline) are generated at build time by ``docs/_ext/hyperloop_docs.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(DOCS / "_ext"))

project = "hyperloop-suspension-gym"
author = "hyperloop-suspension-gym contributors"
copyright = "2026, hyperloop-suspension-gym contributors"  # noqa: A001

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinx.ext.napoleon",
    "hyperloop_docs",
]

source_suffix = {".md": "markdown"}
root_doc = "index"
# docs/benchmark/, docs/disturbances/ and docs/mutation.md are data that scripts write:
# pages include or link them, they are not pages themselves.
exclude_patterns = ["_build", "benchmark", "disturbances", "leaderboard", "mutation.md", "_ext"]

myst_enable_extensions = ["colon_fence", "dollarmath"]
myst_heading_anchors = 3

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"show-inheritance": True}
autodoc_inherit_docstrings = False  # Gymnasium's own docstrings are Gymnasium's docs

html_theme = "furo"
html_title = "hyperloop-suspension-gym"
html_static_path: list[str] = []
