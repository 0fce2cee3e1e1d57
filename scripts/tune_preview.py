#!/usr/bin/env python
"""Choose the preview weight α of ``lqr-preview`` on validation seeds and store the scan.

Every candidate α flies the tune score's validation set (:mod:`agents.training.tune`:
the ``roughness`` capacity search of the headline, per-seed capacities on the validation
seeds from 2 000 000, never evaluation seeds) at the four paper conditions beside plain
``lqr`` on the same seeds; its score is the mean over the conditions of ln(paired capacity
ratio lqr-preview / lqr) (:func:`agents.evaluation.capacity_stats.compare_paired`). The
best α is written with the whole table and the command line to
``agents/controllers/lqr_preview_weight.json``; ``PREVIEW_WEIGHT`` in
:mod:`agents.controllers.lqr_preview` must equal it (tests/agents/controllers/
test_lqr_preview.py checks that).

    python scripts/tune_preview.py                       # default scan, writes the JSON
    python scripts/tune_preview.py --weights 0.5 --dry-run
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shlex
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from agents.evaluation.capacity_stats import compare_paired  # noqa: E402
from agents.training.tune import VALIDATION_KM, validation_capacities  # noqa: E402

OUT = ROOT / "agents" / "controllers" / "lqr_preview_weight.json"


def _floats(text: str) -> list[float]:
    return [float(x) for x in text.split(",") if x.strip()]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--weights", type=_floats, default=[0.25, 0.5, 0.75, 1.0])
    ap.add_argument("--seeds", type=int, default=16, help="validation seeds (default 16)")
    ap.add_argument("--distance-km", type=float, default=VALIDATION_KM)
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--dry-run", action="store_true", help="print the table, write nothing")
    args = ap.parse_args(argv)
    if not args.weights or any(not 0.0 <= w <= 2.0 for w in args.weights):
        ap.error("--weights must be numbers in [0, 2]")
    if args.seeds < 2:
        ap.error("--seeds must be >= 2")
    t0 = time.perf_counter()
    kw = {"seeds": args.seeds, "distance_km": args.distance_km}
    base = validation_capacities("lqr", **kw)
    rows = []
    for w in args.weights:
        caps = validation_capacities("lqr-preview", controller_kwargs={"preview_weight": w}, **kw)
        per = {}
        for cond, a in caps.items():
            b = base[cond]
            c = compare_paired(a["capacity"], a["censored"], b["capacity"], b["censored"])
            per[cond] = {
                "ratio": c.get("ratio"),
                "interval": [c.get("lo"), c.get("hi")],
                "verdict": c.get("verdict"),
            }
        score = sum(math.log(p["ratio"]) for p in per.values()) / len(per)
        rows.append({"weight": w, "score": score, "conditions": per})
        print(
            f"alpha {w:.3g}: score {score:+.4f}  "
            + "  ".join(f"{k} {v['ratio']:.3f}" for k, v in per.items()),
            flush=True,
        )
    best = max(rows, key=lambda r: r["score"])
    doc = {
        "method": (
            "mean over the four paper conditions of ln(paired roughness capacity ratio "
            "lqr-preview / lqr) on validation seeds (agents.training.tune's score)"
        ),
        "command": "python scripts/tune_preview.py " + shlex.join(argv or sys.argv[1:]),
        "seeds": [min(base[next(iter(base))]["seeds"]), max(base[next(iter(base))]["seeds"])],
        "distance_km": args.distance_km,
        "weight": best["weight"],
        "scan": rows,
        "wall_s": round(time.perf_counter() - t0, 1),
    }
    print(f"best alpha {best['weight']:.3g} (score {best['score']:+.4f})")
    if not args.dry_run:
        tmp = args.out.with_name(args.out.name + ".tmp")
        tmp.write_text(json.dumps(doc, indent=2) + "\n")
        os.replace(tmp, args.out)
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
