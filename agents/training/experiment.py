"""The training experiment: environments, model, checkpoints and resume, the training loop
and the final STS evaluation (``train.py`` is its command line, :mod:`.cli`)."""

from __future__ import annotations

import json
import re
import shlex
import sys
import time
from pathlib import Path
from typing import Any

from agents.training.presets import BASELINES
from hyperloop_env.config import EnvConfig
from hyperloop_env.scenarios import PAPER_SCENARIOS


def env_kwargs(cfg: dict[str, Any]) -> dict[str, Any]:
    """The environment keywords of a training config (``track_length_m`` + ``env_kwargs``)."""
    kw: dict[str, Any] = {"track_length_m": float(cfg["track_length_m"])}
    kw.update(cfg.get("env_kwargs") or {})
    return kw


def env_config(cfg: dict[str, Any]) -> EnvConfig:
    """The training environment's :class:`~hyperloop_env.config.EnvConfig`."""
    return EnvConfig.from_kwargs(scenario=cfg["scenario"], **env_kwargs(cfg))


def make_native_vec_env(num_envs: int, config: EnvConfig) -> Any:
    """The native batched ``HyperloopSuspension-v0`` (as ``gymnasium.make_vec(...,
    vectorization_mode="vector_entry_point")``) with ``reset_mask`` support, ready for
    :class:`~agents.training.sb3_adapter.GymnasiumVectorToSB3`."""
    from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

    return HyperloopSuspensionVectorEnv(num_envs=num_envs, config=config)


def make_vec_env(config: EnvConfig, n_envs: int, seed: int, vec: str = "native") -> Any:
    """SB3 VecEnv (VecMonitor on top) of ``n_envs`` HyperloopSuspension-v0 environments."""
    import gymnasium as gym
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecMonitor

    from agents.training.sb3_adapter import GymnasiumVectorToSB3
    from hyperloop_env import ENV_ID

    if vec == "native":
        # = gym.make_vec(..., vectorization_mode="vector_entry_point") + reset_mask support
        sb3_env = GymnasiumVectorToSB3(make_native_vec_env(n_envs, config))
    else:

        def make_one() -> Any:
            return gym.make(ENV_ID, config=config)

        cls = DummyVecEnv if vec == "dummy" else SubprocVecEnv
        sb3_env = cls([make_one] * n_envs)
    sb3_env.seed(seed)
    return VecMonitor(sb3_env)


# --------------------------------------------------------------------------------------
# model
# --------------------------------------------------------------------------------------


def build_model(cfg: dict[str, Any], env: Any, tb_log: str | None) -> Any:
    import torch.nn as nn
    from stable_baselines3 import PPO, SAC

    act = {"tanh": nn.Tanh, "relu": nn.ReLU}[cfg["activation"]]
    common = {
        "env": env,
        "seed": cfg["seed"],
        "device": cfg["device"],
        "tensorboard_log": tb_log,
        "verbose": cfg["verbose"],
        "gamma": cfg["gamma"],
        "learning_rate": cfg["learning_rate"],
    }
    if cfg["algo"] == "ppo":
        return PPO(
            "MlpPolicy",
            n_steps=cfg["n_steps"],
            batch_size=cfg["batch_size"],
            n_epochs=cfg["n_epochs"],
            gae_lambda=cfg["gae_lambda"],
            clip_range=cfg["clip_range"],
            ent_coef=cfg["ent_coef"],
            policy_kwargs={
                "net_arch": {"pi": list(cfg["net_arch"]), "vf": list(cfg["net_arch"])},
                "activation_fn": act,
                "log_std_init": cfg["log_std_init"],
            },
            **common,
        )
    return SAC(
        "MlpPolicy",
        buffer_size=cfg["sac_buffer_size"],
        learning_starts=cfg["sac_learning_starts"],
        batch_size=cfg["batch_size"],
        train_freq=cfg["sac_train_freq"],
        gradient_steps=cfg["sac_gradient_steps"],
        policy_kwargs={
            "net_arch": list(cfg["net_arch"]),
            "activation_fn": act,
            "log_std_init": cfg["log_std_init"],
        },
        **common,
    )


def load_model(algo: str, path: Path, env: Any, device: str) -> Any:
    from stable_baselines3 import PPO, SAC

    cls = {"ppo": PPO, "sac": SAC}[algo]
    return cls.load(str(path), env=env, device=device)


CKPT_RE = re.compile(r"^model_(\d+)_steps\.zip$")


