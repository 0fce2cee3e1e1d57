"""Fragility-evaluation benchmarks: control-loop throughput (single vs batched, with the
controller and the streaming statistics), the batched loop of each controller against the
bare physics, the wall time of a roughness sweep, and the peak memory of a long run.

    python speed/bench_fragility.py [--part throughput|loop|sweep|memory|all]
        [--batch 64] [--sweep-km 2] [--memory-km 1000] [--busy 1]

* throughput: control steps per second of ``run_block`` (env + controller + streaming),
  one seed in the single env vs ``--batch`` seeds in the native vector env, for every
  controller; a controller is run batched when it has ``act_batch`` (PID/LQR are picked up
  automatically once they do). Targets: ≥ 150 000 steps/s batched for the linear
  controllers.
* sweep: 4 controllers (passive, pid, lqr, ppo) × 8 roughness levels × D km of flight per
  case at 1000 km/h on ``--workers`` local processes (10 seeds × D/10 km each), for each D
  of ``--sweep-km``; with two distances the wall time is fitted as ``a + b·D`` (fixed
  costs: worker start-up, model loading, STS fits; per-km cost: the control loop) and
  extrapolated to 100 km per case — labelled as an extrapolation unless 100 is measured.
  Target: < 10 minutes for 100 km.
* loop: the closed loop against the bare physics, per controller (passive, pid, lqr, ppo,
  ppo-guidance — the last on ``actuators="levitation+guidance"``), for one batch of
  ``--batch`` seeds on paper-1000-straight: vehicle-steps/s of the bare physics (the
  simulator's ``step_full(commands, parallel=False)`` of a twin env built and reset alike)
  and of the loop (``ctrl.act_batch`` + ``venv.step``, the env built as the runner builds
  it: ``batch_rollout.batch_env``), timed step by step, alternating (one loop step, then one
  bare step with the commands that loop step applied, so that the bare physics flies the
  same flight — checked: equal records at the end — ``--loop-steps`` of each) in one
  process so that a drifting machine load hits both alike; steps/s and the ratio are from
  the median step times (robust to the preemptions of a shared machine; the ratio of the
  total times is printed beside), with the loop's step split into ``act_batch`` and
  ``venv.step``
  (physics included). Printed beside as well: the paired ratio, the median over the steps of
  each step's bare physics / its loop step, the two timed back to back. A host that switches
  between a fast and a slow mode for seconds at a time (as this project's machine does)
  moves the medians of the two series apart when the switch falls inside a run; it moves a
  pair only when it falls between its two halves.
  ``--busy K`` keeps K extra processes spinning (``while True: pass``) meanwhile: the loaded
  case. Target: loop ≥ 90 % of the bare physics. Also printed: the ceiling
  physics / (physics + act_batch), the ratio the loop would reach if the environment around
  the physics cost nothing (what the controller's own arithmetic allows), and for a learned
  agent its actor's FLOPs per row (2 × the multiply-adds of its layers) and the rate its
  ``act_batch`` reaches.
* memory: peak resident memory (``resource.getrusage``) of one passive run of
  ``--memory-km`` (default 800: the environment caps one run's guideway profile at
  256 MiB, about 838 km) in a fresh process, against a 1 km run: what grows is the
  environment's profile, not the statistics.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from agents.controllers import registry  # noqa: E402
from agents.evaluation.batch_rollout import BlockSpec, build_controller, run_block  # noqa: E402
from agents.evaluation.rollout import episode_config  # noqa: E402

CONTROLLERS = tuple(registry.entrants(registry.LEVITATION))  # passive, pid, lqr, ppo
LEVELS = (0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.7)


def raw_simulator(cfg, n: int, seconds: float = 2.0) -> float:  # type: ignore[no-untyped-def]
    """Vehicle-steps/s of the bare physics (BatchSimulator.step_full, neutral commands), the
    bound of any closed loop; measured beside the runner because the machine is shared."""
    import numpy as np

    from hyperloop_env.physics.simulator import BatchSimulator
    from hyperloop_env.vector_env import PARALLEL_MIN_ENVS

    sim = BatchSimulator(cfg.resolve().base, n)
    sim.reset(list(range(n)))
    cmd = np.stack([s.neutral_command for s in sim._singles])
    sim.step_full(cmd, parallel=n >= PARALLEL_MIN_ENVS)
    k, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        sim.step_full(cmd, parallel=n >= PARALLEL_MIN_ENVS)
        k += 1
    return k * n / (time.perf_counter() - t0)


def throughput(batch: int, km: float) -> dict[str, dict[str, float]]:
    out: dict[str, dict[str, float]] = {}
    cfg = episode_config("paper-1000-straight", km, None, {})
    raw1, rawb = raw_simulator(cfg, 1), raw_simulator(cfg, batch)
    print(
        f"  bare physics (same moment): 1 vehicle {raw1:.0f} steps/s, batch of {batch} "
        f"{rawb:.0f} vehicle-steps/s"
    )
    out["bare_physics"] = {"single": raw1, "batched": rawb}
    for name in CONTROLLERS:
        spec = BlockSpec(name, cfg, (0,), settle_s=0.1)
        run_block(
            BlockSpec(
                name, episode_config("paper-1000-straight", 0.05, None, {}), (0,), settle_s=0.0
            )
        )  # warm-up (compilation, model loading)
        r1 = run_block(BlockSpec(name, cfg, (0,), settle_s=0.1, batched=False))
        row = {"single": r1.steps / r1.wall_s}
        if callable(getattr(build_controller(spec), "act_batch", None)):
            rb = run_block(BlockSpec(name, cfg, tuple(range(batch)), settle_s=0.1, thin_stride=16))
            row["batched"] = rb.steps / rb.wall_s
            row["ratio"] = row["batched"] / row["single"]
        out[name] = row
        b = (
            f"{row['batched']:>8.0f} (x{row['ratio']:.1f}; {row['batched'] / rawb:.0%} of the "
            "bare physics)"
            if "batched" in row
            else "   (no act_batch)"
        )
        print(
            f"  {name:>8}: single {row['single']:>7.0f} steps/s ({row['single'] / raw1:.0%} of "
            f"the bare physics)   batched({batch}) {b}",
            flush=True,
        )
    return out


LOOP_CONTROLLERS = tuple(  # the headline entrants: passive, pid, lqr, ppo, ppo-guidance
    dict.fromkeys(registry.entrants(registry.LEVITATION) + registry.entrants(registry.GUIDED))
)
GUIDED = {  # the entrants that only command guidance too: ppo-guidance
    n: {"actuators": registry.GUIDED}
    for n in LOOP_CONTROLLERS
    if registry.LEVITATION not in registry.controller_spec(n).actuators
}
LOOP_TARGET = 0.9


def loop_ratio(name: str, batch: int, steps: int = 1000, km: float = 5.0) -> dict[str, float]:
    """Bare physics vs the closed loop of ``name`` on the same batch (module docstring)."""
    import numpy as np

    from agents.evaluation.batch_rollout import batch_env

    cfg = episode_config("paper-1000-straight", km, None, GUIDED.get(name, {}))
    seeds = list(range(batch))
    twin = batch_env(cfg, batch)  # its simulator is the bare physics, reset alike
    twin.reset(seed=seeds)
    sim = twin.sim
    venv = batch_env(cfg, batch)  # as the runner builds it
    ctrl = build_controller(BlockSpec(name, cfg, (0,)))
    obs, _ = venv.reset(seed=seeds)
    if callable(getattr(ctrl, "reset_batch", None)):
        ctrl.reset_batch(np.ones(batch, dtype=np.bool_))
    act, step, clock = ctrl.act_batch, venv.step, time.perf_counter_ns
    applied = venv._cmd  # the full command array the env's last step applied [A]
    t = np.zeros((3, steps))  # bare physics, act_batch, venv.step
    ends = 0
    for k in range(-50, steps):  # 50 steps of warm-up (compilation, caches)
        t0 = clock()
        a = act(obs)
        t1 = clock()
        obs, _, te, tr, _ = step(a)
        t2 = clock()
        sim.step_full(applied, parallel=False)  # the same commands: the same flight
        t3 = clock()
        if k >= 0:
            t[:, k] = t3 - t2, t1 - t0, t2 - t1
            ends += int(te.sum() + tr.sum())
    same = bool(np.array_equal(sim.MEAS, venv.sim.MEAS))
    twin.close()
    venv.close()
    loop = t[1] + t[2]
    mb, ml = float(np.median(t[0])), float(np.median(loop))
    pol = getattr(ctrl, "_np_policy", None)  # a learned agent's compiled actor
    flops = (
        0 if pol is None else int(2 * sum(int(n_i) * int(n_o) for _, n_i, n_o, _ in pol._layout))
    )
    act_us = float(np.median(t[1])) / 1e3
    return {
        "ceiling": mb / (mb + float(np.median(t[1]))),  # the loop at zero environment cost
        "actor_flops_per_row": flops,
        "actor_gflop_s": flops * batch / (act_us * 1e3) if flops else 0.0,
        "bare_steps_s": batch * 1e9 / mb,
        "loop_steps_s": batch * 1e9 / ml,
        "ratio": mb / ml,
        "ratio_total": float(t[0].sum() / loop.sum()),
        "ratio_paired": float(np.median(t[0] / loop)),
        "bare_us": mb / 1e3,
        "act_us": act_us,
        "env_us": float(np.median(t[2])) / 1e3,
        "episode_ends": ends,
        "same_flight": same,
    }


def loop_part(batch: int, names: list[str], steps: int, busy: int) -> dict[str, dict[str, float]]:
    procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(busy)]
    out = {}
    try:
        for name in names:
            la = os.getloadavg()[0]
            r = loop_ratio(name, batch, steps)
            out[name] = {**r, "load_1min": la}
            note = f", {r['episode_ends']} episode end(s)" if r["episode_ends"] else ""
            note += "" if r["same_flight"] else ", NOT the same flight"
            verdict = "" if r["ratio"] >= LOOP_TARGET else "  < target"
            if r["actor_flops_per_row"]:
                note += (
                    f"; actor {r['actor_flops_per_row']} FLOPs/row (multiply-adds x 2) at "
                    f"{r['actor_gflop_s']:.1f} GFLOP/s"
                )
            note += f"; ceiling physics/(physics + act_batch) {r['ceiling']:.0%}"
            print(
                f"  {name:>13}: physics {r['bare_steps_s']:>7.0f}  loop "
                f"{r['loop_steps_s']:>7.0f} vehicle-steps/s  loop/physics {r['ratio']:5.1%}"
                f"{verdict} (paired {r['ratio_paired']:.1%}, total times {r['ratio_total']:.0%})"
                f"  a step: physics "
                f"{r['bare_us']:.0f} us | act_batch {r['act_us']:.0f} + venv.step "
                f"{r['env_us']:.0f} us  (load {la:.1f}{note})",
                flush=True,
            )
    finally:
        for p in procs:
            p.kill()
            p.wait()
    return out


def sweep(km: float, workers: int) -> dict[str, float]:
    from agents.evaluation.fragility import fragility

    t0 = time.perf_counter()
    res = fragility(
        list(CONTROLLERS),
        ["paper-1000-straight"],
        "roughness",
        list(LEVELS),
        seeds=10,
        distance_km=km / 10,
        workers=workers,
        n_boot=100,
        settle_s=0.1,
        n_boot_fragility=200,
        progress=False,
        out_dir=Path(tempfile.mkdtemp(prefix="bench_fragility_")),
    )
    wall = time.perf_counter() - t0
    steps = sum(r["steps"] for r in res["levels"])
    planned = len(CONTROLLERS) * len(LEVELS) * km * 1000 / (1000 / 3.6 * 1e-3)
    for f in res["fits"]:
        print(f"  {f['controller']:>8}: {f['summary']}")
    return {
        "wall_s": wall,
        "steps": steps,
        "planned_steps": planned,
        "km_per_case": km,
        "out": res["paths"].get("report", ""),
    }


def _child_memory(km: float) -> None:
    cfg = episode_config("paper-1000-straight", km, None, {})
    from agents.evaluation.batch_rollout import max_steps
    from agents.evaluation.fragility import DEFAULT_MAX_SAMPLES

    stride = max(1, -(-max_steps(cfg) // DEFAULT_MAX_SAMPLES))  # the sweep's thinning rule
    r = run_block(BlockSpec("passive", cfg, (0,), settle_s=1.0, thin_stride=stride, batched=False))
    peak_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(
        json.dumps(
            {
                "km": km,
                "steps": r.steps,
                "wall_s": r.wall_s,
                "peak_rss_mb": peak_kb / 1024,
                "thinned_mb": sum(x.thinned_gap.nbytes for x in r.runs) / 1e6,
            }
        )
    )


def memory(km: float) -> dict[str, dict[str, float]]:
    out = {}
    for k in (1.0, km):
        p = subprocess.run(
            [sys.executable, __file__, "--child-memory", str(k)],
            capture_output=True,
            text=True,
            cwd=ROOT,
        )
        if p.returncode:
            raise RuntimeError(f"memory run of {k:g} km failed:\n{p.stderr[-3000:]}")
        out[str(k)] = json.loads(p.stdout.strip().splitlines()[-1])
        print(f"  {k:g} km: {out[str(k)]}", flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--part", default="all", choices=("throughput", "loop", "sweep", "memory", "all")
    )
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--throughput-km", type=float, default=3.0)
    ap.add_argument("--sweep-km", type=float, nargs="+", default=[1.0, 3.0])
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument(
        "--memory-km",
        type=float,
        default=800.0,
        help="the environment refuses runs whose profile exceeds 256 MiB "
        "(MAX_PROFILE_BYTES: about 838 km)",
    )
    ap.add_argument("--loop-controllers", nargs="+", default=list(LOOP_CONTROLLERS))
    ap.add_argument("--loop-steps", type=int, default=1000, help="timed steps of each kind")
    ap.add_argument(
        "--busy",
        type=int,
        default=0,
        help="extra spinning processes during the loop part (the loaded case)",
    )
    ap.add_argument("--child-memory", type=float, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child_memory is not None:
        _child_memory(args.child_memory)
        return 0
    print(f"os.cpu_count() = {os.cpu_count()}, load average {os.getloadavg()}")
    if args.part in ("throughput", "all"):
        print(f"throughput (env + controller + streaming, {args.throughput_km:g} km runs):")
        throughput(args.batch, args.throughput_km)
    if args.part in ("loop", "all"):
        print(
            f"loop vs bare physics (batch of {args.batch}, paper-1000-straight, "
            f"{args.loop_steps} steps of each, alternating; {args.busy} spinning "
            "process(es) beside):"
        )
        loop_part(args.batch, args.loop_controllers, args.loop_steps, args.busy)
    if args.part in ("sweep", "all"):
        walls = []
        for km in args.sweep_km:
            print(
                f"sweep: 4 controllers x 8 roughness levels x {km:g} km per case "
                f"(10 seeds x {km / 10:g} km), {args.workers} worker(s):"
            )
            s = sweep(km, args.workers)
            walls.append((km, s["wall_s"]))
            print(
                f"  wall {s['wall_s']:.1f} s for {s['steps']:.0f} control steps "
                f"(planned {s['planned_steps']:.0f}; runs end early at contact)",
                flush=True,
            )
        if any(km == 100 for km, _ in walls):
            w = dict(walls)[100]
            print(f"  100 km per case: {w / 60:.1f} min (measured; target < 10 min)")
        elif len(walls) >= 2:
            (k1, w1), (k2, w2) = walls[0], walls[-1]
            b = (w2 - w1) / (k2 - k1)
            a = w1 - b * k1
            print(
                f"  fit wall = {a:.1f} s + {b:.2f} s/km -> 100 km per case: "
                f"{(a + 100 * b) / 60:.1f} min (EXTRAPOLATED from {k1:g} and {k2:g} km; "
                "target < 10 min)"
            )
        else:
            km, w = walls[0]
            print(
                f"  100 km per case: {w * 100 / km / 60:.1f} min (EXTRAPOLATED x{100 / km:g}, "
                "fixed costs scaled too: an upper estimate; target < 10 min)"
            )
    if args.part in ("memory", "all"):
        print(
            f"memory: one passive run, peak RSS of a fresh process (1 km vs {args.memory_km:g} km):"
        )
        memory(args.memory_km)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
