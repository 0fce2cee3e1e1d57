"""Where one headline task's time goes: its flights (the rollout engine) against the paper's
STS of the runs at the suite's levels (candidate fits, KS tests, block bootstrap).

    python speed/bench_capacity_task.py [--entrant lqr] [--condition paper-1000-straight]
                                        [--seeds 8] [--families roughness ...]
                                        [--sts-json PATH]

One :class:`~agents.evaluation.capacity.CapacityTask` as ``python -m agents.capacity`` plans
it (3 km, the headline's search settings, evaluation seeds from 1 000 000), on one core.
Prints the task's total wall time, the flights' (``TaskResult.wall_s``) and the STS's
(``TaskResult.sts_s``); the rest is building the controller and the searches' bookkeeping.
``--sts-json`` writes the task's per-level STS (``TaskResult.sts``) to compare two checkouts
with ``python scripts/sts_diff.py A.json B.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from agents.evaluation.benchmark import load_suite  # noqa: E402
from agents.evaluation.capacity import run_task  # noqa: E402
from agents.evaluation.capacity_benchmark import (  # noqa: E402
    DEFAULT_DISTANCE_KM,
    HEADLINE_FAMILIES,
    plan,
)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--entrant", default="lqr")
    ap.add_argument("--condition", default="paper-1000-straight")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--families", nargs="+", default=list(HEADLINE_FAMILIES))
    ap.add_argument("--sts-json", type=Path, default=None, help="write the task's level STS")
    args = ap.parse_args(argv)
    seeds = list(range(1_000_000, 1_000_000 + args.seeds))
    (task,), _ = plan(
        [args.entrant], [args.condition], args.families, seeds, DEFAULT_DISTANCE_KM, load_suite()
    )
    t0 = time.perf_counter()
    res = run_task(task)
    total = time.perf_counter() - t0
    print(
        f"{args.entrant} on {args.condition}, {args.seeds} seeds × {len(args.families)} "
        f"families: {total:.2f} s in all; flights {res.wall_s:.2f} s "
        f"({100 * res.wall_s / total:.1f} %), STS {res.sts_s:.2f} s "
        f"({100 * res.sts_s / total:.1f} %)"
    )
    if args.sts_json is not None:
        args.sts_json.write_text(json.dumps(res.sts, indent=1, default=str))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
