"""Publish a finished capacity run as the project's headline: its report and figures into
``docs/benchmark/``, its cost table (``cost.md``) and the README's headline block
(between ``<!-- headline:start -->`` and ``<!-- headline:end -->``: the
:func:`~agents.evaluation.capacity_report.readme_block` of its headline.json).

A source is validated whole before anything is touched (:func:`check_source`): every file,
the four paper conditions, the figures, and that the README block and the cost table can
be made from it; then everything is staged and moved in with signals held back
(:func:`agents.evaluation.outputs.publish_report`), the README last.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

from agents.evaluation.capacity_report import cost_table, readme_block
from agents.evaluation.outputs import atomic_write_text, publish_report

START, END = "<!-- headline:start -->", "<!-- headline:end -->"
FILES = ("headline.md", "headline.json", "headline.csv")


class PublishError(ValueError):
    """A source that cannot be published (the message names the file and the problem)."""


def readme_text(readme: Path, doc: dict[str, Any]) -> str:
    """README.md with its headline block replaced by :func:`readme_block` of ``doc``."""
    text = readme.read_text()
    if START not in text or END not in text:
        raise PublishError(f"{readme}: no {START} … {END} block")
    head, rest = text.split(START, 1)
    _, tail = rest.split(END, 1)
    return head + START + "\n" + readme_block(doc) + END + tail


def check_source(src: Path, allow_partial: bool = False) -> dict[str, Any]:
    """The source's headline.json, after checking that every file is there, that it
    covers the four paper conditions and that the README block, the cost table and the
    figures can be made from it (``PublishError`` naming the file and the problem
    otherwise; nothing in docs/ or README.md is touched)."""
    from hyperloop_env.scenarios import PAPER_SCENARIOS

    for name in FILES:
        if not (src / name).is_file():
            raise PublishError(
                f"{src / name}: missing; not a finished `hyperloop capacity` "
                "run (docs/benchmark left as it was)"
            )
    f = src / "headline.json"
    try:
        doc = json.loads(f.read_text())
        conds = doc["settings"]["conditions"]
        doc["headline"]["capacities"]
    except (ValueError, KeyError, TypeError) as exc:
        raise PublishError(f"{f}: not a capacity headline ({exc!r})") from None
    if not allow_partial and sorted(conds) != sorted(PAPER_SCENARIOS):
        raise PublishError(
            f"{f}: covers {conds}, not the four paper "
            "conditions; pass --allow-partial to publish it anyway"
        )
    if not (src / "figures").is_dir() or not any((src / "figures").glob("*.png")):
        raise PublishError(f"{src / 'figures'}: no figures (docs/benchmark left as it was)")
    try:
        readme_block(doc)
        if doc["settings"].get("tasks"):
            cost_table(doc)
    except (ValueError, KeyError, TypeError, IndexError, AttributeError) as exc:
        raise PublishError(
            f"{f}: incomplete, the README block or the cost table cannot be made from it "
            f"({type(exc).__name__}: {exc}); docs/benchmark left as it was"
        ) from None
    return doc


def publish(
    src: Path,
    doc: dict[str, Any],
    docs: Path,
    readme_file: Path,
    package_data: Path | None = None,
) -> None:
    """Copy the report into ``docs``, write the published data that ``hyperloop score``
    pairs with (``package_data``: the file of
    :data:`agents.evaluation.published.PUBLISHED_FILE` in the checkout; None: not written)
    and update the headline block of ``readme_file``. Everything is made first (the staged
    files, the cost table, the published data, the new README); then the files are moved
    in with SIGINT and SIGTERM held back, the README last."""
    from agents.evaluation.published import compact

    docs.mkdir(parents=True, exist_ok=True)
    readme = readme_text(readme_file, doc)
    data = None if package_data is None else json.dumps(compact(doc), indent=0, sort_keys=True)
    names = ["figures", *(["cost.md"] if doc["settings"].get("tasks") else []), *FILES]
    with publish_report(docs, names) as staging:
        for name in FILES:
            shutil.copy2(src / name, staging / name)
        (staging / "figures").mkdir()
        for png in sorted((src / "figures").glob("*.png")):
            shutil.copy2(png, staging / "figures" / png.name)
        if "cost.md" in names:  # what each entrant cost (README, "The run behind")
            (staging / "cost.md").write_text(cost_table(doc))
    if package_data is not None and data is not None:
        atomic_write_text(package_data, data + "\n")
    atomic_write_text(readme_file, readme)
