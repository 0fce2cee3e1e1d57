"""Sphinx extension: tables generated from the code at build time.

A line ``<!-- generated: NAME -->`` alone in a page's Markdown source is replaced, before
the page is parsed, by the Markdown that :data:`GENERATORS` ``[NAME]`` returns. An unknown
name fails the build.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

from sphinx.errors import ExtensionError

MARKER = re.compile(r"^<!-- generated: ([\w-]+) -->$", re.M)

GENERATORS: dict[str, Callable[[], str]] = {}


def generated(name: str) -> str:
    """The Markdown of generated block ``name``."""
    if name not in GENERATORS:
        raise ExtensionError(f"unknown generated block {name!r} (known: {sorted(GENERATORS)})")
    return GENERATORS[name]().rstrip("\n") + "\n"


def expand(text: str) -> str:
    """``text`` with every marker line replaced by its generated block."""
    return MARKER.sub(lambda m: generated(m.group(1)), text)


def _source_read(app: Any, docname: str, source: list[str]) -> None:
    source[0] = expand(source[0])


def setup(app: Any) -> dict[str, Any]:
    app.connect("source-read", _source_read)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
