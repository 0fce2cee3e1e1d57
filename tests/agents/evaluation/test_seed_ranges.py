"""A learned agent is refused on the seeds its training log records as training seeds
(agents.evaluation.seeds.recorded_training_seeds), not only on the training range: an agent
trained outside the training range (an older train.py, another tool) is not evaluated on
the episodes it was trained on. No simulation runs: the check reads the training log."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from agents.evaluation import seeds as sd

E0 = sd.EVAL_SEED0


def _agent(tmp_path: Path, log: dict[str, Any], name: str = "agent") -> Path:
    run = tmp_path / name
    run.mkdir()
    (run / "model.zip").write_bytes(b"PK")  # a model file is what makes a path learned
    (run / "training_log.json").write_text(json.dumps(log))
    return run


def test_an_agent_trained_on_evaluation_seeds_is_refused_on_them(tmp_path: Path) -> None:
    run = _agent(tmp_path, {"algo": "ppo", "seed": E0, "n_envs": 4, "resumed_from": None})
    assert sd.recorded_training_seeds(str(run)) == [(E0, E0 + 3), (E0 + 10_000, E0 + 10_003)]
    for controller in (str(run), str(run / "model.zip"), str(run / "best" / "best_model.zip")):
        with pytest.raises(ValueError, match="--allow-training-seeds") as exc:
            sd.check_evaluation_seeds(["lqr", controller], list(range(E0, E0 + 8)))
        assert f"seeds {E0}, {E0 + 1}, {E0 + 2}, …" in str(exc.value)
        assert "were training seeds of the learned agent" in str(exc.value)
    sd.check_evaluation_seeds([str(run)], list(range(E0, E0 + 8)), allow=True)
    sd.check_evaluation_seeds([str(run)], [E0 + 4, E0 + 5])  # not among its training seeds
    sd.check_evaluation_seeds(["lqr", "pid"], [E0])  # baselines are never refused


def test_the_reseed_of_an_older_resumed_run_is_among_its_training_seeds(tmp_path: Path) -> None:
    log = {"algo": "ppo", "seed": 3, "n_envs": 2, "resumed_from": {"num_timesteps": 2048}}
    run = _agent(tmp_path, log)
    r = int(np.random.SeedSequence([3, 2048]).generate_state(1)[0])  # what it re-seeded with
    assert (r, r + 1) in sd.recorded_training_seeds(str(run))
    with pytest.raises(ValueError, match="were training seeds"):
        sd.check_evaluation_seeds([str(run)], [r + 1], names=sd.API_NAMES)


def test_a_log_of_this_train_py_records_the_training_range(tmp_path: Path) -> None:
    record = {
        "range": [0, sd.TRAIN_SEED_LIMIT - 1],
        "envs": [7, 10],
        "eval_envs": [10_007, 10_010],
        "resume_envs": None,
    }
    run = _agent(tmp_path, {"seed": 7, "n_envs": 4, "training_seeds": record})
    spans = sd.recorded_training_seeds(str(run))
    assert spans == [(0, sd.TRAIN_SEED_LIMIT - 1), (7, 10), (10_007, 10_010)]
    sd.check_evaluation_seeds([str(run)], list(range(E0, E0 + 32)))  # the default seeds


def test_agents_without_a_readable_log_and_the_shipped_agents(tmp_path: Path) -> None:
    run = tmp_path / "bare"
    run.mkdir()
    (run / "model.zip").write_bytes(b"PK")
    assert sd.recorded_training_seeds(str(run)) == []
    (run / "training_log.json").write_text("{not json")
    assert sd.recorded_training_seeds(str(run)) == []
    sd.check_evaluation_seeds([str(run)], [E0])
    for name in ("ppo", "ppo+g", "sac"):  # shipped: trained below the training limit
        spans = sd.recorded_training_seeds(name)
        assert spans and all(hi < sd.TRAIN_SEED_LIMIT for _, hi in spans), name
        sd.check_evaluation_seeds([name], list(range(E0, E0 + 32)))
