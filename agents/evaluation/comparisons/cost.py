"""What each entrant of a headline run cost (``hyperloop compare cost``): worker time per
entrant and per seed, from ``settings.tasks`` of a ``headline.json``
(:func:`agents.evaluation.capacity_report.cost_table`; ``hyperloop headline`` writes the
same table to ``docs/benchmark/cost.md``)."""

from __future__ import annotations

from pathlib import Path

from agents.evaluation.capacity_report import cost_table
from agents.evaluation.comparisons import ComparisonInputError, field, read_json


def headline_cost(path: str | Path) -> str:
    """The Markdown cost table of the headline run ``path``;
    :class:`ComparisonInputError` naming the file and the field it lacks."""
    doc = read_json(path, "a capacity run's headline.json")
    settings = field(doc, path, "settings")
    field(doc, path, "settings", "entrants")
    if not settings.get("tasks"):
        raise ComparisonInputError(
            f"{path}: no field settings.tasks (a run from before they were kept)"
        )
    for k, task in enumerate(settings["tasks"]):
        for key in ("entrant", "seeds"):
            if not isinstance(task, dict) or key not in task:
                raise ComparisonInputError(f"{path}: settings.tasks[{k}] has no {key!r}")
    try:
        return cost_table(doc)
    except (KeyError, TypeError, ZeroDivisionError) as exc:
        raise ComparisonInputError(f"{path}: not a headline run's tasks ({exc!r})") from None
