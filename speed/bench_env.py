"""Throughput of HyperloopSuspension-v0 next to CartPole-v1 (same run, same machine).

    python speed/bench_env.py [--steps 20000] [--num-envs 256] [--vec-steps 400]

Prints steps/s of ``env.step`` through ``gymnasium.make`` (one env, constant action, reset
when an episode ends) and the aggregate env-steps/s of the native vector env
(``make_vec(..., vectorization_mode="vector_entry_point")``, autoreset), each with the
ratio to CartPole-v1 measured the same way. Targets: ≥ 20 000 steps/s single,
≥ 100 000 env-steps/s at num_envs = 256. Prints figures only (no assertions).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import gymnasium as gym
import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from hyperloop_env import ENV_ID  # noqa: E402  (importing registers the env)


def bench_single(env_id: str, action: np.ndarray | int, steps: int, **kwargs: object) -> float:
    env = gym.make(env_id, **kwargs)
    env.reset(seed=0)
    for _ in range(200):  # warm-up (JIT, caches)
        _, _, te, tr, _ = env.step(action)
        if te or tr:
            env.reset()
    env.reset(seed=1)
    t0 = time.perf_counter()
    for _ in range(steps):
        _, _, te, tr, _ = env.step(action)
        if te or tr:
            env.reset()
    dt = time.perf_counter() - t0
    env.close()
    return steps / dt


def bench_vector(env_id: str, actions: np.ndarray, n: int, steps: int, **kwargs: object) -> float:
    envs = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    envs.reset(seed=0)
    for _ in range(20):
        envs.step(actions)
    t0 = time.perf_counter()
    for _ in range(steps):
        envs.step(actions)
    dt = time.perf_counter() - t0
    envs.close()
    return n * steps / dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20_000)
    ap.add_argument("--num-envs", type=int, default=256)
    ap.add_argument("--vec-steps", type=int, default=400)
    ap.add_argument("--scenario", default="paper-1000-straight")
    args = ap.parse_args()
    n = args.num_envs
    print(f"os.cpu_count() = {os.cpu_count()}, load average = {os.getloadavg()[0]:.1f}")
    print(f"numpy {np.__version__}, gymnasium {gym.__version__}, scenario {args.scenario}")

    hl = bench_single(ENV_ID, np.zeros(4, np.float32), args.steps, scenario=args.scenario)
    cp = bench_single("CartPole-v1", 1, args.steps)
    print(
        f"single env via gymnasium.make: {ENV_ID} {hl:10,.0f} steps/s | CartPole-v1 "
        f"{cp:10,.0f} steps/s | ratio {hl / cp:.2f}"
    )

    hv = bench_vector(
        ENV_ID, np.zeros((n, 4), np.float32), n, args.vec_steps, scenario=args.scenario
    )
    cv = bench_vector("CartPole-v1", np.ones(n, np.int64), n, args.vec_steps)
    threads = numba.get_num_threads()
    print(
        f"native vector env, num_envs={n}: {ENV_ID} {hv:12,.0f} env-steps/s | CartPole-v1 "
        f"{cv:12,.0f} env-steps/s | ratio {hv / cv:.3f}  (numba threads: {threads})"
    )
    if threads > 1:  # threads contend badly on a loaded machine: show the serial figure too
        numba.set_num_threads(1)
        h1 = bench_vector(
            ENV_ID, np.zeros((n, 4), np.float32), n, args.vec_steps, scenario=args.scenario
        )
        numba.set_num_threads(threads)
        print(f"native vector env, num_envs={n}, 1 numba thread: {h1:12,.0f} env-steps/s")


if __name__ == "__main__":
    main()
