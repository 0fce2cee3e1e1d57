#!/usr/bin/env python
"""Ride comfort of controllers on common evaluation seeds, compared pairwise.

    python scripts/comfort_compare.py --controllers lqr mpc ppo ppo-memory sac \\
        --reference lqr --seeds 32 --distance-km 3 --out docs/benchmark/comfort

Per paper condition and seed, every controller flies the same run (the scenario's own
irregularity, evaluation seeds from 1 000 000, ``--distance-km`` km); its ISO 2631-1
comfort is the W_k-weighted RMS vertical acceleration a_wz [m/s²] of the capsule after
the 1 s settling time (:func:`hyperloop_env.comfort.ride_comfort`; a run that touched is
left out of both sides of a pair). Each controller is compared with ``--reference`` on
the common seeds by :func:`agents.evaluation.capacity_stats.compare_paired` applied to
a_wz (the geometric mean of the per-seed ratios, paired bootstrap 95 % interval,
Wilcoxon test, verdict with the ±5 % equivalence band). Lower a_wz is a smoother ride,
so "W_k no worse than the reference" means the verdict is ``below`` or ``equivalent``.
Writes ``comfort.json`` and ``comfort.md`` to ``--out`` (refused if they exist, unless
``--overwrite``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from agents.evaluation.capacity_stats import compare_paired  # noqa: E402
from agents.evaluation.outputs import atomic_write_text  # noqa: E402
from agents.evaluation.rollout import run_episodes  # noqa: E402
from agents.evaluation.seeds import EVAL_SEED0  # noqa: E402
from hyperloop_env.comfort import ride_comfort  # noqa: E402
from hyperloop_env.scenarios import PAPER_SCENARIOS  # noqa: E402

SETTLE_S = 1.0


def a_wz(controller: str, condition: str, seeds: list[int], km: float) -> list[float | None]:
    """W_k-weighted RMS heave acceleration [m/s²] per seed (None: the run touched)."""
    out: list[float | None] = []
    for e in run_episodes(controller, condition, seeds, km, None):
        if e.terminated:
            out.append(None)
        else:
            out.append(
                ride_comfort(e.acc_m_s2[1:, 0], e.acc_m_s2[1:, 1], e.dt_s, SETTLE_S).a_wz_m_s2
            )
    return out


def compare(a: list[float | None], b: list[float | None]) -> dict:
    keep = [i for i in range(len(a)) if a[i] is not None and b[i] is not None]
    x = np.array([a[i] for i in keep])
    y = np.array([b[i] for i in keep])
    no = np.zeros(len(keep), dtype=bool)
    res = compare_paired(x, no, y, no)
    return {"n": len(keep), **{k: res[k] for k in ("ratio", "lo", "hi", "p_value", "verdict")}}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--controllers", nargs="+", required=True)
    ap.add_argument("--reference", default="lqr")
    ap.add_argument("--conditions", nargs="+", default=list(PAPER_SCENARIOS))
    ap.add_argument("--seeds", type=int, default=32)
    ap.add_argument(
        "--seed0",
        type=int,
        default=EVAL_SEED0,
        help="first seed (default: the evaluation range; a search's selection uses the "
        "validation seeds, agents.evaluation.seeds.VALIDATION_SEED0)",
    )
    ap.add_argument("--distance-km", type=float, default=3.0)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--overwrite", action="store_true")
    args = ap.parse_args(argv)
    if args.seeds < 2 or not args.distance_km > 0:
        ap.error("--seeds must be >= 2 and --distance-km > 0")
    files = [args.out / "comfort.json", args.out / "comfort.md"]
    if any(f.exists() for f in files) and not args.overwrite:
        ap.error(f"{args.out} holds a comfort comparison (pass --overwrite)")
    names = list(dict.fromkeys([args.reference, *args.controllers]))
    seeds = list(range(args.seed0, args.seed0 + args.seeds))
    t0 = time.perf_counter()
    per: dict[str, dict[str, list[float | None]]] = {}
    for cond in args.conditions:
        per[cond] = {c: a_wz(c, cond, seeds, args.distance_km) for c in names}
        print(f"{cond}: done ({time.perf_counter() - t0:.0f} s)", flush=True)
    rows = []
    for cond in args.conditions:
        ref = per[cond][args.reference]
        for c in names:
            vals = [v for v in per[cond][c] if v is not None]
            row = {
                "condition": cond,
                "controller": c,
                "a_wz_mean_m_s2": float(np.mean(vals)) if vals else None,
                "contacts": sum(v is None for v in per[cond][c]),
            }
            if c != args.reference:
                row["vs_reference"] = compare(per[cond][c], ref)
            rows.append(row)
    doc = {
        "command": "python scripts/comfort_compare.py " + " ".join(argv or sys.argv[1:]),
        "reference": args.reference,
        "seeds": [seeds[0], seeds[-1]],
        "distance_km": args.distance_km,
        "settle_s": SETTLE_S,
        "wall_s": time.perf_counter() - t0,
        "rows": rows,
        "a_wz_per_seed": per,
    }
    md = [
        f"W_k-weighted RMS heave acceleration a_wz [m/s²], mean over {args.seeds} seeds "
        f"({seeds[0]}–{seeds[-1]}) × {args.distance_km:g} km, and the paired ratio to "
        f"`{args.reference}` (lower is smoother; runs that touched are left out of both "
        "sides: `comfort.json` counts them):",
        "",
        f"| condition | controller | a_wz [m/s²] | / `{args.reference}` (paired) [95 %] "
        "| verdict |",
        "|---|---|---:|---|---|",
    ]
    for r in rows:
        v = r.get("vs_reference")
        cmp = f"{v['ratio']:.3f} [{v['lo']:.3f}, {v['hi']:.3f}]" if v else "—"
        mean = f"{r['a_wz_mean_m_s2']:.4f}" if r["a_wz_mean_m_s2"] is not None else "n/a"
        verdict = (
            {"A above B": "rougher", "B above A": "smoother"}.get(v["verdict"], v["verdict"])
            if v
            else ""
        )
        md.append(f"| {r['condition']} | {r['controller']} | {mean} | {cmp} | {verdict} |")
    args.out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(files[0], json.dumps(doc, indent=1) + "\n")
    atomic_write_text(files[1], "\n".join(md) + "\n")
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
