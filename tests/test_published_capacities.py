"""The published headline reproduces: a published entrant re-flown now, on its first
evaluation seeds with the published search settings, finds the published per-seed
capacities bit for bit (the library's refactorings preserve behaviour; the same check
guards a new entrant's comparability with the published table)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from agents.evaluation import capacity_benchmark as cb
from agents.evaluation.benchmark import load_suite
from agents.evaluation.capacity import run_task

DOC = Path(__file__).resolve().parents[1] / "docs" / "benchmark" / "headline.json"


@pytest.mark.parametrize(
    ("entrant", "condition", "family"),
    [("lqr", "paper-1000-straight", "roughness"), ("pid", "paper-2000-curved", "thermal_camber")],
)
def test_published_capacities_are_reflown_bit_for_bit(
    entrant: str, condition: str, family: str
) -> None:
    doc = json.loads(DOC.read_text())
    st = doc["settings"]
    published = doc["analysis"][condition][family]["entrants"][entrant]
    seeds = published["seeds"][:2]
    (task,), _ = cb.plan(
        [entrant],
        [condition],
        [family],
        seeds,
        st["distance_km"],
        load_suite(),
        rows=st["rows"],
        ratio=st["ratio"],
        step=st["step"],
        check_above=st["check_above"],
    )
    res = run_task(type(task)(**{**task.__dict__, "sts_stride": 0}))
    got = [(s.seed, s.capacity, s.censored == "right") for s in res.searches]
    want = list(zip(seeds, published["capacity"][:2], published["censored"][:2], strict=True))
    assert got == want
