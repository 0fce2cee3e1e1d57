"""Reproduce the paper's study with this model: passive STS tables, radius sweep, critical
radius.

    python -m agents.reproduce_paper [--out reports/paper] [--distance-km 10] [--seeds 1]
        [--sweep-km 2] [--magnet repelling] [--overwrite]

``--out`` is checked before anything runs: it must be new or empty unless ``--overwrite``,
which first removes what a previous reproduction wrote there (:data:`OUTPUT_FILES`); a
run that fails or is interrupted before writing leaves no empty folder behind.

1. The passive system over the paper's four conditions (1000/2000 km/h, straight and
   R = 200 km) in the form of the paper's Tables 2–3 (via :func:`agents.evaluate.evaluate`).
2. A radius sweep at 1000 and 2000 km/h (passive): P(unsteady), mean lateral offset,
   contact yes/no per radius (``--sweep-km`` per run: the 500 m transition and ≥ 1.4 km of
   full curve).
3. The critical radius (smallest radius without contact over ``--sweep-km``) by bisection
   on log-radius, for passive and PID, next to the quasi-static estimate v²/a_cap with
   a_cap = g·δ0/b2 (the lateral guidance ceiling of the magnets, MODEL.md).

The paper's published numbers (Tables 2–3) are typed in below, labelled as the paper's;
every number of ours is computed. No model parameter is tuned to the paper.
"""

from __future__ import annotations

import argparse
import json
import math
import shlex
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from agents.controllers import make_controller
from agents.evaluation.evaluate import check_settling, episode_configs, evaluate
from agents.evaluation.metrics import summarise
from agents.evaluation.outputs import (
    OutputDirError,
    atomic_write_text,
    discard_if_empty,
    prepare_output_dir,
)
from agents.evaluation.report import _finite, _fmt
from agents.evaluation.rollout import run_episode
from hyperloop_env.config import MAGNETS, build_config
from hyperloop_env.physics.params import OperatingCondition
from hyperloop_env.scenarios import PAPER_SCENARIOS
from hyperloop_env.sts import format_probability, normal_p_unsteady

# The paper's Tables 2–3 (published values, typed in; mean and std in metres, then its
# "P(steady)/P(unsteady)" pair). Not computed here and not used by any computation.
PAPER_TABLES: dict[str, dict[str, tuple[float, float, float, float]]] = {
    "paper-1000-straight": {
        "FL": (0.000643564, 0.001500849, 0.9999, 0.00356),
        "FR": (0.00064351028, 0.001500660, 0.9999, 0.00426),
        "RL": (0.0005307696, 0.00125932818, 0.9999, 0.00356),
        "RR": (0.000530715685, 0.0012591756, 0.9999, 0.00357),
    },
    "paper-1000-curved": {
        "FL": (0.00135772256, 0.0041107885, 0.99024, 0.01077),
        "FR": (0.00135765939, 0.00411063733, 0.99024, 0.01077),
        "RL": (0.00124279509, 0.003959562, 0.98862, 0.01125),
        "RR": (0.0012427319, 0.0039426835, 0.99024, 0.01077),
    },
    "paper-2000-straight": {
        "FL": (0.0053174648, 0.01086606, 0.88982, 0.03149),
        "FR": (0.0053159854, 0.01086289500, 0.9039, 0.03148),
        "RL": (0.00469238594, 0.0097347381, 0.9385, 0.02814),
        "RR": (0.00469120652, 0.00973194839, 0.9039, 0.02813),
    },
    "paper-2000-curved": {
        "FL": (0.006915739420, 0.016245364, 0.81912, 0.04595),
        "FR": (0.00681447120, 0.0162416190, 0.81915, 0.04594),
        "RL": (0.00618407671, 0.01514287177, 0.82554, 0.04266),
        "RR": (0.00618280847, 0.01513931248, 0.82557, 0.04265),
    },
}

DEFAULT_RADII_M = (50e3, 80e3, 120e3, 200e3, 300e3, 500e3, 1000e3)

OUTPUT_FILES: tuple[str, ...] = ("report.md", "results.json", "passive")
"""What a reproduction writes into ``--out`` (``passive/`` is the evaluation of the four
paper conditions); removed first by ``--overwrite``."""


