"""``hyperloop checkpoints``: every model of a training run scored on the validation set,
the best one that flies named (agents.cli.checkpoints over
agents.training.checkpoint_scores; the scoring itself is faked here — it is
agents.training.tune.validation_score, tested on a real run in test_training.py)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from agents.cli import checkpoints as cli
from agents.training import checkpoint_scores as cs

SCORES = {1024: -0.5, 2048: 0.3, 3072: 0.1}
"""Fake validation score per step count; 2048 touches in the flight check."""
ACTUATORS_SEEN: list[str] = []


@pytest.fixture
def run_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A run with two checkpoints and a final model; the actuators LQR was scored with go
    to ``ACTUATORS_SEEN``."""
    from agents.training import tune

    run = tmp_path / "run"
    (run / "checkpoints").mkdir(parents=True)
    for n in (1024, 2048):
        (run / "checkpoints" / f"model_{n}_steps.zip").write_bytes(b"")
    (run / "model.zip").write_bytes(b"")
    log = {"num_timesteps": 3072, "algo": "ppo", "env_kwargs": {"actuators": "levitation"}}
    (run / "training_log.json").write_text(json.dumps(log))

    def capacities(controller: str, actuators: str = "levitation", **kw: Any) -> dict:
        ACTUATORS_SEEN.append(actuators)
        return {"c": {"seeds": [1], "capacity": [1.0], "censored": [False]}}

    def score(
        path: Path, actuators: str, baseline: Any = None, algo: Any = None, **kw: Any
    ) -> tuple:
        steps = 3072 if Path(path).name == "model.zip" else int(Path(path).stem.split("_")[1])
        return SCORES[steps], {"conditions": {"c": {"ratio": 1.0 + SCORES[steps]}}}

    def contacts(model: Path, actuators: str, n_seeds: int, km: float, workers: int = 1) -> dict:
        return {"c": int("2048" in Path(model).name)}

    monkeypatch.setattr(tune, "validation_capacities", capacities)
    monkeypatch.setattr(tune, "validation_score", score)
    monkeypatch.setattr(cs, "flight_contacts", contacts)
    ACTUATORS_SEEN.clear()
    return run


def test_the_best_checkpoint_is_the_best_that_flies(
    run_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert cli.main([str(run_dir), "--fly-seeds", "2", "--fly-km", "1"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[-1] == (
        f"best: 3072 steps (score 0.100); wrote {run_dir / 'checkpoint_validation.json'}"
    )
    doc = json.loads((run_dir / "checkpoint_validation.json").read_text())
    assert [(r["steps"], r["model"], r["flies"]) for r in doc["checkpoints"]] == [
        (1024, "checkpoints/model_1024_steps.zip", True),
        (2048, "checkpoints/model_2048_steps.zip", False),
        (3072, "model.zip", True),
    ]
    assert doc["best"]["steps"] == 3072 and doc["actuators"] == "levitation"
    assert doc["validation"]["flight_check"]["distance_km"] == 1.0
    assert ACTUATORS_SEEN == ["levitation"]  # the run's own, LQR scored once


def test_existing_scores_need_overwrite_and_bad_values_are_refused(
    run_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    other = tmp_path / "elsewhere.json"
    args = [str(run_dir), "--fly-seeds", "0", "--scores-file", str(other)]
    assert cli.main(args) == 0
    assert not (run_dir / "checkpoint_validation.json").exists()  # the run is untouched
    doc = json.loads(other.read_text())
    assert doc["best"]["steps"] == 2048 and doc["best"]["flies"] is None  # no flight check
    for bad, msg in (
        (args, "exists (pass --overwrite)"),
        ([str(run_dir), "--fly-seeds", "-1"], "--fly-seeds must be >= 0"),
        ([str(tmp_path / "nothing")], "no checkpoints or final model"),
    ):
        with pytest.raises(SystemExit) as exc:
            cli.main(bad)
        assert exc.value.code == 2
        assert msg in capsys.readouterr().err
    assert cli.main([*args, "--overwrite", "--min-steps", "2049", "--actuators", "levitation"]) == 0
    assert [r["steps"] for r in json.loads(other.read_text())["checkpoints"]] == [3072]


def test_checkpoints_is_a_subcommand(capsys: pytest.CaptureFixture[str]) -> None:
    from agents.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["checkpoints", "--help"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.startswith("usage: hyperloop checkpoints ")
