"""scripts/mutants.toml stays in step with the code: every curated mutant's original text
occurs exactly once in its file (scripts/mutation.py applies it there), its replacement
differs, and the ids are unique — so a refactor that moves a mutated line fails here, not
silently in the next mutation run."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_every_mutant_applies_exactly_once() -> None:
    doc = tomllib.loads((ROOT / "scripts" / "mutants.toml").read_text())
    mutants = doc["mutant"]
    assert len(mutants) >= 50
    ids = [m["id"] for m in mutants]
    assert len(ids) == len(set(ids)), "duplicate mutant ids"
    stale = []
    for m in mutants:
        src = (ROOT / m["file"]).read_text()
        if src.count(m["original"]) != 1 or m["replacement"] == m["original"]:
            stale.append((m["id"], m["file"], src.count(m["original"])))
        tests = m["tests"]
        for t in doc["groups"][tests] if isinstance(tests, str) else tests:
            assert (ROOT / t.split("::")[0]).exists(), (m["id"], t)
    assert not stale, f"mutants whose original text is not found exactly once: {stale}"
