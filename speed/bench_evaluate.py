"""Time the evaluation of 3 controllers (passive, pid, lqr) x 4 paper scenarios x 10 km x
1 seed (target: < 2 minutes on a 2-core machine).

    python speed/bench_evaluate.py [--distance-km 10] [--out /tmp/bench_evaluate]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from agents.controllers.registry import default_controllers  # noqa: E402
from agents.evaluation.evaluate import evaluate, summary_table  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--distance-km", type=float, default=10.0)
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--no-figures", action="store_true")
    args = ap.parse_args(argv)
    out = args.out or Path(tempfile.mkdtemp(prefix="bench_evaluate_"))
    t0 = time.perf_counter()
    res = evaluate(
        default_controllers(),  # passive, pid, lqr
        ["paper"],
        args.distance_km,
        1,
        "repelling",
        out,
        settle_s=1.0,
        progress=False,
        figures=not args.no_figures,
    )
    wall = time.perf_counter() - t0
    steps = sum(r["metrics"]["steps_total"] for r in res["results"])
    sim_wall = sum(r["metrics"]["wall_s"] for r in res["results"])
    print(summary_table(res["results"]))
    print(
        f"bench_evaluate: 3 controllers x 4 paper scenarios x {args.distance_km:g} km x 1 seed: "
        f"{wall:.1f} s total ({steps} control steps, closed-loop {sim_wall:.1f} s = "
        f"{1e6 * sim_wall / max(steps, 1):.1f} us/step; target < 120 s) -> {out}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
