"""What the second core adds to the native vector env: its physics kernel and its whole step,
on one numba thread and on all of them, in one run.

    python speed/bench_threads.py [--num-envs 64 256 1024] [--rounds 3]
    GOMP_SPINCOUNT=1000 python speed/bench_threads.py     # threads sleep between steps

Per batch size: microseconds per environment and control step of the kernel alone
(``Simulator.step_full``, serial vs ``parallel``) and of ``env.step`` (the vector env with
``parallel=False``, ``True`` and the default ``None``, which measures both as it steps),
best of ``--rounds`` alternating rounds, and the ratios to the serial step. numba's OpenMP
threads sleep between parallel regions unless the OpenMP wait policy keeps them spinning;
waking them costs a fixed time per step, which is what separates the ratio from the core
count on a virtual machine (``hyperloop_env`` sets ``GOMP_SPINCOUNT`` for that unless it is
set). Prints figures only.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from functools import partial
from pathlib import Path

import gymnasium as gym
import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from hyperloop_env import ENV_ID  # noqa: E402  (importing registers the env)


def _best(fn, reps: int, rounds: int) -> float:
    best = float("inf")
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(reps):
            fn()
        best = min(best, (time.perf_counter() - t0) / reps)
    return best


def _vec(n: int, parallel: bool | None) -> gym.vector.VectorEnv:
    env = gym.make_vec(
        ENV_ID, num_envs=n, vectorization_mode="vector_entry_point", parallel=parallel
    )
    env.reset(seed=0)
    return env


def measure(n: int, rounds: int) -> dict[str, float]:
    """µs per environment-step: kernel and env.step, serial and parallel. The kernel is
    timed on environments of its own (stepping the physics alone moves their vehicles on
    without the environment's episode logic)."""
    out: dict[str, float] = {}
    steppers = {par: _vec(n, par) for par in (False, True, None)}
    kernels = {par: _vec(n, par) for par in (False, True)}
    reps = max(40, 40_000 // n)
    actions = np.zeros((n, 4), np.float32)
    for env in steppers.values():
        for _ in range(20):
            env.step(actions)
    for _ in range(2):  # alternate, so that drift hits every mode
        for par, env in steppers.items():
            key = {False: "serial", True: "parallel", None: "auto"}[par]
            if par is not None:
                k_env = kernels[par]
                k = _best(partial(k_env.sim.step_full, k_env._cmd, parallel=par), reps, rounds)
                out[f"kernel {key}"] = min(out.get(f"kernel {key}", 1e9), k / n * 1e6)
            s = _best(partial(env.step, actions), reps, rounds)
            out[f"step {key}"] = min(out.get(f"step {key}", 1e9), s / n * 1e6)
    for env in (*steppers.values(), *kernels.values()):
        env.close()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--num-envs", type=int, nargs="+", default=[64, 256, 1024])
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    policy = os.environ.get("OMP_WAIT_POLICY", "(unset)")
    spin = os.environ.get("GOMP_SPINCOUNT", "(unset)")  # hyperloop_env sets it if unset
    print(
        f"os.cpu_count() = {os.cpu_count()}, numba threads = {numba.get_num_threads()}, "
        f"load average = {os.getloadavg()[0]:.1f}, OMP_WAIT_POLICY = {policy}, "
        f"GOMP_SPINCOUNT = {spin}"
    )
    for n in args.num_envs:
        r = measure(n, args.rounds)
        print(
            f"num_envs={n:5d}: kernel {r['kernel serial']:.2f} → {r['kernel parallel']:.2f} "
            f"µs/env-step (×{r['kernel serial'] / r['kernel parallel']:.2f}); env.step "
            f"{r['step serial']:.2f} → {r['step parallel']:.2f} µs/env-step "
            f"(×{r['step serial'] / r['step parallel']:.2f}); env.step with the measured "
            f"choice (parallel=None) {r['step auto']:.2f} µs/env-step "
            f"(×{r['step serial'] / r['step auto']:.2f})"
        )


if __name__ == "__main__":
    main()