def find_last_checkpoint(out: Path) -> tuple[Path, Path, int] | None:
    """(model.zip, vecnormalize.pkl, timesteps) of the newest complete checkpoint."""
    ckpt_dir = out / "checkpoints"
    found: list[tuple[int, Path, Path]] = []
    if ckpt_dir.is_dir():
        for f in ckpt_dir.iterdir():
            m = CKPT_RE.match(f.name)
            if not m:
                continue
            steps = int(m.group(1))
            vn = ckpt_dir / f"model_vecnormalize_{steps}_steps.pkl"
            if vn.exists():
                found.append((steps, f, vn))
    # the final model of a finished run also counts (resume = train further)
    final_model, final_vn = out / "model.zip", out / "vecnormalize.pkl"
    log = out / "training_log.json"
    if final_model.exists() and final_vn.exists() and log.exists():
        try:
            steps = int(json.loads(log.read_text())["num_timesteps"])
            found.append((steps, final_model, final_vn))
        except (ValueError, KeyError):
            pass
    if not found:
        return None
    # on a tie the finished run's model.zip wins: a checkpoint is written during the last
    # rollout, before that rollout's update, so the final model is the newer state
    steps, model, vn = max(found, key=lambda t: (t[0], t[1] == final_model))
    return model, vn, steps


# --------------------------------------------------------------------------------------
# training
# --------------------------------------------------------------------------------------


