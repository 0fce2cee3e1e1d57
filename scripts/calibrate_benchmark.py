#!/usr/bin/env python
"""Calibrate the benchmark suite's severity levels on the passive and PID baselines.

    python scripts/calibrate_benchmark.py [--out docs/benchmark] [--seeds 8] [--distance-km 5]

For every family of :data:`GRIDS` it runs the fragility sweep (``agents.fragility``) of the
passive and PID baselines — never a learned agent — over the four paper conditions (or the
family's conditions) on the calibration seeds (from :data:`CALIBRATION_SEED0`, disjoint
from the evaluation and validation seeds), fits the lognormal fragility functions and
chooses three levels per family: the geometric-mean median capacity of the passive
baseline over the conditions ("low"), of PID ("high"), and their geometric middle
("mid"), each rounded to two significant digits and clipped to the grid. Families the
passive vehicle does not feel (a coil fault, a sensor dropout act on active control
only) are calibrated on PID alone, on top of a fixed roughness. The chosen levels, the
fits and each baseline's contact probability per 10 km at each level (with the band check:
0.05–0.95 per 10 km, or a P(unsteady) in 1e-4–0.5) go to
``agents/evaluation/benchmark_suite.json`` and ``docs/benchmark/calibration.md``.

The suite is calibrated once; it is never re-tuned to an agent.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from agents.evaluation.benchmark import CALIBRATION_SEED0  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))


GRIDS: dict[str, dict[str, Any]] = {
    # family: severity grid, baselines, fixed disturbances, conditions ("paper" = the four)
    "roughness": {
        "levels": [0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.8],
        "controllers": ["passive", "pid"],
    },
    "pier_settlement": {
        "levels": [0.5e-3, 1e-3, 2e-3, 3e-3, 4e-3, 6e-3],
        "controllers": ["passive", "pid"],
    },
    "joint_steps": {
        "levels": [0.25e-3, 0.5e-3, 1e-3, 1.5e-3, 2e-3, 3e-3],
        "controllers": ["passive", "pid"],
    },
    "thermal_camber": {
        "levels": [2e-3, 4e-3, 6e-3, 8e-3, 12e-3],
        "controllers": ["passive", "pid"],
    },
    # felt only under active control: PID alone, on a guideway as rough as the passive
    # capacity (0.2; below PID's roughness capacity at every paper condition)
    "actuator_fault": {
        "levels": [0.25, 0.5, 0.75, 0.9, 1.0],
        "controllers": ["pid"],
        "fixed": {"roughness": 0.2},
    },
    "sensor_dropout": {
        "levels": [0.05, 0.1, 0.2, 0.4, 0.6, 0.8],
        "controllers": ["pid"],
        "fixed": {"roughness": 0.2},
    },
}


def _round2(x: float) -> float:
    return float(f"{x:.2g}")


def calibrate_family(
    family: str, spec: dict[str, Any], seeds: int, km: float, workers: int, out: Path
) -> dict[str, Any]:
    from agents.evaluation.benchmark import capacity_estimate
    from agents.evaluation.fragility import fragility
    from hyperloop_env.scenarios import PAPER_SCENARIOS

    res = fragility(
        spec["controllers"],
        list(PAPER_SCENARIOS),
        family,
        spec["levels"],
        seeds=list(range(CALIBRATION_SEED0, CALIBRATION_SEED0 + seeds)),
        distance_km=km,
        fixed=spec.get("fixed"),
        n_boot=50,
        n_boot_fragility=200,
        workers=workers,
        out_dir=out / family,
        overwrite=True,
        progress=False,
    )
    caps: dict[str, dict[str, float]] = {}
    for f in res["fits"]:
        caps.setdefault(f["controller"], {})[f["condition"]] = capacity_estimate(f["fit"])
    geo = {
        c: float(np.exp(np.mean(np.log([v for v in d.values() if v > 0])))) for c, d in caps.items()
    }
    lo_g, hi_g = min(spec["levels"]), max(spec["levels"])
    if "passive" in geo:
        low, high = geo["passive"], geo["pid"]
    else:  # PID only: its capacity and a level on each side
        low, high = geo["pid"] / 1.5, geo["pid"] * 1.5
    mid = math.sqrt(low * high)
    levels = sorted({_round2(min(max(v, lo_g), hi_g)) for v in (low, mid, high)})
    band = []
    scale = 10.0 / km
    for r in res["levels"]:
        p10 = 1.0 - (1.0 - r["p_contact"]) ** scale  # per run of km → per 10 km
        pu = r.get("p_unsteady")
        in_band = (0.05 <= p10 <= 0.95) or (pu is not None and 1e-4 <= pu <= 0.5)
        band.append(
            {
                "controller": r["controller"],
                "condition": r["condition"],
                "level": r["level"],
                "p_contact_run": r["p_contact"],
                "p_contact_10km": p10,
                "p_unsteady": pu,
                "in_band": bool(in_band),
            }
        )
    return {
        "family": family,
        "grid": spec["levels"],
        "fixed": spec.get("fixed", {}),
        "controllers": spec["controllers"],
        "capacity": caps,
        "geometric_capacity": geo,
        "levels": levels,
        "band": band,
        "report": str(out / family / "report.md"),
    }


def fitting_grid(levels: list[float], lo_g: float, hi_g: float) -> list[float]:
    """The fragility grid of a family: the suite levels and two more on each side, ×/÷ 1.34
    and ×/÷ 1.8 of the outer levels (so a controller better or worse than the baselines
    still has levels around its capacity), two significant digits, inside the family's
    valid range (``lo_g``/``hi_g`` only bound the calibration grid and are not used)."""
    lo, hi = min(levels), max(levels)
    pts = {_round2(lo / 1.8), _round2(lo / 1.34), *levels, _round2(hi * 1.34), _round2(hi * 1.8)}
    return sorted(p for p in pts if p > 0)


def suite_from_calibration(
    cal: dict[str, Any], seeds: int, km: float, wall_s: float | None
) -> dict[str, Any]:
    """The suite file's content from the calibration results."""
    fams, excluded = {}, {}
    for f, c in cal.items():
        caps = [v for d in c["capacity"].values() for v in d.values()]
        inside = [v for v in caps if math.isfinite(v) and v < max(c["grid"])]
        if not inside:  # no baseline's capacity lies inside the grid: not a benchmark level
            excluded[f] = (
                "no baseline reaches the measurable band on the calibration grid "
                f"{c['grid']} (capacities {c['capacity']}); see "
                "docs/benchmark/calibration.md"
            )
            continue
        fams[f] = {
            "levels": c["levels"],
            "grid": fitting_grid(c["levels"], min(c["grid"]), max(c["grid"])),
            "fixed": c["fixed"],
            "calibrated_on": c["controllers"],
            "geometric_capacity": c["geometric_capacity"],
        }
    return {
        "description": "benchmark suite: severity levels per disturbance family, calibrated "
        "on the passive and PID baselines by scripts/calibrate_benchmark.py "
        "(never on a learned agent); levels = low, mid, high; grid = the "
        "fragility fitting grid",
        "calibration": {
            "seeds": [CALIBRATION_SEED0, CALIBRATION_SEED0 + seeds - 1],
            "distance_km": km,
            "wall_s": wall_s,
        },
        "families": fams,
        "excluded": excluded,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "benchmark")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--distance-km", type=float, default=5.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--families", nargs="*", default=list(GRIDS))
    ap.add_argument(
        "--suite-file", type=Path, default=ROOT / "agents" / "evaluation" / "benchmark_suite.json"
    )
    ap.add_argument(
        "--rewrite-suite",
        type=Path,
        default=None,
        metavar="CALIBRATION_JSON",
        help="no runs: rewrite the suite file from a calibration.json",
    )
    args = ap.parse_args(argv)
    if args.rewrite_suite is not None:
        cal = json.loads(args.rewrite_suite.read_text())
        suite = suite_from_calibration(cal, args.seeds, args.distance_km, None)
        args.suite_file.write_text(json.dumps(suite, indent=1) + "\n")
        print(f"wrote {args.suite_file}")
        return 0
    t0 = time.perf_counter()
    args.out.mkdir(parents=True, exist_ok=True)
    cal = {}
    for fam in args.families:
        t = time.perf_counter()
        cal[fam] = calibrate_family(
            fam, GRIDS[fam], args.seeds, args.distance_km, args.workers, args.out
        )
        print(f"{fam}: levels {cal[fam]['levels']} ({time.perf_counter() - t:.0f} s)", flush=True)
    prev = args.out / "calibration.json"  # families calibrated by an earlier invocation
    if prev.exists():
        cal = {**{k: v for k, v in json.loads(prev.read_text()).items() if k not in cal}, **cal}
        cal = {f: cal[f] for f in GRIDS if f in cal}
    suite = suite_from_calibration(cal, args.seeds, args.distance_km, time.perf_counter() - t0)
    old = {}
    if args.suite_file.exists():
        old = json.loads(args.suite_file.read_text()).get("families", {})
    suite["families"] = {
        **{k: v for k, v in old.items() if k not in suite["excluded"]},
        **suite["families"],
    }
    args.suite_file.write_text(json.dumps(suite, indent=1) + "\n")
    md = [
        "# Benchmark suite calibration",
        "",
        f"Command: `python scripts/calibrate_benchmark.py --seeds {args.seeds} "
        f"--distance-km {args.distance_km}` ({time.perf_counter() - t0:.0f} s)",
        "",
        "| family | baselines | fixed | passive θ (geo. mean) | PID θ (geo. mean) | suite levels |",
        "|---|---|---|---:|---:|---|",
    ]
    for f, c in cal.items():
        g = c["geometric_capacity"]
        md.append(
            f"| {f} | {', '.join(c['controllers'])} | {c['fixed'] or ''} "
            f"| {g.get('passive', float('nan')):.3g} | {g['pid']:.3g} "
            f"| {', '.join(f'{v:g}' for v in c['levels'])} |"
        )
    md += [
        "",
        "Contact probability per 10 km (from the calibration runs) at the grid levels; "
        "✓ = in the measurable band (0.05–0.95 per 10 km, or P(unsteady) 1e-4–0.5):",
        "",
    ]
    for f, c in cal.items():
        md += [
            f"## {f}",
            "",
            "| controller | condition | level | P(contact) per run "
            "| per 10 km | P(unsteady) | band |",
            "|---|---|---:|---:|---:|---:|---|",
        ]
        for b in c["band"]:
            pu = "n/a" if b["p_unsteady"] is None else f"{b['p_unsteady']:.2g}"
            md.append(
                f"| {b['controller']} | {b['condition']} | {b['level']:g} "
                f"| {b['p_contact_run']:.2f} | {b['p_contact_10km']:.2f} | {pu} "
                f"| {'✓' if b['in_band'] else ''} |"
            )
        md.append("")
    (args.out / "calibration.md").write_text("\n".join(md) + "\n")
    (args.out / "calibration.json").write_text(json.dumps(cal, indent=1, default=str) + "\n")
    print(f"wrote {args.suite_file} and {args.out / 'calibration.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