def lateral_capacity_m_s2(magnet: str = "repelling") -> float:
    """Quasi-static lateral acceleration the four magnets can hold: a_cap = 4·F0·δ0/b2 /
    (m_v + m_m) = g·δ0/b2 (MODEL.md; F_z ceiling ≈ F_y·δ0/b2 per unit, no cant)."""
    p = build_config("paper-1000-straight", magnet=magnet).base
    return p.simulation.gravity_m_s2 * p.magnet.nominal_gap_m / p.magnet.pole_width_m


def usable_lateral_capacity_m_s2(magnet: str = "repelling") -> float:
    """a_cap reduced to what the magnets give before the lateral clearance is reached:
    F_z(z) = F_z,max·(2/π)·arctan(z/δ0) at z = lateral clearance (force law of
    :mod:`hyperloop_env.physics.magnets`)."""
    p = build_config("paper-1000-straight", magnet=magnet).base
    frac = 2 / math.pi * math.atan(p.magnet.lateral_clearance_m / p.magnet.nominal_gap_m)
    return lateral_capacity_m_s2(magnet) * frac


def _a_lat(speed_kmh: float, radius_m: float) -> float:
    """Quasi-static lateral demand v²/R [m/s²] (no cant)."""
    return OperatingCondition(speed_kmh=speed_kmh).speed_m_s ** 2 / radius_m


def _run_curve(
    controller: str, speed_kmh: float, radius_m: float, seed: int, km: float, magnet: str
) -> Any:
    sc = "paper-1000-curved" if speed_kmh == 1000 else "paper-2000-curved"
    return run_episode(
        lambda env: make_controller(controller, env),
        sc,
        seed,
        km,
        magnet,
        env_kwargs={"curve_radius_m": float(radius_m), "speed_kmh": float(speed_kmh)},
    )


def radius_sweep(
    radii: tuple[float, ...], speeds: tuple[float, ...], km: float, seed: int, magnet: str,
    settle_s: float,
) -> list[dict[str, Any]]:  # fmt: skip
    """Passive runs over a set of radii: P(unsteady), mean lateral offset, contact."""
    rows = []
    for v in speeds:
        for r in radii:
            ep = _run_curve("passive", v, r, seed, km, magnet)
            rep, m = summarise([ep], settle_s, n_boot=0)
            lat = ep.lateral_m[1:]
            rows.append({
                "speed_kmh": v,
                "radius_m": r,
                "a_lat_m_s2": _a_lat(v, r),
                "contact": bool(ep.terminated),
                "contact_kind": ep.contact_kind,
                "time_to_contact_s": ep.contact_time_s,
                "position_of_contact_m": ep.contact_position_m,
                "worst_p_unsteady": rep.worst_p_unsteady,
                "mean_lateral_mm": float(np.nanmean(lat)) * 1e3 if len(lat) else math.nan,
                "max_abs_lateral_mm": float(np.nanmax(np.abs(lat))) * 1e3 if len(lat) else math.nan,
                "rms_gap_mm": m["rms_gap_mm"],
            })  # fmt: skip
    return rows


def critical_radius(
    controller: str, speed_kmh: float, km: float, seed: int, magnet: str,
    lo_m: float = 10e3, hi_m: float = 3000e3, iters: int = 8,
) -> dict[str, Any]:  # fmt: skip
    """Smallest radius without contact over ``km`` (bisection on log-radius between a
    radius with contact and one without). Returns the bracket and the evaluations."""
    evals: list[tuple[float, bool]] = []

    def contact(r: float) -> bool:
        ep = _run_curve(controller, speed_kmh, r, seed, km, magnet)
        evals.append((r, bool(ep.terminated)))
        return bool(ep.terminated)

    if not contact(lo_m) or contact(hi_m):
        c_lo = evals[0][1]
        return {
            "controller": controller, "speed_kmh": speed_kmh, "critical_radius_m": None,
            "bracket_m": None, "evaluations": evals,
            "note": ("no contact even at the smallest radius" if not c_lo
                     else "contact even at the largest radius"),
        }  # fmt: skip
    a, b = math.log(lo_m), math.log(hi_m)  # contact at a, none at b
    for _ in range(iters):
        mid = 0.5 * (a + b)
        if contact(math.exp(mid)):
            a = mid
        else:
            b = mid
    return {
        "controller": controller,
        "speed_kmh": speed_kmh,
        "critical_radius_m": math.exp(b),
        "bracket_m": [math.exp(a), math.exp(b)],
        "evaluations": evals,
        "note": "",
    }


