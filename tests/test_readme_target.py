"""The README's target table (issue "Controllers that set the bar", point 6) and comfort
table are the files the scripts wrote (``scripts/target_check.py``:
docs/benchmark/target/target.md; ``scripts/comfort_compare.py``:
docs/benchmark/comfort/comfort.md), and target.json says what the README concludes."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET = ROOT / "docs" / "benchmark" / "target"
COMFORT = ROOT / "docs" / "benchmark" / "comfort"


def test_readme_has_the_target_and_comfort_tables_as_written() -> None:
    readme = (ROOT / "README.md").read_text()
    assert (TARGET / "target.md").read_text() in readme
    assert (COMFORT / "comfort.md").read_text() in readme


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