def train(cfg: dict[str, Any]) -> dict[str, Any]:
    """Train according to ``cfg`` (see :func:`resolve_config`); returns the training log."""
    import numpy as np
    import torch
    from stable_baselines3.common.callbacks import CheckpointCallback, EvalCallback
    from stable_baselines3.common.vec_env import VecNormalize

    torch.set_num_threads(1)
    out = Path(cfg["out"])
    resume_from = None
    if cfg["resume"]:
        resume_from = find_last_checkpoint(out)
        if resume_from is None:
            raise SystemExit(
                f"train.py: error: --resume: no checkpoint in {out} (looked for "
                f"{out}/checkpoints/model_<N>_steps.zip with its VecNormalize statistics, and "
                f"for a finished run's model.zip); train without --resume first"
            )
        prev = read_json(out / "training_log.json") or {}
        for key in ("algo", "scenario"):  # a resumed run keeps what it was trained on
            if key in prev and prev[key] != cfg[key]:
                print(f"note: --resume keeps {key}={prev[key]!r} of the checkpointed run")
                cfg[key] = prev[key]
    out.mkdir(parents=True, exist_ok=True)
    kw = env_kwargs(cfg)
    ecfg = env_config(cfg)
    n_envs = cfg["n_envs"]
    train_env = make_vec_env(ecfg, n_envs, cfg["seed"], cfg["vec"])
    eval_n = min(cfg["eval_episodes"], 4)
    eval_env = make_vec_env(ecfg, eval_n, cfg["seed"] + 10_000, cfg["vec"])
    eval_env = VecNormalize(eval_env, training=False, norm_reward=False)
    tb_log = str(out / "tb")
    t0 = time.perf_counter()
    if resume_from is not None:
        model_path, vn_path, steps = resume_from
        print(f"resuming from {model_path} ({steps} timesteps)")
        train_env = VecNormalize.load(str(vn_path), train_env)
        train_env.training = True
        model = load_model(cfg["algo"], model_path, train_env, cfg["device"])
        model.tensorboard_log = tb_log
        replay = model_path.parent / f"model_replay_buffer_{steps}_steps.pkl"
        if cfg["algo"] == "sac" and replay.exists():
            model.load_replay_buffer(str(replay))
        remaining = max(0, cfg["timesteps"] - model.num_timesteps)
        if remaining == 0:
            print(
                f"already trained {model.num_timesteps} >= --timesteps {cfg['timesteps']}; "
                "raise --timesteps to train further"
            )
    else:
        train_env = VecNormalize(
            train_env, norm_obs=True, norm_reward=cfg["norm_reward"], gamma=cfg["gamma"]
        )
        model = build_model(cfg, train_env, tb_log)
        remaining = cfg["timesteps"]

    eval_cb = EvalCallback(
        eval_env,
        n_eval_episodes=cfg["eval_episodes"],
        eval_freq=max(1, cfg["eval_freq"] // n_envs),
        best_model_save_path=str(out / "best"),
        log_path=str(out / "eval"),
        deterministic=True,
        verbose=cfg["verbose"],
    )
    ckpt_cb = CheckpointCallback(
        save_freq=max(1, cfg["checkpoint_freq"] // n_envs),
        save_path=str(out / "checkpoints"),
        name_prefix="model",
        save_vecnormalize=True,
        save_replay_buffer=cfg["algo"] == "sac",
    )
    if remaining > 0:
        model.learn(
            total_timesteps=remaining,
            callback=[eval_cb, ckpt_cb],
            progress_bar=cfg["progress_bar"],
            reset_num_timesteps=resume_from is None,
            tb_log_name=cfg["algo"],
        )
    wall = time.perf_counter() - t0
    model.save(str(out / "model.zip"))
    train_env.save(str(out / "vecnormalize.pkl"))
    # a short evaluation of the final policy, for the log
    from stable_baselines3.common.evaluation import evaluate_policy

    eval_env.obs_rms = train_env.obs_rms
    mean_r, std_r = evaluate_policy(model, eval_env, n_eval_episodes=cfg["eval_episodes"])
    prev_log = read_json(out / "training_log.json") if resume_from else None
    log = {
        "command": "python " + " ".join(shlex.quote(a) for a in sys.argv),
        "preset": cfg["preset"],
        "algo": cfg["algo"],
        "scenario": cfg["scenario"],
        "seed": cfg["seed"],
        "num_timesteps": int(model.num_timesteps),
        "timesteps_requested": cfg["timesteps"],
        "n_envs": n_envs,
        "vec": cfg["vec"],
        "wall_time_s": round(wall + (prev_log or {}).get("wall_time_s", 0.0), 1),
        "env_steps_per_s": round(remaining / wall, 1) if wall > 0 and remaining else None,
        "final_eval_mean_reward": float(mean_r),
        "final_eval_std_reward": float(std_r),
        "best_eval_mean_reward": float(eval_cb.best_mean_reward)
        if np.isfinite(eval_cb.best_mean_reward)
        else None,
        "env_kwargs": kw,
        "hyperparameters": {
            k: cfg[k]
            for k in (
                "gamma",
                "learning_rate",
                "n_steps",
                "batch_size",
                "n_epochs",
                "gae_lambda",
                "clip_range",
                "ent_coef",
                "log_std_init",
                "net_arch",
                "activation",
                "norm_reward",
            )
        },
        "resumed_from": str(resume_from[0]) if resume_from else None,
        "versions": _versions(),
    }
    (out / "training_log.json").write_text(json.dumps(log, indent=2) + "\n")
    train_env.close()
    eval_env.close()
    print(
        f"trained {cfg['algo']} for {model.num_timesteps} timesteps in {wall:.0f} s; "
        f"final eval reward {mean_r:.1f} +- {std_r:.1f}; model saved to {out / 'model.zip'}"
    )
    return log


def _versions() -> dict[str, str]:
    import gymnasium
    import stable_baselines3
    import torch

    return {
        "python": sys.version.split()[0],
        "stable_baselines3": stable_baselines3.__version__,
        "torch": torch.__version__,
        "gymnasium": gymnasium.__version__,
    }


def read_json(path: Path) -> dict[str, Any] | None:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


# --------------------------------------------------------------------------------------
# evaluation
# --------------------------------------------------------------------------------------


EVAL_ENV_KEYS = (
    "actuators",
    "action_scale",
    "sensor_noise_std",
    "sensor_delay",
    "coil_time_constant_s",
    "control_dt_s",
    "clearance_m",
    "magnet",
)


def evaluate_run(cfg: dict[str, Any]) -> dict[str, Any]:
    """STS evaluation of the trained agent and the baselines on the four paper conditions
    (:func:`agents.evaluation.evaluate.evaluate`); the report goes to ``<out>/report/``."""
    from agents.evaluation import evaluate as ev

    out = Path(cfg["out"])
    algo = cfg["algo"]
    kw = env_kwargs(cfg)
    eval_kw = {k: kw[k] for k in EVAL_ENV_KEYS if k in kw and k != "magnet"}
    cmd = (
        f"python train.py --eval-only --algo {algo} --out {out} "
        f"--eval-distance-km {cfg['eval_distance_km']} --eval-seeds {cfg['eval_seeds']}"
    )
    return ev.evaluate(
        [*BASELINES, algo],
        scenarios=list(PAPER_SCENARIOS),
        distance_km=float(cfg["eval_distance_km"]),
        seeds=cfg["eval_seeds"],
        magnet=kw.get("magnet", "repelling"),
        out_dir=out / "report",
        progress=cfg["progress_bar"],
        env_kwargs=eval_kw or None,
        controller_kwargs={algo: {"path": str(out)}},
        command=f"{cmd}  (agents.evaluate.evaluate: passive pid lqr {algo}, paper scenarios)",
    )