def _paper_comparison(res: dict[str, Any]) -> list[str]:
    lines = [
        "## Comparison with the paper's Tables 2–3",
        "",
        "Paper values are the **published numbers of the paper** (typed in, not computed); "
        "ours are computed by this run (passive, normal fit as in the paper). Means and "
        "standard deviations in mm.",
        "",
        "| condition | unit | paper mean | paper std | paper P(unsteady) | normal law from the "
        "paper's own mean/std | our mean | our std | our P(unsteady) | our contacts |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    by_sc = {r["metrics"]["scenario"]: r for r in res["results"]}
    for sc in PAPER_SCENARIOS:
        r = by_sc.get(sc)
        for unit, (pm, ps, _pst, pun) in PAPER_TABLES[sc].items():
            recomputed = normal_p_unsteady(pm, ps)
            if r is not None:
                u = r["report"].unit(unit)
                ours = (f"{_fmt(u.mean_m * 1e3, 4)} | {_fmt(u.std_m * 1e3, 4)} | "
                        f"{format_probability(u.p_unsteady)} | {u.n_contacts}")  # fmt: skip
            else:
                ours = "n/a | n/a | n/a | n/a"
            lines.append(
                f"| {sc} | {unit} | {pm * 1e3:.4f} | {ps * 1e3:.4f} | {pun:g} "
                f"| {format_probability(recomputed)} | {ours} |"
            )
    p_check = normal_p_unsteady(0.643564e-3, 1.500849e-3)
    lines += [
        "",
        "**The paper's own probabilities cannot be recomputed from its own normal "
        "parameters**: for 1000 km/h straight (FL) a normal law with mean 0.643564 mm and "
        f"std 1.500849 mm gives P(|s| ≥ 8 mm) = `sts.normal_p_unsteady(0.643564e-3, "
        f"1.500849e-3)` = {p_check:.2e}, not the published 0.00356 (column 'normal law from "
        "the paper's own mean/std' above does this for every row; at 2000 km/h the paper's "
        "std exceeds the clearance, so its published P(unsteady) of 0.03–0.05 is also far "
        "below what its own normal law implies). We therefore compare trends, not numbers.",
        "",
    ]
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m agents.reproduce_paper", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    ap.add_argument("--out", type=Path, default=Path("reports/paper"),
                    help="output directory (must be new or empty unless --overwrite)")  # fmt: skip
    ap.add_argument("--overwrite", action="store_true",
                    help="replace a previous reproduction in --out")  # fmt: skip
    ap.add_argument("--distance-km", type=float, default=10.0, help="per paper condition")
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--sweep-km", type=float, default=2.0, help="per sweep/bisection run")
    ap.add_argument("--settle-s", type=float, default=1.0)
    ap.add_argument("--magnet", default="repelling")
    ap.add_argument("--bisection-steps", type=int, default=7)
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(argv)
    if not (math.isfinite(args.distance_km) and args.distance_km > 0):
        ap.error(f"--distance-km must be > 0, got {args.distance_km}")
    if not (math.isfinite(args.sweep_km) and args.sweep_km > 0):
        ap.error(f"--sweep-km must be > 0, got {args.sweep_km}")
    if not (math.isfinite(args.settle_s) and args.settle_s >= 0):
        ap.error(f"--settle-s must be a finite number >= 0, got {args.settle_s}")
    if args.seeds < 1:
        ap.error(f"--seeds must be >= 1, got {args.seeds}")
    if args.magnet not in MAGNETS:
        ap.error(f"--magnet must be one of {list(MAGNETS)}, got {args.magnet!r}")
    if args.bisection_steps < 1:
        ap.error("--bisection-steps must be >= 1")
    try:
        paper = episode_configs(PAPER_SCENARIOS, args.distance_km, args.magnet, None,
                                "--distance-km")  # fmt: skip
        check_settling(paper, args.settle_s, args.distance_km, ("--distance-km", "--settle-s"))
        sweep_cfgs = {
            f"{sc} (sweep)": cfg
            for sc, cfg in episode_configs(
                ["paper-1000-curved", "paper-2000-curved"], args.sweep_km, args.magnet, None,
                "--sweep-km",
            ).items()
        }  # fmt: skip
        check_settling(sweep_cfgs, args.settle_s, args.sweep_km, ("--sweep-km", "--settle-s"))
    except ValueError as exc:
        ap.error(str(exc))
    cmd = "python -m agents.reproduce_paper " + " ".join(
        shlex.quote(a) for a in (argv if argv is not None else sys.argv[1:])
    )
    try:
        out = prepare_output_dir(args.out, overwrite=args.overwrite, owned=OUTPUT_FILES)
    except OutputDirError as exc:
        ap.error(str(exc))
    try:
        return _reproduce(args, out, cmd)
    except BaseException:
        discard_if_empty(out)  # a failure before the first file leaves no empty folder
        raise


