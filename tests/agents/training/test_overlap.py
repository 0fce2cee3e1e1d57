"""PPO with each update on a learner process (the option ``overlap_updates``,
agents/training/overlap.py): the learner's update is Stable-Baselines3's ``PPO.train`` bit
for bit, a seed reproduces a run, a checkpoint holds every update of the rollouts before it
without changing the run, and a learner that fails is an error in the trainer."""

from __future__ import annotations

import io
import json
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("stable_baselines3")

import torch as th  # noqa: E402
from stable_baselines3 import PPO  # noqa: E402
from stable_baselines3.common.callbacks import BaseCallback  # noqa: E402
from stable_baselines3.common.vec_env import VecNormalize  # noqa: E402

from agents.cli import train as cli  # noqa: E402
from agents.training import experiment  # noqa: E402
from agents.training.overlap import LearnerError, OverlappedPPO  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
N_ENVS = 2
ROLLOUT = 256 * N_ENVS  # the tiny preset's n_steps × the envs
SEED = 7


def _cfg(tmp_path: Path, *more: str) -> dict:
    return cli.resolve_config(
        ["--preset", "tiny", "--n-envs", str(N_ENVS), "--seed", str(SEED), "--out"]
        + [str(tmp_path / "run"), "--no-eval", "--no-progress", "--overlap-updates", *more]
    )


def _model(cfg: dict) -> OverlappedPPO:
    env = experiment.make_vec_env(experiment.env_config(cfg), N_ENVS, SEED, "native")
    env = VecNormalize(env, norm_obs=True, norm_reward=cfg["norm_reward"], gamma=cfg["gamma"])
    model = experiment.build_model(cfg, env, None)
    assert type(model) is OverlappedPPO
    return model


def _state(model: PPO) -> dict[str, th.Tensor]:
    return {k: v.clone() for k, v in model.policy.state_dict().items()}


def _assert_same(a: dict[str, th.Tensor], b: dict[str, th.Tensor]) -> None:
    assert a.keys() == b.keys()
    for k in a:
        assert th.equal(a[k], b[k]), k


_ONE_ROLLOUT = """
import io, json, sys
import agents.training  # pins the CPU numerics before torch is imported (numerics.py)
import numpy as np, torch
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import VecNormalize
from agents.cli import train as cli
from agents.training import experiment
args, mode, out, n_envs, seed, steps = json.loads(sys.argv[1])
torch.set_num_threads(1)  # as train() runs
cfg = cli.resolve_config(args)
env = experiment.make_vec_env(experiment.env_config(cfg), n_envs, seed, "native")
env = VecNormalize(env, norm_obs=True, norm_reward=cfg["norm_reward"], gamma=cfg["gamma"])
model = experiment.build_model(cfg, env, None)
if mode == "plain":  # the same model as Stable-Baselines3's own PPO
    buf = io.BytesIO()
    model.save(buf)
    buf.seek(0)
    model = PPO.load(buf, env=env, device="cpu")
assert type(model).__name__ == ("PPO" if mode == "plain" else "OverlappedPPO")
model.set_random_seed(seed)
np.random.random(3)  # the generator moved on from the seed's state (the learner's own)
model.learn(steps)
torch.save({"policy": model.policy.state_dict(), "optim": model.policy.optimizer.state_dict(),
            "rng": torch.as_tensor(np.random.get_state()[1].astype(np.int64)),
            "n_updates": model._n_updates}, out)
"""


