"""The README's headline table is the one docs/benchmark/headline.json gives
(``python scripts/headline.py`` writes both; a hand edit of either fails here)."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _headline_script():  # noqa: ANN202
    spec = importlib.util.spec_from_file_location("headline_script", ROOT / "scripts" /
                                                  "headline.py")
    mod = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(mod)  # type: ignore[union-attr]
    return mod


def test_readme_headline_matches_the_json() -> None:
    hs = _headline_script()
    doc = json.loads((ROOT / "docs" / "benchmark" / "headline.json").read_text())
    text = (ROOT / "README.md").read_text()
    block = text.split(hs.START, 1)[1].split(hs.END, 1)[0]
    assert block.strip() == hs.readme_block(doc).strip()


def test_headline_json_is_complete() -> None:
    """Every paper condition × entrant has a roughness capacity and the suite's roughness
    levels, and the numbers are finite where a capacity was fitted."""
    doc = json.loads((ROOT / "docs" / "benchmark" / "headline.json").read_text())
    s, h = doc["settings"], doc["headline"]
    assert len(s["conditions"]) == 4 and "roughness" in s["families"]
    assert len(s["families"]) >= 3
    assert len(h["rows"]) == len(s["conditions"]) * len(s["entrants"])
    levels = s["suite"]["roughness"]["levels"]
    for row in h["rows"]:
        cap = row["capacity"]["roughness"]
        assert cap["lo"] is None or cap["theta"] is None or cap["lo"] <= cap["theta"] or (
            cap["kind"] == "upper bound")
        assert sorted(a["level"] for a in row["at_levels"]) == sorted(levels)
        for a in row["at_levels"]:
            assert 0.0 <= a["p_contact"] <= 1.0
            assert a["p_unsteady"] is None or 0.0 <= a["p_unsteady"] <= 1.0
            assert a["contact_rate_per_100km"] is None or math.isfinite(
                a["contact_rate_per_100km"])
    assert s["seed_range"][0] == 1_000_000


def test_readme_suite_table_is_the_suite_file() -> None:
    from agents.evaluation.benchmark import load_suite, suite_markdown

    text = (ROOT / "README.md").read_text()
    block = text.split("<!-- suite:start -->", 1)[1].split("<!-- suite:end -->", 1)[0]
    assert block.strip() == suite_markdown(load_suite()).strip()
