"""PPO training throughput: native vector env (through the SB3 adapter) vs DummyVecEnv.

    python speed/bench_train.py [--n-envs 8] [--steps-per-env 4096] [--repeat 1]

Both runs train the same PPO (MlpPolicy [64, 64], n_steps 256 per env, batch 256,
10 epochs, VecMonitor + VecNormalize, torch 1 thread) for ``n_envs * steps_per_env``
environment steps on ``paper-1000-straight``; the figure is env-steps per second of
wall-clock time for the whole ``learn`` call (rollouts *and* gradient updates), plus the
rollout-only throughput (policy forward + env step, no updates). Prints both and the ratio.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402
import torch  # noqa: E402


def _make(vec: str, n_envs: int) -> object:
    from stable_baselines3.common.vec_env import VecNormalize

    from agents.training.experiment import make_vec_env
    from hyperloop_env.config import EnvConfig

    cfg = EnvConfig(scenario="paper-1000-straight", track_length_m=1000.0)
    env = make_vec_env(cfg, n_envs, 0, vec)
    return VecNormalize(env)


def bench_learn(vec: str, n_envs: int, steps_per_env: int) -> float:
    from stable_baselines3 import PPO

    env = _make(vec, n_envs)
    model = PPO("MlpPolicy", env, n_steps=256, batch_size=256, seed=0, device="cpu")
    model.learn(256 * n_envs)  # warm-up (numba compile cache, torch init)
    total = n_envs * steps_per_env
    t = time.perf_counter()
    model.learn(total, reset_num_timesteps=False)
    rate = total / (time.perf_counter() - t)
    env.close()
    return rate


def bench_rollout(vec: str, n_envs: int, steps_per_env: int) -> float:
    from stable_baselines3 import PPO

    env = _make(vec, n_envs)
    model = PPO("MlpPolicy", env, n_steps=256, batch_size=256, seed=0, device="cpu")
    obs = env.reset()
    for _ in range(50):
        env.step(model.predict(obs)[0])
    t = time.perf_counter()
    for _ in range(steps_per_env):
        with torch.no_grad():
            act, _, _ = model.policy(torch.as_tensor(obs))
        obs, _, _, _ = env.step(np.clip(act.numpy(), -1, 1))
    rate = n_envs * steps_per_env / (time.perf_counter() - t)
    env.close()
    return rate


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n-envs", type=int, default=8)
    ap.add_argument("--steps-per-env", type=int, default=4096)
    ap.add_argument("--repeat", type=int, default=1, help="take the best of N runs")
    args = ap.parse_args()
    torch.set_num_threads(1)
    print(
        f"cores: {os.cpu_count()}, torch threads: {torch.get_num_threads()}, "
        f"n_envs {args.n_envs} x {args.steps_per_env} steps = "
        f"{args.n_envs * args.steps_per_env} env steps per run"
    )
    res: dict[str, dict[str, float]] = {}
    for vec in ("native", "dummy"):
        learn = max(bench_learn(vec, args.n_envs, args.steps_per_env) for _ in range(args.repeat))
        roll = max(
            bench_rollout(vec, args.n_envs, args.steps_per_env // 4) for _ in range(args.repeat)
        )
        res[vec] = {"learn": learn, "rollout": roll}
        print(
            f"{vec:>7}: PPO learn {learn:8.0f} env-steps/s   rollout only {roll:8.0f} env-steps/s"
        )
    print(
        f"  ratio native/dummy: learn {res['native']['learn'] / res['dummy']['learn']:.2f}x, "
        f"rollout {res['native']['rollout'] / res['dummy']['rollout']:.2f}x"
    )


if __name__ == "__main__":
    main()
