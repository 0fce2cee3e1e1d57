#!/usr/bin/env python
"""What each entrant of a headline run cost: worker time per entrant and per seed.

    python scripts/headline_cost.py [docs/benchmark/headline.json]

Reads ``settings.tasks`` (one task per entrant × condition: its wall time on its worker, its
seeds, control steps of all rows and of the runs themselves) and prints a Markdown table:
per entrant the seeds it flew, the worker-minutes of its four tasks, the worker-seconds per
seed (all conditions and families) and that per-seed cost relative to ``lqr``'s, the share
of its control steps spent by idle rows (the schedule's tail), and its share of all worker
time (:func:`agents.evaluation.capacity_benchmark.cost_table`; ``scripts/headline.py`` writes
it to ``docs/benchmark/cost.md``, and the README's table under "The run behind the table" is
that file: ``tests/test_readme_headline.py``).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from agents.evaluation.capacity_benchmark import cost_table  # noqa: E402

DOC = ROOT / "docs" / "benchmark" / "headline.json"


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    path = Path(args[0]) if args else DOC
    print(cost_table(json.loads(path.read_text())), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
