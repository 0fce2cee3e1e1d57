"""Every shipped agent flies the four paper conditions on the default track: 0 contacts
over 20 evaluation seeds × 10 km each (issue "Controllers that set the bar", point 5), on
the rollout engine (about 10 s per agent and condition here). ``ppo-guidance`` does not
(5 of 20 episodes end in lateral contact on paper-2000-curved, measured 2026-12-02): its
case is a strict xfail until the agent is retrained, so a retrained agent that flies turns
this file red until the mark is removed and agents/shipped/README.md updated."""

from __future__ import annotations

import pytest

from agents.evaluation.rollout import episode_config, run_episodes
from agents.evaluation.seeds import EVAL_SEED0
from hyperloop_env.scenarios import PAPER_SCENARIOS

SEEDS = list(range(EVAL_SEED0, EVAL_SEED0 + 20))
ACTUATORS = {"ppo": "levitation", "ppo-guidance": "levitation+guidance"}
KNOWN = {
    ("ppo-guidance", "paper-2000-curved"): "5/20 lateral contacts (first at 1.29 s), "
    "mean lateral offset 4.7 mm: to be retrained (issue 20 point 5)"
}


def _cases() -> list:
    out = []
    for name in ACTUATORS:
        for cond in PAPER_SCENARIOS:
            marks = []
            if (name, cond) in KNOWN:
                marks = [pytest.mark.xfail(reason=KNOWN[(name, cond)], strict=True)]
            out.append(pytest.param(name, cond, marks=marks, id=f"{name}-{cond}"))
    return out


@pytest.mark.slow
@pytest.mark.parametrize(("name", "condition"), _cases())
def test_shipped_agent_flies_the_paper_condition(name: str, condition: str) -> None:
    cfg = episode_config(condition, 10.0, None, {"actuators": ACTUATORS[name]})
    eps = run_episodes(name, cfg, SEEDS, 10.0, None)
    touched = [(e.seed, e.contact_kind, e.contact_time_s) for e in eps if e.terminated]
    assert not touched, f"{name} on {condition}: {len(touched)}/{len(eps)} contacts {touched}"
    assert all(e.distance_m > 9_900 for e in eps)
