"""What the vector env's step costs around the physics, part by part.

    python speed/bench_env_step.py [--rows 64] [--controller lqr] [--steps 2000]

The engine's vector env (``agents.evaluation.engine.vector_env``: one thread, no info) of
``--rows`` rows on paper-1000-straight, flown ``--controller`` for 200 steps. Then, each
the median over ``--steps`` calls (µs):

* ``step_outcome``: the compiled step after the physics (observation, reward, counters);
* ``commanded_currents``: the compiled action → current map;
* ``action check``: the controller's action check (``all_finite``) on its last action;
* ``env step without physics``: ``venv.step`` with the simulator's step replaced by one
  that returns its records (the Python, the allocations and the two compiled calls);
* ``act_batch``: the controller's ``act_batch`` as the engine calls it (its action check
  included) on the last observation, again and again (its state moves on: timing only).

Run alone, with warm caches: inside the loop every part runs a little slower
(``speed/bench_fragility.py --part loop`` measures the loop itself).
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

from agents.controllers.base import all_finite  # noqa: E402
from agents.evaluation.batch_rollout import BlockSpec, batch_env, build_controller  # noqa: E402
from agents.evaluation.rollout import episode_config  # noqa: E402
from hyperloop_env import kernels  # noqa: E402
from hyperloop_env.vector_env import _CONTACT, PREVIEW  # noqa: E402


def _median_us(fn, steps: int) -> float:  # type: ignore[no-untyped-def]
    clock = time.perf_counter_ns
    t = np.empty(steps)
    for k in range(steps):
        t0 = clock()
        fn()
        t[k] = clock() - t0
    return float(np.median(t)) / 1e3


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=64)
    ap.add_argument("--controller", default="lqr")
    ap.add_argument("--steps", type=int, default=2000)
    args = ap.parse_args(argv)
    print(f"os.cpu_count() = {os.cpu_count()}, load average {os.getloadavg()}")
    n = args.rows
    cfg = episode_config("paper-1000-straight", 5.0)
    venv = batch_env(cfg, n)
    ctrl = build_controller(BlockSpec(args.controller, cfg, (0,)))
    obs, _ = venv.reset(seed=list(range(n)))
    if callable(getattr(ctrl, "reset_batch", None)):
        ctrl.reset_batch(np.ones(n, dtype=np.bool_))
    for _ in range(200):
        a = ctrl.act_batch(obs)
        obs, *_ = venv.step(a)
    s = venv.sim
    # copies of the env's state: the timed calls must not move its episode on
    prev, mode, steps = venv._prev.copy(), venv._mode.copy(), venv._steps.copy()
    obs_b, terms, rew = venv._obs.copy(), venv._terms.copy(), venv._reward.copy()
    never = np.full(n, 2**62, dtype=np.int64)
    flags = [np.empty(n, dtype=np.bool_) for _ in range(3)]
    no_rows, prev_done = np.zeros(0, dtype=np.int64), np.zeros(n, dtype=np.bool_)
    cmd = venv._cmd.copy()

    def outcome() -> None:
        kernels.step_outcome(
            s.MEAS, s.P, prev, mode, obs_b, venv._offsets, PREVIEW, venv._weights, terms,
            rew, prev_done, steps, never, no_rows, _CONTACT, *flags,
        )  # fmt: skip

    def currents() -> None:
        kernels.commanded_currents(
            a, venv._base, venv._neutral, venv.action_scale, venv._index, cmd
        )

    parts = {
        "step_outcome": outcome,
        "commanded_currents": currents,
        "action check": lambda: all_finite(a),
    }
    res = {name: _median_us(fn, args.steps) for name, fn in parts.items()}
    venv._max_steps[:] = 2**62  # no row ends while the physics stands still
    s.step_full = lambda commands, parallel=True, rows=None: s.MEAS  # the physics skipped
    res["env step without physics"] = _median_us(lambda: venv.step(a), args.steps)
    res["act_batch"] = _median_us(lambda: ctrl.act_batch(obs), args.steps)
    print(f"{n} rows, {args.controller}'s actions, median of {args.steps} calls:")
    for name, us in res.items():
        print(f"  {name:>26}: {us:6.2f} us")
    venv.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
