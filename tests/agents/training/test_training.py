"""train.py, the SB3 adapter and the SB3 controller (fast; the full training is -m slow)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")
import torch  # noqa: E402
from stable_baselines3.common.vec_env import DummyVecEnv  # noqa: E402

import hyperloop_env  # noqa: E402, F401
from agents.cli import train as cli  # noqa: E402
from agents.controllers.learned import (  # noqa: E402
    SB3Controller,
    available_shipped,
    load_shipped,
)
from agents.training import experiment  # noqa: E402
from agents.training.experiment import make_native_vec_env  # noqa: E402
from agents.training.presets import PRESETS  # noqa: E402
from agents.training.sb3_adapter import GymnasiumVectorToSB3  # noqa: E402
from hyperloop_env.config import EnvConfig  # noqa: E402
from hyperloop_env.observation import OBS_SIZE  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]

torch.set_num_threads(1)


def _run(*args: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(ROOT / "train.py"), *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=ROOT,
    )


# ---- adapter --------------------------------------------------------------------------


@pytest.mark.parametrize("magnet", ["repelling", "attracting"])
def test_adapter_matches_dummy_vec_env_across_autoresets(magnet: str) -> None:
    """Native vector env through the adapter == DummyVecEnv of single envs, bit for bit,
    including terminal observations, TimeLimit.truncated and the reset after an episode
    (the open-loop unstable attracting magnet under random actions gives contacts)."""
    kw = {"scenario": "random", "track_length_m": 40.0, "magnet": magnet}
    n = 3
    a = GymnasiumVectorToSB3(make_native_vec_env(n, EnvConfig(**kw)))
    d = DummyVecEnv([lambda: gym.make("HyperloopSuspension-v0", **kw)] * n)
    a.seed(7)
    d.seed(7)
    np.testing.assert_array_equal(a.reset(), d.reset())
    rng = np.random.default_rng(0)
    ended = {"terminated": 0, "truncated": 0}
    for _ in range(500):
        act = rng.uniform(-1, 1, (n, 4)).astype(np.float32)
        a.step_async(act)
        d.step_async(act)
        o1, r1, d1, i1 = a.step_wait()
        o2, r2, d2, i2 = d.step_wait()
        np.testing.assert_array_equal(o1, o2)
        np.testing.assert_allclose(r1, r2, rtol=1e-6)
        np.testing.assert_array_equal(d1, d2)
        for i in np.flatnonzero(d1):
            np.testing.assert_array_equal(
                i1[i]["terminal_observation"], i2[i]["terminal_observation"]
            )
            assert i1[i]["TimeLimit.truncated"] == i2[i]["TimeLimit.truncated"]
            ended["truncated" if i1[i]["TimeLimit.truncated"] else "terminated"] += 1
    assert ended["truncated"] > 0 or magnet == "attracting"
    if magnet == "attracting":
        assert ended["terminated"] > 0


@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_adapter_generic_gymnasium_vector_env(mode: str) -> None:
    from gymnasium.vector import AutoresetMode

    v = GymnasiumVectorToSB3(
        gym.make_vec(
            "CartPole-v1",
            num_envs=2,
            vectorization_mode="sync",
            vector_kwargs={"autoreset_mode": AutoresetMode(mode)},
        )
    )
    d = DummyVecEnv([lambda: gym.make("CartPole-v1")] * 2)
    v.seed(3)
    d.seed(3)
    np.testing.assert_allclose(v.reset(), d.reset())
    rng = np.random.default_rng(1)
    n_done = 0
    for _ in range(300):
        act = rng.integers(0, 2, 2)
        v.step_async(act)
        d.step_async(act)
        o1, r1, d1, i1 = v.step_wait()
        o2, r2, d2, i2 = d.step_wait()
        np.testing.assert_allclose(o1, o2)
        np.testing.assert_array_equal(d1, d2)
        for i in np.flatnonzero(d1):
            n_done += 1
            np.testing.assert_allclose(i1[i]["terminal_observation"], i2[i]["terminal_observation"])
    assert n_done > 0


# ---- tiny training run ------------------------------------------------------------------


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("tiny") / "run"
    cfg = cli.resolve_config(
        ["--preset", "tiny", "--out", str(out), "--no-eval", "--no-progress", "--seed", "3"]
    )
    experiment.train(cfg)
    return out


def test_tiny_run_saves_everything(tiny_run: Path) -> None:
    for f in ("model.zip", "vecnormalize.pkl", "training_log.json"):
        assert (tiny_run / f).exists(), f
    log = json.loads((tiny_run / "training_log.json").read_text())
    assert log["algo"] == "ppo" and log["num_timesteps"] >= 4096 and log["seed"] == 3
    assert np.isfinite(log["final_eval_mean_reward"])
    assert any((tiny_run / "checkpoints").glob("model_*_steps.zip"))
    assert any((tiny_run / "checkpoints").glob("model_vecnormalize_*_steps.pkl"))
    assert (tiny_run / "best" / "best_model.zip").exists()
    assert any((tiny_run / "tb").rglob("events.out.tfevents.*"))


def test_reload_gives_identical_deterministic_actions(tiny_run: Path) -> None:
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    cfg = EnvConfig(scenario="random", track_length_m=200.0)
    env = experiment.make_vec_env(cfg, 2, 0, "native")
    vn = VecNormalize.load(str(tiny_run / "vecnormalize.pkl"), env)
    vn.training = False
    vn.norm_reward = False
    model = PPO.load(str(tiny_run / "model.zip"), device="cpu")
    raw = np.random.default_rng(0).normal(0, 0.3, (16, OBS_SIZE)).astype(np.float32)
    ref, _ = model.predict(vn.normalize_obs(raw), deterministic=True)
    ref = np.clip(ref, -1, 1)
    model2 = PPO.load(str(tiny_run / "model.zip"), device="cpu")
    again, _ = model2.predict(vn.normalize_obs(raw), deterministic=True)
    np.testing.assert_array_equal(np.clip(again, -1, 1), ref)
    # the controller (NumPy forward pass) and the torch fallback give the same actions
    ctrl = SB3Controller(tiny_run)
    np.testing.assert_allclose(ctrl.act_batch(raw), ref, atol=1e-5)
    ctrl_t = SB3Controller(tiny_run, use_numpy=False)
    np.testing.assert_allclose(ctrl_t.act_batch(raw), ref, atol=1e-6)
    np.testing.assert_allclose(ctrl.act(raw[0]), ref[0], atol=1e-5)
    env.close()


def test_resume_continues_from_checkpoint(tiny_run: Path) -> None:
    before = json.loads((tiny_run / "training_log.json").read_text())["num_timesteps"]
    cfg = cli.resolve_config(
        [
            "--preset",
            "tiny",
            "--out",
            str(tiny_run),
            "--resume",
            "--seed",
            "3",
            "--timesteps",
            str(before + 1024),
            "--no-eval",
            "--no-progress",
        ]
    )
    log = experiment.train(cfg)
    assert log["num_timesteps"] == before + 1024
    assert log["resumed_from"]["num_timesteps"] == before


def test_tiny_sac_run_and_controller(tmp_path: Path) -> None:
    out = tmp_path / "sac"
    cfg = cli.resolve_config(
        ["--preset", "tiny", "--algo", "sac", "--timesteps", "512", "--out", str(out)]
        + ["--no-eval", "--no-progress", "--eval-freq", "512", "--checkpoint-freq", "512"]
    )
    experiment.train(cfg)
    ctrl = SB3Controller(out)
    assert ctrl.algo == "sac"
    raw = np.random.default_rng(1).normal(0, 0.3, (8, OBS_SIZE)).astype(np.float32)
    ref = SB3Controller(out, use_numpy=False).act_batch(raw)
    np.testing.assert_allclose(ctrl.act_batch(raw), ref, atol=1e-5)
    assert np.all(np.abs(ref) <= 1.0)


# ---- CLI ----------------------------------------------------------------------------------


def test_help_exits_zero() -> None:
    r = _run("--help")
    assert r.returncode == 0
    assert "--algo" in r.stdout and "--resume" in r.stdout and "--preset" in r.stdout


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--algo", "dqn"], "--algo must be one of"),
        (["--scenario", "moon"], "unknown --scenario"),
        (["--timesteps", "0"], "--timesteps must be"),
        (["--n-envs", "0"], "--n-envs must be"),
        (["--device", "banana"], "--device"),
        (["--preset", "nope"], "unknown preset"),
        (["--env-kwarg", "bogus_option=1"], "bogus_option"),
    ],
)
def test_bad_arguments_exit_nonzero_with_message(args: list[str], message: str) -> None:
    r = _run(*args)
    assert r.returncode != 0
    assert message in r.stderr


def test_resume_without_checkpoint_fails_clearly(tmp_path: Path) -> None:
    r = _run("--resume", "--out", str(tmp_path / "empty"), "--no-progress")
    assert r.returncode != 0
    assert "no checkpoint" in r.stderr
    assert not (tmp_path / "empty" / "model.zip").exists()


def test_eval_only_without_model_fails_clearly(tmp_path: Path) -> None:
    r = _run("--eval-only", "--out", str(tmp_path / "nothing"))
    assert r.returncode != 0
    assert "no model.zip" in r.stderr


def test_presets_resolve() -> None:
    for name in PRESETS:
        cfg = cli.resolve_config(["--preset", name])
        assert cfg["timesteps"] >= 1 and cfg["out"]
    cfg = cli.resolve_config(["--preset", "shipped-ppo", "--timesteps", "1e5", "--seed", "4"])
    assert cfg["timesteps"] == 100_000 and cfg["seed"] == 4 and cfg["n_envs"] == 16


# ---- shipped agent ------------------------------------------------------------------------


def _shipped() -> SB3Controller:
    if "ppo" not in available_shipped():
        pytest.skip("no shipped PPO agent in agents/shipped/ppo")
    return load_shipped("ppo")


def test_shipped_agent_loads_and_acts() -> None:
    ctrl = _shipped()
    ctrl.reset(seed=0)
    env = gym.make("HyperloopSuspension-v0", scenario="paper-1000-straight", track_length_m=50.0)
    obs, _ = env.reset(seed=0)
    for _ in range(20):
        a = ctrl.act(obs)
        assert a.shape == (4,) and a.dtype == np.float32
        assert np.all(np.isfinite(a)) and np.all(np.abs(a) <= 1.0)
        obs, *_ = env.step(a)
    batch = ctrl.act_batch(np.zeros((5, OBS_SIZE), dtype=np.float32))
    assert batch.shape == (5, 4)


def test_shipped_agent_files_small() -> None:
    _shipped()
    from agents.controllers.learned import shipped_path

    total = sum(f.stat().st_size for f in shipped_path("ppo").rglob("*") if f.is_file())
    assert total < 5e6


def test_shipped_agent_registered_controller() -> None:
    _shipped()
    from agents import make_controller

    ctrl = make_controller("ppo")
    assert isinstance(ctrl, SB3Controller) and ctrl.name == "ppo"
    assert make_controller("ppo") is ctrl  # cached: loaded once per evaluation


def test_shipped_agent_short_evaluation(tmp_path: Path) -> None:
    _shipped()
    ev = pytest.importorskip("agents.evaluation.evaluate")
    res = ev.evaluate(
        ["ppo", "passive"],
        scenarios=["paper-1000-straight"],
        distance_km=0.5,
        seeds=1,
        out_dir=tmp_path,
        settle_s=0.5,
        progress=False,
        figures=False,
        n_boot=0,
    )
    assert (tmp_path / "report.md").exists() and (tmp_path / "results.json").exists()
    m = {r["metrics"]["controller"]: r["metrics"] for r in res["results"]}
    assert m["ppo"]["n_contact_episodes"] == 0


@pytest.mark.slow
def test_default_cli_run_end_to_end(tmp_path: Path) -> None:
    r = _run("--out", str(tmp_path / "run"), "--no-progress", timeout=900)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "STS report" in r.stdout


def test_validation_score_runs_on_a_saved_agent(tiny_run: Path) -> None:
    """The search's and hyperloop checkpoints' validation score runs end to end on a
    saved run: the mean log of the paired capacity ratios against LQR, computed from the
    per-seed capacities it reports."""
    from agents.training.tune import validation_capacities, validation_score

    args = {"seeds": 3, "distance_km": 0.7, "conditions": ("paper-1000-straight",)}
    lqr = validation_capacities("lqr", **args)
    score, details = validation_score(tiny_run, baseline=lqr, **args)
    d = details["conditions"]["paper-1000-straight"]
    assert d["lqr_capacity"] == lqr["paper-1000-straight"]["capacity"]
    assert lqr["paper-1000-straight"]["seeds"] == [2_000_000, 2_000_001, 2_000_002]
    both = [
        (a, b)
        for a, b, ca, cb in zip(
            d["capacity"],
            d["lqr_capacity"],
            d["censored"],
            lqr["paper-1000-straight"]["censored"],
            strict=True,
        )
        if not (ca and cb)
    ]
    expect = float(np.mean([math.log(a / b) for a, b in both])) if both else 0.0
    assert score == pytest.approx(expect, abs=1e-12)
    again, _ = validation_score(tiny_run, **args)  # LQR computed inside: the same score
    assert again == score


def test_validation_score_and_flight_check_on_workers_as_in_one_process(tiny_run: Path) -> None:
    """hyperloop checkpoints' pieces on two worker processes of one pool: the same
    capacities, score and flight contacts as in this process (the conditions' tasks come
    back in their order: the per-condition values differ)."""
    from agents.evaluation.backends import shared_pool
    from agents.training.checkpoint_scores import flight_contacts
    from agents.training.tune import validation_capacities, validation_score

    args = {
        "seeds": 3,
        "distance_km": 0.7,
        "conditions": ("paper-1000-straight", "paper-2000-curved"),
    }
    here = validation_score(tiny_run, **args)
    fly_here = flight_contacts(tiny_run / "model.zip", "levitation", 2, 0.4)
    with shared_pool(2):
        lqr = validation_capacities("lqr", **args, workers=2)
        there = validation_score(tiny_run, baseline=lqr, **args, workers=2)
        fly_there = flight_contacts(tiny_run / "model.zip", "levitation", 2, 0.4, workers=2)
    assert there == here
    one = {"seeds": 3, "distance_km": 0.7}
    alone = {c: validation_capacities("lqr", **one, conditions=(c,))[c] for c in args["conditions"]}
    assert lqr == alone  # each condition's capacities are its own task's
    assert alone["paper-1000-straight"] != alone["paper-2000-curved"]
    from hyperloop_env.scenarios import PAPER_SCENARIOS

    assert fly_there == fly_here and list(fly_here) == list(PAPER_SCENARIOS)
