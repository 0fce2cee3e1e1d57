#!/usr/bin/env python
"""Every trial of a Ray Tune search as a markdown table (for agents/shipped/README.md).

    python scripts/search_table.py agents/shipped/ppo-memory/tune_results.json

One row per trial: its configuration (the search space's keys), the validation score
(mean over the paper conditions of ln(paired roughness capacity ratio against LQR)), the
ratio per condition and the training time; the chosen trial in bold.
``tests/test_readme_searches.py`` checks that the shipped agents' README holds these tables.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

SHORT = {
    "gap_weight": "gap",
    "guidance_weight": "guidance",
    "comfort_weight": "comfort",
    "current_weight": "current",
    "learning_rate": "lr",
    "n_steps": "n_steps",
    "ent_coef": "ent_coef",
    "width": "width",
    "observation": "memory",
}


def _cell(key: str, v: Any) -> str:
    if key == "learning_rate":
        return f"{v:.1e}"
    if isinstance(v, float):
        return f"{v:.3g}" if key != "ent_coef" else f"{v:g}"
    return str(v)


def table(doc: dict[str, Any]) -> str:
    keys = list(doc["search_space"])
    best = doc["best"]["index"]
    head = [
        "#",
        *(SHORT.get(k, k) for k in keys),
        "score",
        "ratio / LQR per condition",
        "train [s]",
    ]
    lines = ["| " + " | ".join(head) + " |", "|" + "---:|" * len(head)]
    for t in doc["trials"]:
        conds = (t.get("details") or {}).get("conditions") or {}
        ratios = ", ".join(
            f"{c['ratio']:.3f}" if c.get("ratio") is not None else "—" for c in conds.values()
        )
        score = t["score"]
        s = f"{score:.4f}" if math.isfinite(score) else (t["error"] or "not scored")
        train = f"{t['train_s']:.0f}" if t.get("train_s") is not None else "—"
        row = [str(t["index"]), *(_cell(k, t[k]) for k in keys), s, ratios or "—", train]
        if t["index"] == best:
            row = [f"**{c}**" for c in row]
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    sys.stdout.write(table(json.loads(Path(args[0]).read_text())))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
