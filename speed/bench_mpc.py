"""The MPC's cost per control step: its batched loop beside the LQR's, and its QP solves.

    python speed/bench_mpc.py [--batch 64] [--steps 1000] [--roughness 1.0 0.5]
    python speed/bench_mpc.py --controller mpc-preview     # the MPC with the preview

For each roughness severity: ``--batch`` seeds on paper-1000-straight flown ``--steps``
control steps by the MPC (default design: 20 ms horizon) and, in the same process and on
twins of the same batch, by the LQR, alternating step by step. Printed: the median
``act_batch`` time of each (µs per step of the whole batch), the share of vehicle-steps
that needed a QP (the others take the unconstrained optimum, the LQR's command), and the
DAQP solves' wall time per QP (median and 95th percentile, Python included), their mean
number of iterations and the share that did not end optimal. Timing stops for a
controller when one of its rows touches (the batch then stops stepping).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from agents.evaluation.batch_rollout import BlockSpec, batch_env, build_controller  # noqa: E402
from agents.evaluation.rollout import episode_config  # noqa: E402


def run(batch: int, steps: int, roughness: float, controller: str = "mpc") -> dict[str, float]:
    cfg = episode_config(
        "paper-1000-straight", 5.0, None, {"disturbances": {"roughness": roughness}}
    )
    seeds = list(range(10_000, 10_000 + batch))  # the evaluation range
    envs, ctrls, obs = {}, {}, {}
    for name in ("mpc", "lqr"):
        envs[name] = batch_env(cfg, batch)
        obs[name], _ = envs[name].reset(seed=seeds)
        ctrls[name] = build_controller(BlockSpec(controller if name == "mpc" else name, cfg, (0,)))
        ctrls[name].reset_batch(np.ones(batch, dtype=bool))
    mpc = getattr(ctrls["mpc"], "controller", ctrls["mpc"])  # inside the action check
    qp_times: list[float] = []
    solve = mpc._solve

    def timed(*a):  # noqa: ANN002, ANN202
        t0 = time.perf_counter()
        r = solve(*a)
        qp_times.append(time.perf_counter() - t0)
        return r

    mpc._solve = timed
    t = {"mpc": [], "lqr": []}
    alive = {n: np.ones(batch, dtype=bool) for n in t}
    for k in range(-20, steps):
        for name in ("mpc", "lqr"):
            if not alive[name].all():
                continue
            t0 = time.perf_counter_ns()
            a = ctrls[name].act_batch(obs[name])
            t1 = time.perf_counter_ns()
            obs[name], _, te, tr, _ = envs[name].step(a)
            alive[name] &= ~(te | tr)
            if k >= 0:
                t[name].append(t1 - t0)
    for e in envs.values():
        e.close()
    qp = np.array(qp_times) * 1e6
    s = mpc.stats
    return {
        "mpc_act_us": float(np.median(t["mpc"])) / 1e3,
        "lqr_act_us": float(np.median(t["lqr"])) / 1e3,
        "mpc_steps": len(t["mpc"]),
        "qp_share": s["qp_solves"] / max(1, s["rows"]),
        "qp_median_us": float(np.median(qp)) if qp.size else float("nan"),
        "qp_p95_us": float(np.percentile(qp, 95)) if qp.size else float("nan"),
        "qp_unsolved": s["qp_unsolved"] / max(1, s["qp_solves"]),
        "qp_solves": s["qp_solves"],
        "qp_iters": s["qp_iterations"] / max(1, s["qp_solves"]),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--roughness", type=float, nargs="+", default=[0.3, 0.45])
    ap.add_argument("--controller", choices=["mpc", "mpc-preview"], default="mpc")
    args = ap.parse_args(argv)
    print(f"os.cpu_count() = {os.cpu_count()}, load average {os.getloadavg()}")
    for r in args.roughness:
        m = run(args.batch, args.steps, r, args.controller)
        print(
            f"roughness {r:g}: act_batch {args.controller} {m['mpc_act_us']:.0f} us, lqr "
            f"{m['lqr_act_us']:.0f} us per step of {args.batch} rows ({m['mpc_steps']} steps);"
            f" QP on {100 * m['qp_share']:.2f} % of vehicle-steps ({m['qp_solves']} QPs), "
            f"per QP {m['qp_median_us']:.0f} us median, {m['qp_p95_us']:.0f} us p95, "
            f"{m['qp_iters']:.1f} iterations on average, not optimal: "
            f"{100 * m['qp_unsolved']:.1f} %"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
