"""The comparison page's target table and comfort table (docs/comparison.md) are the
files the commands wrote (``hyperloop compare target``: docs/benchmark/target/target.md;
``hyperloop compare comfort``: docs/benchmark/comfort/comfort.md, both reproduced in
tests/agents/evaluation/test_compare.py), included as they are, and target.json says what
the page concludes."""

from __future__ import annotations

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET = ROOT / "docs" / "benchmark" / "target"
COMFORT = ROOT / "docs" / "benchmark" / "comfort"


def test_the_page_includes_the_target_and_comfort_tables_as_written() -> None:
    page = ROOT / "docs" / "comparison.md"
    text = page.read_text()
    included = {
        (page.parent / p).resolve() for p in re.findall(r"^```\{include\} (\S+)$", text, re.M)
    }
    assert {(TARGET / "target.md").resolve(), (COMFORT / "comfort.md").resolve()} <= included
    # no hand-copied rows beside the included files
    for f in (TARGET / "target.md", COMFORT / "comfort.md"):
        assert f.read_text().splitlines()[2] not in text
    doc = json.loads((TARGET / "target.json").read_text())
    best = max(doc["conditions_met"].items(), key=lambda kv: len(kv[1]))
    if doc["target_met"]:  # what the page concludes
        assert f"`{best[0]}` — PPO that also sees" in text or f"So `{best[0]}`" in text


def test_target_json_is_consistent_with_its_rows() -> None:
    doc = json.loads((TARGET / "target.json").read_text())
    per = {
        a: [r["condition"] for r in doc["rows"] if r["agent"] == a and r["meets"]]
        for a in doc["learned"]
    }
    assert per == doc["conditions_met"]
    for r in doc["rows"]:
        above = all(v["verdict"] == "A above B" for v in r["vs"].values())
        assert r["above_every_classical"] == above
        assert r["meets"] == bool(above and r["comfort_no_worse"])
    assert doc["target_met"] == (max(len(v) for v in per.values()) >= 2)
