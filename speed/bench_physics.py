"""Throughput of the simulator (issue: physics core). Prints figures; not a test.

    python speed/bench_physics.py [--steps 20000] [--batch 256] [--no-radau]

One control step = 1 ms of simulated time (2 RK4 substeps, 6 modes per span and plane).
Targets on a 2-core machine: >= 50 000 steps/s for one vehicle, >= 150 000 vehicle-steps/s
for the batched form with 256 vehicles, and the speed-up over scipy's solve_ivp (Radau)
on the same run (taken from the verification case ``integrator_vs_radau``).
"""

from __future__ import annotations

import argparse
import os
import time

import numba
import numpy as np

from hyperloop_env.physics import BatchSimulator, ModelParams, Simulator


def bench_single(n_steps: int) -> tuple[float, float]:
    sim = Simulator(ModelParams())
    sim.reset(seed=0)
    cur = np.full(4, sim.nominal_current_A)
    for _ in range(200):  # warm-up (compilation is cached on disk)
        sim.step_record(cur)
    t = time.perf_counter()
    for _ in range(n_steps):
        sim.step_record(cur)
    per_call = n_steps / (time.perf_counter() - t)
    sim.reset(seed=0)
    t = time.perf_counter()
    sim.run(cur, n_steps)
    looped = n_steps / (time.perf_counter() - t)
    return per_call, looped


def bench_batch(n: int, n_steps: int, threads: int) -> float:
    numba.set_num_threads(threads)
    b = BatchSimulator(ModelParams(), n=n)
    b.reset(list(range(n)))
    cur = np.full((n, 4), b.nominal_current_A[0])
    for _ in range(5):
        b.step(cur)
    t = time.perf_counter()
    for _ in range(n_steps):
        b.step(cur)
    return n * n_steps / (time.perf_counter() - t)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=20_000)
    ap.add_argument("--batch", type=int, default=256)
    ap.add_argument("--batch-steps", type=int, default=200)
    ap.add_argument("--no-radau", action="store_true", help="skip the solve_ivp comparison")
    args = ap.parse_args()
    print(
        f"cores: os.cpu_count() = {os.cpu_count()}, "
        f"numba threads = {numba.config.NUMBA_NUM_THREADS}"
    )
    per_call, looped = bench_single(args.steps)
    print(
        f"single vehicle, Simulator.step_record per call : {per_call:10.0f} steps/s"
        "  (target >= 50 000)"
    )
    print(f"single vehicle, Simulator.run (compiled loop)  : {looped:10.0f} steps/s")
    one = bench_batch(args.batch, args.batch_steps, 1)
    allc = bench_batch(args.batch, args.batch_steps, numba.config.NUMBA_NUM_THREADS)
    print(f"batch of {args.batch}, 1 thread                  : {one:10.0f} vehicle-steps/s")
    print(
        f"batch of {args.batch}, {numba.config.NUMBA_NUM_THREADS} threads                 : "
        f"{allc:10.0f} vehicle-steps/s  (target >= 150 000; x{allc / one:.2f} over 1 thread)"
    )
    if not args.no_radau:
        try:
            from hyperloop_env import verification
        except ImportError:
            print("solve_ivp comparison: hyperloop_env.verification not available")
            return
        res = verification.integrator_vs_radau()
        print(
            f"same 1 s run at 1000 km/h with irregularity: RK4 {res.info['rk4_wall_s']:.4f} s, "
            f"solve_ivp(Radau, rtol 1e-8) {res.info['radau_wall_s']:.2f} s -> "
            f"speed-up x{res.info['speedup']:.0f} (gap RMS error {res.value:.2e} of RMS)"
        )


if __name__ == "__main__":
    main()
