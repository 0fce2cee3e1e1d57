"""The safety cost of the shipped agents on the default track: none of their steps comes
within the default 2 mm safety margin of a clearance (``info["cost"]`` 0 throughout),
while a run that touches costs more than 0 (tests/env/test_safety_cost.py)."""

from __future__ import annotations

import pytest

from agents.evaluation.metrics import episode_safety_cost
from agents.evaluation.rollout import run_episodes
from hyperloop_env.config import EnvConfig

SHIPPED = [
    ("ppo", None),
    ("ppo-memory", None),
    ("sac", None),
    ("ppo-guidance", {"actuators": "levitation+guidance"}),
]


@pytest.mark.parametrize(("name", "kw"), SHIPPED, ids=[n for n, _ in SHIPPED])
def test_shipped_agents_cost_nothing_on_the_default_track(name: str, kw: dict | None) -> None:
    cfg = EnvConfig()  # the default scenario and track
    km = cfg.resolve().base.simulation.track_length_m / 1e3
    episodes = run_episodes(name, cfg.scenario, [1_000_000, 1_000_001], km, None, kw)
    assert [e.terminated for e in episodes] == [False, False]
    assert [episode_safety_cost(e) for e in episodes] == [0.0, 0.0]
