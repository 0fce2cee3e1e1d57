"""Every seed a training run uses lies in the training range (agents.training.seeding):
``--seed`` outside it is refused naming the flag and the range, the envs, the evaluation
envs and the re-seed of a resumed run stay inside it, the training log records them, and
the agent is then refused on exactly those seeds, never on the evaluation seeds (tiny
preset, a few seconds)."""

from __future__ import annotations

import json
import zipfile
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("stable_baselines3")
import torch  # noqa: E402

from agents.cli import train as cli  # noqa: E402
from agents.evaluation import seeds as sd  # noqa: E402
from agents.training import experiment  # noqa: E402
from agents.training import seeding as ts  # noqa: E402
from agents.training.sb3_adapter import GymnasiumVectorToSB3  # noqa: E402

TINY = ["--preset", "tiny", "--no-eval", "--no-progress"]
LIMIT = sd.TRAIN_SEED_LIMIT

torch.set_num_threads(1)


@pytest.mark.parametrize(
    ("seed", "n_envs"),
    [(1_000_000, 4), (LIMIT, 4), (LIMIT - 1, 4), (89_999, 4), (LIMIT - 2, 200_000), (-1, 4)],
)
def test_a_seed_outside_the_training_range_is_refused(
    seed: int, n_envs: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    args = [*TINY, "--seed", str(seed), "--n-envs", str(n_envs), "--out", str(out)]
    with pytest.raises(SystemExit) as exc:
        cli.resolve_config(args)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"--seed {seed}" in err and f"[0, {LIMIT - 1}]" in err, err
    assert not out.exists()


def test_the_largest_seed_accepted_keeps_every_seed_in_range() -> None:
    # tiny: 2 evaluation episodes, so 2 evaluation envs from seed + 10 000
    top = ts.largest_seed(4, 2)
    assert top == LIMIT - ts.EVAL_SEED_OFFSET - 2
    assert cli.resolve_config([*TINY, "--seed", str(top), "--n-envs", "4"])["seed"] == top
    for n_envs in (1, 4, 16, 20_000):
        for eval_envs in (1, 4):
            top = ts.largest_seed(n_envs, eval_envs)
            for seed in (0, top):
                rec = ts.seed_record(seed, n_envs, eval_envs, resumed_at=123_456)
                spans = [rec[k] for k in ("envs", "eval_envs", "resume_envs")]
                assert all(0 <= lo <= hi < LIMIT for lo, hi in spans), (seed, n_envs, rec)


def test_resume_seeds_are_deterministic_and_inside_the_range() -> None:
    for n_envs in (1, 16, 99_999):
        got = [ts.resume_seed(7, steps, n_envs) for steps in range(0, 200_000, 997)]
        assert got == [ts.resume_seed(7, steps, n_envs) for steps in range(0, 200_000, 997)]
        assert all(0 <= r and r + n_envs - 1 < LIMIT for r in got)
    assert len({ts.resume_seed(7, steps, 16) for steps in range(0, 200_000, 997)}) > 150


@pytest.fixture
def env_seeds(monkeypatch: pytest.MonkeyPatch) -> list[tuple[int, int]]:
    """Every ``(first seed, number of envs)`` a training run gives its vector envs."""
    calls: list[tuple[int, int]] = []
    original = GymnasiumVectorToSB3.seed

    def seed(self: Any, seed: int | None = None) -> Any:
        calls.append((seed, self.num_envs))
        return original(self, seed)

    monkeypatch.setattr(GymnasiumVectorToSB3, "seed", seed)
    return calls


def test_every_seed_of_a_run_and_its_resume_stays_in_the_training_range(
    env_seeds: list[tuple[int, int]], tmp_path: Path
) -> None:
    out = tmp_path / "run"
    top = ts.largest_seed(2, 2)
    common = [*TINY, "--out", str(out), "--n-envs", "2", "--seed", str(top)]
    common += ["--checkpoint-freq", "512", "--eval-freq", "512"]
    experiment.train(cli.resolve_config([*common, "--timesteps", "512"]))
    log = experiment.train(cli.resolve_config([*common, "--timesteps", "1024", "--resume"]))
    assert log["resumed_from"]["num_timesteps"] == 512
    used = {s + i for s, n in env_seeds for i in range(n)}
    assert used and min(used) >= 0 and max(used) < LIMIT, sorted(used)[-5:]
    # the log records what was used
    rec = log["training_seeds"]
    assert rec == json.loads((out / "training_log.json").read_text())["training_seeds"]
    assert rec["range"] == [0, LIMIT - 1]
    assert rec["envs"] == [top, top + 1] and rec["eval_envs"] == [top + 10_000, top + 10_001]
    r = ts.resume_seed(top, 512, 2)
    assert rec["resume_envs"] == [r, r + 1] and (r, 2) in env_seeds
    spans = [rec[k] for k in ("envs", "eval_envs", "resume_envs")]
    assert {s for lo, hi in spans for s in range(lo, hi + 1)} == used
    # so the agent is refused on its training seeds and accepted on the evaluation seeds
    with pytest.raises(ValueError, match="--allow-training-seeds"):
        sd.check_evaluation_seeds([str(out)], [r])
    sd.check_evaluation_seeds([str(out)], list(range(sd.EVAL_SEED0, sd.EVAL_SEED0 + 64)))


def test_eval_only_refuses_an_agent_trained_on_the_evaluation_seeds(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An agent trained elsewhere on the evaluation seeds (its log says so) is not given
    the report of train.py --eval-only: exit 2, nothing written."""
    out = tmp_path / "run"
    out.mkdir()
    with zipfile.ZipFile(out / "model.zip", "w") as z:
        z.writestr("data", "{}")
    log = {"algo": "ppo", "seed": sd.EVAL_SEED0, "n_envs": 4}
    (out / "training_log.json").write_text(json.dumps(log))
    before = {f: f.read_bytes() for f in out.rglob("*") if f.is_file()}
    assert cli.main(["--preset", "tiny", "--no-progress", "--out", str(out), "--eval-only"]) == 2
    err = capsys.readouterr().err
    assert f"seeds {sd.EVAL_SEED0} were training seeds of the learned agent {out}" in err, err
    assert "--allow-training-seeds" in err
    assert {f: f.read_bytes() for f in out.rglob("*") if f.is_file()} == before