def _one_rollout(tmp_path: Path, mode: str) -> dict:
    """One rollout and its update in a fresh process (numerics pinned as in train.py)."""
    out = tmp_path / f"{mode}.pt"
    args = ["--preset", "tiny", "--n-envs", str(N_ENVS), "--seed", str(SEED), "--no-eval"]
    arg = json.dumps([[*args, "--overlap-updates"], mode, str(out), N_ENVS, SEED, ROLLOUT])
    proc = subprocess.run(
        [sys.executable, "-c", _ONE_ROLLOUT, arg], cwd=ROOT, capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return th.load(out)


def test_the_learners_update_is_ppos_own_bit_for_bit(tmp_path: Path) -> None:
    """One rollout: no lag yet, so the overlapped run and Stable-Baselines3's PPO (the same
    model, env and random states) must end with the same weights and Adam state — the
    rollout, the progress, and the mini-batch permutations' random state all reach the
    learner as PPO.train would see them — and the trainer's generator must advance as
    PPO.train's own draws advance it."""
    over, plain = _one_rollout(tmp_path, "overlap"), _one_rollout(tmp_path, "plain")
    assert over["n_updates"] == plain["n_updates"] == 2  # the tiny preset's n_epochs
    _assert_same(over["policy"], plain["policy"])
    for i, s in plain["optim"]["state"].items():
        for key, v in s.items():
            assert th.equal(over["optim"]["state"][i][key], v), (i, key)
    assert th.equal(over["rng"], plain["rng"])
    init = _state(_model(_cfg(tmp_path)))  # the weights before: the update did change them
    assert any(not th.equal(init[k], v) for k, v in plain["policy"].items())


def test_a_seed_reproduces_an_overlapped_run_and_the_lag_is_real(tmp_path: Path) -> None:
    cfg = _cfg(tmp_path)
    runs = []
    for _ in range(2):
        m = _model(cfg)
        m.set_random_seed(SEED)
        m.learn(3 * ROLLOUT)
        assert m._n_updates == 3 * cfg["n_epochs"]  # every rollout's update is in the model
        runs.append(_state(m))
    _assert_same(runs[0], runs[1])
    plain = PPO.load(_saved(_model(cfg)), env=_model(cfg).get_env(), device="cpu")
    plain.set_random_seed(SEED)
    plain.learn(3 * ROLLOUT)  # rollouts 2 and 3 collected by newer policies than overlapped
    assert any(not th.equal(runs[0][k], v) for k, v in _state(plain).items())


def _saved(model: PPO) -> io.BytesIO:
    buf = io.BytesIO()
    model.save(buf)
    buf.seek(0)
    return buf


def _policy_of(path: Path) -> dict[str, th.Tensor]:
    return _state(PPO.load(str(path), device="cpu"))


def test_a_checkpoint_holds_every_update_before_it_and_does_not_change_the_run(
    tmp_path: Path,
) -> None:
    """A checkpoint at the start of rollout 3 holds the updates of rollouts 1 and 2 (what a
    run of two rollouts ends with), though the learner was still updating rollout 2 when
    it was written; and a run that wrote checkpoints ends as one that wrote none."""
    short = experiment.train(_cfg(tmp_path / "a", "--timesteps", str(2 * ROLLOUT)))
    assert short["num_timesteps"] == 2 * ROLLOUT
    two = _policy_of(tmp_path / "a" / "run" / "model.zip")
    experiment.train(
        _cfg(tmp_path / "b", "--timesteps", str(3 * ROLLOUT), "--checkpoint-freq", str(ROLLOUT))
    )
    ckpt = tmp_path / "b" / "run" / "checkpoints" / f"model_{2 * ROLLOUT}_steps.zip"
    _assert_same(_policy_of(ckpt), two)
    experiment.train(
        _cfg(tmp_path / "c", "--timesteps", str(3 * ROLLOUT), "--checkpoint-freq", "1000000")
    )
    assert not (tmp_path / "c" / "run" / "checkpoints" / ckpt.name).exists()
    _assert_same(
        _policy_of(tmp_path / "b" / "run" / "model.zip"),
        _policy_of(tmp_path / "c" / "run" / "model.zip"),
    )


def test_a_resumed_overlapped_run_overlaps_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    experiment.train(_cfg(tmp_path, "--timesteps", str(ROLLOUT)))
    seen = []
    learn = OverlappedPPO.learn

    def spy(self: OverlappedPPO, *args: object, **kwargs: object) -> OverlappedPPO:
        seen.append(type(self))
        return learn(self, *args, **kwargs)

    monkeypatch.setattr(OverlappedPPO, "learn", spy)
    log = experiment.train(_cfg(tmp_path, "--timesteps", str(2 * ROLLOUT), "--resume"))
    assert seen == [OverlappedPPO]
    assert log["num_timesteps"] == 2 * ROLLOUT and log["resumed_from"]["num_timesteps"] == ROLLOUT


class _KillLearner(BaseCallback):
    def _on_rollout_start(self) -> None:
        if self.model.num_timesteps >= 2 * ROLLOUT:
            self.model._learner.proc.kill()

    def _on_step(self) -> bool:
        return True


def test_a_learner_that_dies_is_an_error_in_the_trainer(tmp_path: Path) -> None:
    model = _model(_cfg(tmp_path))
    with pytest.raises(LearnerError, match="learner process went away"):
        model.learn(6 * ROLLOUT, callback=_KillLearner())
    assert model._learner is None  # closed: the model can be saved and learn again
    model.learn(ROLLOUT, reset_num_timesteps=True)


def test_runs_without_it_keep_plain_ppo_and_their_fingerprint(tmp_path: Path) -> None:
    cfg = cli.resolve_config(["--preset", "tiny", "--out", str(tmp_path / "r")])
    assert cfg["overlap_updates"] is False
    assert "overlap_updates" not in experiment.run_fingerprint(cfg)
    assert experiment.run_fingerprint(_cfg(tmp_path))["overlap_updates"] is True


def test_it_is_refused_for_sac_and_a_non_boolean_is_a_preset_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from agents.training.presets import PresetError, load_preset

    with pytest.raises(SystemExit):
        cli.resolve_config(["--preset", "tiny", "--overlap-updates", "--algo", "sac"])
    assert "overlap_updates" in capsys.readouterr().err
    preset = tmp_path / "p.json"
    preset.write_text(json.dumps({"overlap_updates": "yes"}))
    with pytest.raises(PresetError, match="overlap_updates"):
        load_preset(str(preset))


def test_a_learner_starts_from_a_thread_other_than_the_main_one() -> None:
    """As in a Ray Tune trial, whose function runs in a thread: SIGINT's disposition can
    only be set in the main thread, so the learner then sets its own alone."""
    import threading

    from agents.training.overlap import start_learner

    codes: list[int | None] = []

    def start_and_stop() -> None:
        learner = start_learner()
        learner.close()
        codes.append(learner.proc.exitcode)

    t = threading.Thread(target=start_and_stop)
    t.start()
    t.join(timeout=60)
    assert codes == [0]
