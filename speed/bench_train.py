"""PPO training throughput: native vector env (through the SB3 adapter) vs DummyVecEnv;
and this checkout's training preset against an earlier commit's.

    python speed/bench_train.py [--n-envs 8] [--steps-per-env 4096] [--repeat 1]
    python speed/bench_train.py --vs c7715c1 [--preset shipped-ppo] [--timesteps 200000]
        [--rounds 3]

``--vs COMMIT``: the learning throughput (env steps per second of ``model.learn``, rollouts
and updates: ``num_timesteps / wall_time_s`` of the run's ``training_log.json``) of
``train.py --preset PRESET --timesteps T --no-eval`` in this checkout and in COMMIT's tree
(extracted with ``git worktree``; its own preset of that name, so each side trains with its
own settings: same scenario and number of envs), the two run in turn ``--rounds`` times, each
after one short warm-up run (numba compilation); the ratio is taken pair by pair and the
median quoted (the machine is shared: the spread says how noisy it was).

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


def train_throughput(root: Path, preset: str, timesteps: int, out: Path) -> tuple[float, int]:
    """(env steps/s of ``model.learn``, number of envs) of one ``train.py`` run in ``root``."""
    import json
    import subprocess

    cmd = [sys.executable, "train.py", "--preset", preset, "--timesteps", str(timesteps)]
    cmd += ["--no-eval", "--no-progress", "--out", str(out), "--overwrite"]
    env = {**os.environ, "PYTHONPATH": str(root)}
    subprocess.run(cmd, cwd=root, env=env, check=True, capture_output=True, text=True)
    log = json.loads((out / "training_log.json").read_text())
    return log["num_timesteps"] / log["wall_time_s"], int(log["n_envs"])


def compare_with(base: str, preset: str, timesteps: int, rounds: int) -> None:
    """This checkout's preset against ``base``'s, in turn (module docstring)."""
    import statistics
    import subprocess
    import tempfile

    here = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory(prefix="bench-train-") as tmp:
        tree = Path(tmp) / "base"
        subprocess.run(
            ["git", "-C", str(here), "worktree", "add", "--detach", str(tree), base],
            check=True,
            capture_output=True,
        )
        try:
            sides = {"this checkout": here, base: tree}
            for name, root in sides.items():  # warm-up: numba compilation, caches
                train_throughput(root, preset, 4096 * 4, Path(tmp) / f"warm-{len(name)}")
            ratios = []
            for r in range(rounds):
                got = {}
                for name, root in sides.items():
                    got[name] = train_throughput(root, preset, timesteps, Path(tmp) / "run")
                new, old = got["this checkout"], got[base]
                if new[1] != old[1]:
                    raise SystemExit(f"different numbers of envs: {new[1]} vs {old[1]}")
                ratios.append(new[0] / old[0])
                print(
                    f"round {r + 1}: this checkout {new[0]:8.0f} env-steps/s, {base} "
                    f"{old[0]:8.0f} env-steps/s ({new[1]} envs): x{ratios[-1]:.2f}",
                    flush=True,
                )
            print(
                f"--preset {preset}, {timesteps} steps per run: this checkout / {base} = "
                f"x{statistics.median(ratios):.2f} (median of {rounds}; "
                f"x{min(ratios):.2f}..x{max(ratios):.2f}); load average {os.getloadavg()}"
            )
        finally:
            subprocess.run(
                ["git", "-C", str(here), "worktree", "remove", "--force", str(tree)],
                check=False,
                capture_output=True,
            )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n-envs", type=int, default=8)
    ap.add_argument("--steps-per-env", type=int, default=4096)
    ap.add_argument("--repeat", type=int, default=1, help="take the best of N runs")
    ap.add_argument("--vs", default=None, help="compare the training preset with this commit")
    ap.add_argument("--preset", default="shipped-ppo", help="with --vs: the preset to train")
    ap.add_argument("--timesteps", type=int, default=200_000, help="with --vs: steps per run")
    ap.add_argument("--rounds", type=int, default=3, help="with --vs: pairs of runs")
    args = ap.parse_args()
    if args.vs is not None:
        print(f"cores: {os.cpu_count()}, load average {os.getloadavg()}")
        compare_with(args.vs, args.preset, args.timesteps, args.rounds)
        return
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