def _reproduce(args: argparse.Namespace, out: Path, cmd: str) -> int:
    t0 = time.perf_counter()
    res = evaluate(
        ["passive"], ["paper"], args.distance_km, args.seeds, args.magnet, out / "passive",
        args.settle_s, progress=not args.no_progress, command=cmd,
    )  # fmt: skip
    print("passive paper conditions done", flush=True)
    sweep = radius_sweep(DEFAULT_RADII_M, (1000.0, 2000.0), args.sweep_km, 0, args.magnet,
                         args.settle_s)  # fmt: skip
    print("radius sweep done", flush=True)
    crit = [
        critical_radius(c, v, args.sweep_km, 0, args.magnet, iters=args.bisection_steps)
        for c in ("passive", "pid")
        for v in (1000.0, 2000.0)
    ]
    print("critical radius search done", flush=True)
    a_cap = lateral_capacity_m_s2(args.magnet)
    a_use = usable_lateral_capacity_m_s2(args.magnet)

    md = [
        "# Reproduction of the paper's study (stochastic technical stability)",
        "",
        f"Command: `{cmd}`  ",
        f"Magnet: {args.magnet}; paper conditions: {args.distance_km} km × {args.seeds} "
        f"seed(s), settling {args.settle_s} s; sweep and bisection runs: {args.sweep_km} km "
        f"(curve from x = 100 m, 500 m clothoid transition, no cant), seed 0. Wall time "
        f"{time.perf_counter() - t0:.0f} s.",
        "",
        "## 1. Passive system, the paper's four conditions",
        "",
        "Full tables (form of the paper's Tables 2–3), figures and CSV/JSON: "
        "[passive/report.md](passive/report.md).",
        "",
        (out / "passive" / "report.md")
        .read_text()
        .split("## Summary", 1)[1]
        .split("## STS tables", 1)[0]
        .strip(),
        "",
    ]
    for r in res["results"]:
        md.append(r["table_md"])
    md += _paper_comparison(res)
    md += [
        "## 2. Radius sweep (passive)",
        "",
        f"Quasi-static lateral guidance capacity of the magnets a_cap = g·δ0/b2 = "
        f"{a_cap:.3f} m/s² (no cant), so contact is expected where v²/R > a_cap.",
        "",
        "| speed [km/h] | R [km] | v²/R [m/s²] | contact | kind | time to contact [s] "
        "| worst P(unsteady) | mean lateral offset [mm] | max lateral [mm] | RMS gap [mm] |",
        "|---:|---:|---:|---|---|---:|---:|---:|---:|---:|",
    ]
    for s in sweep:
        md.append(
            f"| {s['speed_kmh']:.0f} | {s['radius_m'] / 1e3:.0f} | {s['a_lat_m_s2']:.3f} "
            f"| {'yes' if s['contact'] else 'no'} | {s['contact_kind'] or ''} "
            f"| {_fmt(s['time_to_contact_s'])} | {format_probability(s['worst_p_unsteady'])} "
            f"| {_fmt(s['mean_lateral_mm'], 2)} | {_fmt(s['max_abs_lateral_mm'], 2)} "
            f"| {_fmt(s['rms_gap_mm'])} |"
        )
    md += [
        "",
        "## 3. Critical radius (smallest radius without contact over the run)",
        "",
        "| controller | speed [km/h] | critical radius [km] | bracket [km] | estimate v²/a_cap "
        "[km] | estimate v²/a_usable [km] | runs |",
        "|---|---:|---:|---|---:|---:|---:|",
    ]
    for c in crit:
        est = _a_lat(c["speed_kmh"], 1.0) / a_cap / 1e3
        est_u = _a_lat(c["speed_kmh"], 1.0) / a_use / 1e3
        cr = c["critical_radius_m"]
        br = c["bracket_m"]
        md.append(
            f"| {c['controller']} | {c['speed_kmh']:.0f} | "
            f"{'n/a' if cr is None else f'{cr / 1e3:.0f}'} | "
            f"{c['note'] if br is None else f'[{br[0] / 1e3:.0f}, {br[1] / 1e3:.0f}]'} | "
            f"{est:.0f} | {est_u:.0f} | {len(c['evaluations'])} |"
        )
    by_sc = {r["metrics"]["scenario"]: r["metrics"] for r in res["results"]}
    c2000 = by_sc.get("paper-2000-curved", {})
    md += [
        "",
        f"a_usable = a_cap·(2/π)·arctan(z_clear/δ0) = {a_use:.3f} m/s² is the lateral force "
        "available before the unit reaches its lateral clearance (20 mm); the simulated "
        "critical radius lies above even that estimate because the lightly damped lateral "
        "response overshoots in the 500 m clothoid transition (dynamic, not quasi-static).",
        "",
        "## Findings",
        "",
        "- The 2000 km/h, R = 200 km condition needs v²/R = "
        f"{_a_lat(2000.0, 200e3):.2f} m/s² of lateral guidance, above the magnets' "
        f"capacity ≈ {a_cap:.2f} m/s² without cant: the passive vehicle "
        + (
            f"ends in {c2000.get('contact_kind')} contact at t = "
            f"{_fmt(c2000.get('time_to_first_contact_s'))} s (inside the transition curve), "
            if c2000.get("n_contact_episodes")
            else "does not touch in this run (unexpected), "
        )
        + "so this model cannot reproduce the paper's finite P(unsteady) for that condition; "
        "its critical radius at 2000 km/h is reported above. The paper's statement that radii "
        "below 200 km led to contact is consistent in kind (a critical radius exists and grows "
        "with v²), not in value: here it follows from the pole geometry (δ0/b2) and cant.",
        "- Current modulation cannot raise the lateral capacity at a held gap (F_z ∝ I²/δ with "
        "I² fixed by the weight), so the PID's critical radius is close to the passive one.",
        "- Trends vs the paper: compare the P(unsteady) and std of the straight and curved "
        "rows above; where ours differ from the paper's trends (e.g. a curve below the "
        "capacity barely changes the gap statistics here, because the lateral offset changes "
        "the overlap area only to second order), that is the model's result, not tuned.",
        "",
    ]
    atomic_write_text(out / "report.md", "\n".join(md) + "\n")
    payload = {
        "command": cmd,
        "passive": [r["metrics"] for r in res["results"]],
        "passive_sts": [r["report"].to_dict() for r in res["results"]],
        "paper_tables_published": PAPER_TABLES,
        "paper_fl_normal_recomputed": normal_p_unsteady(0.643564e-3, 1.500849e-3),
        "radius_sweep": sweep,
        "critical_radius": crit,
        "lateral_capacity_m_s2": a_cap,
        "usable_lateral_capacity_m_s2": a_use,
    }
    atomic_write_text(out / "results.json", json.dumps(_finite(payload), indent=1) + "\n")
    print(f"wrote {out / 'report.md'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
