"""Training residual controllers (agents/training/residual.py): the wrappers at zero
correction fly the plant as the bare base law, bit for bit (masked resets, NEXT_STEP
autoresets, the single env); SB3 sees an ordinary env; a tiny PPO and SAC run through
``train.py``'s experiment with a ``residual`` preset, whose log records the base law and
whose run builds the residual controller."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

import hyperloop_env  # noqa: E402, F401
from agents.cli import train as cli  # noqa: E402
from agents.controllers.registry import GUIDED, LEVITATION, make_controller  # noqa: E402
from agents.controllers.residual import ResidualController  # noqa: E402
from agents.training import experiment  # noqa: E402
from agents.training.residual import ResidualEnv, residual_env, residual_vec_env  # noqa: E402
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv  # noqa: E402

RECORD = {"base": "lqr-preview", "scale": 0.1}
KW = {"scenario": "paper-1000-straight", "track_length_m": 50.0}  # episodes of 180 steps


@pytest.mark.parametrize("actuators", [LEVITATION, GUIDED])
@pytest.mark.parametrize("masked", [True, False])
def test_vector_wrapper_at_zero_correction_is_the_base_law(actuators: str, masked: bool) -> None:
    """Three rows over two episodes each: the wrapper stepped with zero corrections gives
    the observations and rewards of the bare env driven by the base law, bit for bit, when
    the ended rows are reset by a masked reset (the SB3 adapter) and when the env resets
    them itself on the next step (NEXT_STEP autoreset)."""
    n = 3
    bare = HyperloopSuspensionVectorEnv(n, actuators=actuators, **KW)
    wrapped = residual_vec_env(HyperloopSuspensionVectorEnv(n, actuators=actuators, **KW), RECORD)
    base = make_controller("lqr-preview", bare)
    base.reset_batch(np.ones(n, dtype=bool))
    o1, _ = bare.reset(seed=5)
    o2, _ = wrapped.reset(seed=5)
    restart = np.zeros(n, dtype=bool)
    ends = 0
    for k in range(400):
        a = base.act_batch(o1)
        o1, r1, t1, u1, _ = bare.step(a)
        o2, r2, t2, u2, _ = wrapped.step(np.zeros_like(a))
        if restart.any():  # NEXT_STEP: this step started their new episode
            base.reset_batch(restart)
        done = t1 | u1
        ends += int(done.sum())
        restart = done & ~restart
        if masked and done.any():
            o1, _ = bare.reset(options={"reset_mask": done})
            o2, _ = wrapped.reset(options={"reset_mask": done})
            base.reset_batch(done)
            restart[:] = False
        assert o1.tobytes() == o2.tobytes() and r1.tobytes() == r2.tobytes(), k
        assert (t1 == t2).all() and (u1 == u2).all()
    assert ends >= n  # every row finished an episode and flew the next


def test_single_wrapper_is_an_ordinary_env_and_zero_is_the_base() -> None:
    from stable_baselines3.common.env_checker import check_env

    env = residual_env(gym.make("HyperloopSuspension-v0", **KW), RECORD)
    assert isinstance(env, ResidualEnv)
    check_env(env, warn=False)
    bare = gym.make("HyperloopSuspension-v0", **KW)
    base = make_controller("lqr-preview", bare)
    o1, _ = bare.reset(seed=9)
    base.reset()
    o2, _ = env.reset(seed=9)
    for _ in range(100):
        a = base.act(o1)
        o1, r1, *_ = bare.step(a)
        o2, r2, _, _, info = env.step(np.zeros_like(a))
        assert info["residual_base_action"].tobytes() == a.tobytes()
        assert o1.tobytes() == o2.tobytes() and r1 == r2


def _preset(tmp_path: Path, **extra: object) -> str:
    opts = {
        "timesteps": 1024,
        "n_envs": 4,
        "track_length_m": 100.0,
        "n_steps": 128,
        "batch_size": 256,
        "n_epochs": 1,
        "eval_freq": 512,
        "eval_episodes": 2,
        "checkpoint_freq": 1024,
        "sac_learning_starts": 128,
        "sac_buffer_size": 4096,
        "residual": RECORD,
        **extra,
    }
    path = tmp_path / "residual-tiny.json"
    path.write_text(json.dumps(opts))
    return str(path)


@pytest.mark.parametrize("algo", ["ppo", "sac"])
def test_tiny_residual_run_builds_the_residual_controller(tmp_path: Path, algo: str) -> None:
    out = tmp_path / "run"
    cfg = cli.resolve_config(
        ["--preset", _preset(tmp_path), "--algo", algo, "--out", str(out), "--no-eval"]
        + ["--no-progress"]
    )
    log = experiment.train(cfg)
    assert log["residual"] == {**RECORD, "base_kwargs": {}}
    assert log["config"]["residual"] == log["residual"]  # part of the run's fingerprint
    venv = HyperloopSuspensionVectorEnv(2, scenario="paper-1000-straight")
    ctrl = make_controller("agents.controllers.residual:make_residual", venv, path=str(out))
    assert isinstance(ctrl, ResidualController) and ctrl.base.name == "lqr-preview"
    obs, _ = venv.reset(seed=1)
    ctrl.reset_batch(np.ones(2, dtype=bool))
    a = ctrl.act_batch(obs)
    assert a.shape == (2, 4) and np.isfinite(a).all()
    # the shipped agents' factories (the registry's entry points), given a run instead
    from agents.controllers import residual

    shipped = residual.ppo_residual(venv, path=out)
    assert shipped.name == "ppo-residual" and shipped.scale == RECORD["scale"]
    # the tools' entry point of a preset's run directory, given another directory
    from agents.training import residual_runs

    named = make_controller("agents.training.residual_runs:ppo_residual", venv, path=str(out))
    assert named.name == "ppo-residual" and set(residual_runs.RUNS) >= {"ppo-residual"}
    assert (
        residual_runs.RUNS["ppo-residual"]
        == cli.resolve_config(["--preset", "ppo-residual"])["out"]
    )


def test_a_residual_run_without_no_eval_is_refused_before_training(tmp_path: Path) -> None:
    out = tmp_path / "run"
    cfg = cli.resolve_config(["--preset", _preset(tmp_path), "--out", str(out), "--no-progress"])
    with pytest.raises(experiment.RunDirError, match="--no-eval"):
        experiment.train(cfg)
    assert not out.exists() or not any(out.iterdir())


def test_runs_without_residual_keep_their_fingerprint() -> None:
    cfg = cli.resolve_config(["--preset", "tiny"])
    assert cfg["residual"] is None
    assert "residual" not in experiment.run_fingerprint(cfg)


def test_every_named_run_has_its_preset() -> None:
    """Each run of the tools' entry points is what a preset writes: a named preset, or a
    variant in docs/benchmark/residual/presets/ (its ``out`` the run's directory)."""
    from agents.training import residual_runs

    docs = Path(__file__).resolve().parents[3] / "docs" / "benchmark" / "residual" / "presets"
    for name, out in residual_runs.RUNS.items():
        variant = docs / f"{name}.json"
        preset = str(variant) if variant.exists() else name
        cfg = cli.resolve_config(["--preset", preset])
        assert cfg["out"] == out and cfg["residual"] is not None, name
        assert callable(getattr(residual_runs, name.replace("-", "_")))
