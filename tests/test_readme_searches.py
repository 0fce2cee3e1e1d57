"""agents/shipped/README.md holds every trial of the searches behind the shipped agents
with memory, as scripts/search_table.py prints them from the shipped tune_results.json."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SEARCHES = ("ppo-memory", "sac")


def _table_module():
    spec = importlib.util.spec_from_file_location(
        "search_table", ROOT / "scripts" / "search_table.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("name", SEARCHES)
def test_the_shipped_readme_has_every_trial_of_the_search(name: str) -> None:
    doc = json.loads((ROOT / "agents" / "shipped" / name / "tune_results.json").read_text())
    table = _table_module().table(doc)
    assert len(doc["trials"]) >= 16
    assert table in (ROOT / "agents" / "shipped" / "README.md").read_text()
