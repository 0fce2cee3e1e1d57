"""Sphinx extension: the site's tables that the code defines, generated at build time.

A line ``<!-- generated: NAME -->`` alone in a page's Markdown source is replaced, before
the page is parsed, by the Markdown that ``GENERATORS[NAME]`` returns:

* ``keywords`` — the environment's keyword table, from the declarations of
  :class:`hyperloop_env.config.EnvConfig` (:func:`hyperloop_env.keywords.keyword_table`,
  the table ``help(env)`` shows, with the constructor's own keywords);
* ``scenarios`` — the named scenarios of :mod:`hyperloop_env.scenarios`;
* ``verification`` — a fresh run of the verification cases
  (:func:`hyperloop_env.verification.registry.run_all`, the table that
  ``hyperloop verify --markdown`` prints);
* ``suite`` — the benchmark suite file (:func:`agents.evaluation.benchmark.suite_markdown`);
* ``headline`` — the leaderboard from the published ``docs/benchmark/headline.json``
  (:func:`agents.evaluation.capacity_benchmark.readme_block`: the median capacities, the
  paper's P(unsteady) at the suite's levels and the paired verdicts);
* ``leaderboard`` — the published entrants and the admitted score results of
  ``docs/leaderboard/`` (:func:`agents.evaluation.leaderboard.table`);
* ``published-comfort`` — the published entrants' ride comfort that ``hyperloop score``
  pairs with (:func:`agents.evaluation.score_report.published_comfort_table`).

An unknown name fails the build. The generators import neither Sphinx nor anything but
the project, so the tests call them too (``tests/test_docs_snippets.py`` and the tests of
the pages' tables). The environment class's docstring, written for
``help()`` in Gymnasium's Markdown style, is shown on the environment page; the API
reference points there instead of rendering it as reStructuredText.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any

DOCS = Path(__file__).resolve().parents[1]
MARKER = re.compile(r"^<!-- generated: ([\w-]+) -->$", re.M)


def keywords() -> str:
    from hyperloop_env.config import EnvConfig
    from hyperloop_env.env import CONSTRUCTOR_KEYWORDS
    from hyperloop_env.keywords import keyword_table

    table = keyword_table(EnvConfig, CONSTRUCTOR_KEYWORDS)
    return table.replace("``", "`")  # the alias note is written for reStructuredText


def scenarios() -> str:
    from hyperloop_env.scenarios import SCENARIOS

    def radius(r: float) -> str:
        return "straight" if r == float("inf") else f"{r / 1000:g} km"

    rows = ["| scenario | description | speed [km/h] | curve |", "|---|---|---:|---|"]
    for name, sc in SCENARIOS.items():
        if sc.random is None:
            curve = radius(sc.curve_radius_m)
            rows.append(f"| `{name}` | {sc.description} | {sc.speed_kmh:g} | {curve} |")
        else:
            rows.append(f"| `{name}` | {sc.description} | drawn | drawn |")
    return "\n".join(rows)


@cache
def verification() -> str:
    from hyperloop_env.verification.registry import outcome, run_all
    from hyperloop_env.verification.report import markdown_table

    results = run_all()
    passed = sum(outcome(name, r) == "PASS" for name, r in results.items())
    return f"{markdown_table(results).rstrip()}\n\n({passed}/{len(results)} pass.)\n"


def suite() -> str:
    from agents.evaluation.benchmark import load_suite, suite_markdown

    return suite_markdown(load_suite())


def headline() -> str:
    from agents.evaluation.capacity_benchmark import readme_block

    doc = json.loads((DOCS / "benchmark" / "headline.json").read_text())
    return readme_block(doc)


def leaderboard() -> str:
    from agents.evaluation.leaderboard import table

    return table(DOCS / "leaderboard")


def published_comfort() -> str:
    from agents.evaluation.published import load_published, load_published_comfort
    from agents.evaluation.score_report import published_comfort_table

    return published_comfort_table(load_published_comfort(published=load_published()))


GENERATORS: dict[str, Callable[[], str]] = {
    "keywords": keywords,
    "scenarios": scenarios,
    "verification": verification,
    "suite": suite,
    "headline": headline,
    "leaderboard": leaderboard,
    "published-comfort": published_comfort,
}


def generated(name: str) -> str:
    """The Markdown of generated block ``name``."""
    if name not in GENERATORS:
        from sphinx.errors import ExtensionError

        raise ExtensionError(f"unknown generated block {name!r} (known: {sorted(GENERATORS)})")
    return GENERATORS[name]().rstrip("\n") + "\n"


def expand(text: str) -> str:
    """``text`` with every marker line replaced by its generated block."""
    return MARKER.sub(lambda m: generated(m.group(1)), text)


def _source_read(app: Any, docname: str, source: list[str]) -> None:
    source[0] = expand(source[0])


def _env_docstring(
    app: Any, what: str, name: str, obj: Any, options: Any, lines: list[str]
) -> None:
    if name == "hyperloop_env.env.HyperloopSuspensionEnv":
        lines[:] = [
            "The single environment, ``HyperloopSuspension-v0``. Its docstring, for",
            "``help(env)``, says what the :doc:`environment page </environment>` says:",
            "spaces, reward terms, episode end, rendering, keywords and ``info``.",
        ]


def setup(app: Any) -> dict[str, Any]:
    app.connect("source-read", _source_read)
    app.connect("autodoc-process-docstring", _env_docstring)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
