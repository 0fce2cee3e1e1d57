"""Evaluate controllers over scenarios: STS tables (paper Tables 2–3), RMS excursion,
contacts, ride comfort (ISO 2631-1) and current effort; Markdown + JSON + CSV + PNG.

    python -m agents.evaluate --controllers passive pid lqr --scenarios paper \\
        --distance-km 10 --seeds 5 --out reports/ [--magnet repelling|attracting] [--settle-s 1.0]

``--scenarios paper`` expands to the four paper scenarios; individual names
(``paper-1000-straight`` …, ``random``) are accepted too. Each (controller, scenario, seed)
is one episode of ``HyperloopSuspension-v0`` over ``--distance-km`` (it ends early on
contact; such an episode is reported — time and place of the contact, P(unsteady) = 1 —
never dropped). Seeds are 0 … n−1.

Files written into ``--out``: ``report.md``, ``results.json``, ``summary.csv`` (one row per
controller × scenario), ``sts_units.csv`` (one row per unit), ``figures/hist_*.png``
(excursion histograms with the fitted density and ±Ω, as the paper's Fig. 5) and
``figures/timeseries_*.png`` (excursions over the run, as Figs. 8–11).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import shlex
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents.registry import available_controllers, make_controller
from agents.rollout import Episode, expected_steps, run_episode
from hyperloop_env.comfort import comfort_label, ride_comfort
from hyperloop_env.scenarios import SCENARIOS, build_config
from hyperloop_env.sts import (
    UNIT_NAMES,
    STSReport,
    analyse_episodes,
    format_probability,
    paper_table_markdown,
)

PAPER_SCENARIOS: tuple[str, ...] = (
    "paper-1000-straight",
    "paper-1000-curved",
    "paper-2000-straight",
    "paper-2000-curved",
)
MAGNETS = ("repelling", "attracting")


def expand_scenarios(names: Sequence[str]) -> list[str]:
    """``paper`` → the four paper scenarios; other names must be known scenarios."""
    out: list[str] = []
    for n in names:
        items = PAPER_SCENARIOS if n == "paper" else (n,)
        for it in items:
            if it not in SCENARIOS:
                raise ValueError(
                    f"unknown scenario {it!r}; valid: 'paper', {', '.join(sorted(SCENARIOS))}"
                )
            if it not in out:
                out.append(it)
    return out


def _seed_list(seeds: int | Sequence[int]) -> list[int]:
    if isinstance(seeds, int | np.integer) and not isinstance(seeds, bool):
        if seeds < 1:
            raise ValueError(f"seeds must be >= 1, got {seeds!r}")
        return list(range(int(seeds)))
    lst = [int(s) for s in seeds]
    if not lst:
        raise ValueError("seeds must not be empty")
    return lst


def _finite(x: Any) -> Any:
    if isinstance(x, float | np.floating):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_finite(v) for v in x]
    if isinstance(x, np.ndarray):
        return _finite(x.tolist())
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def summarise(
    episodes: list[Episode], settle_s: float, n_boot: int = 200
) -> tuple[STSReport, dict[str, Any]]:
    """STS report and scalar metrics of the episodes of one controller × scenario."""
    ep0 = episodes[0]
    dt = ep0.dt_s
    n0 = int(math.ceil(settle_s / dt - 1e-9)) if settle_s > 0 else 0
    report = analyse_episodes(
        [(e.gap_m[1:], bool(e.terminated)) for e in episodes],  # row 0 is the reset state
        dt,
        settle_s=settle_s,
        n_boot=n_boot,
        clearance_m=_clearance(ep0),
    )
    post = [e.gap_m[1 + n0 :] for e in episodes]
    post = [g for g in post if len(g)]
    allg = np.concatenate(post) if post else np.empty((0, 4))
    rms_units = np.sqrt(np.mean(allg**2, axis=0)) if len(allg) else np.full(4, np.nan)
    lat = np.concatenate([e.lateral_m[1 + n0 :] for e in episodes])
    cur = np.concatenate([e.current_A[1 + n0 :] - e.nominal_current_A for e in episodes])
    comfort = [
        ride_comfort(e.acc_m_s2[1:, 0], e.acc_m_s2[1:, 1], dt, settle_s)
        for e in episodes
        if len(e.acc_m_s2) - 1 > n0 + 10
    ]
    contacts = [e for e in episodes if e.terminated]
    first = min(contacts, key=lambda e: e.contact_time_s) if contacts else None

    def _mean(vals: list[float]) -> float:
        v = [x for x in vals if math.isfinite(x)]
        return float(np.mean(v)) if v else math.nan

    a_wz = _mean([c.a_wz_m_s2 for c in comfort])
    a_wy = _mean([c.a_wy_m_s2 for c in comfort])
    a_v = _mean([c.a_v_m_s2 for c in comfort])
    metrics = {
        "controller": ep0.controller,
        "scenario": ep0.scenario,
        "magnet": ep0.magnet,
        "speed_kmh": ep0.speed_kmh,
        "curve_radius_m": ep0.curve_radius_m,
        "n_episodes": len(episodes),
        "seeds": [e.seed for e in episodes],
        "distance_km_mean": float(np.mean([e.distance_m for e in episodes])) / 1e3,
        "steps_total": int(sum(e.n_steps for e in episodes)),
        "wall_s": float(sum(e.wall_s for e in episodes)),
        "rms_gap_mm": float(np.sqrt(np.mean(allg**2))) * 1e3 if len(allg) else math.nan,
        "rms_gap_units_mm": (rms_units * 1e3).tolist(),
        "max_abs_gap_mm": float(np.max(np.abs(allg))) * 1e3 if len(allg) else math.nan,
        "mean_lateral_mm": float(np.mean(lat)) * 1e3 if len(lat) else math.nan,
        "max_abs_lateral_mm": float(np.max(np.abs(lat))) * 1e3 if len(lat) else math.nan,
        "rms_current_dev_A": float(np.sqrt(np.mean(cur**2))) if len(cur) else math.nan,
        "n_contact_episodes": len(contacts),
        "time_to_first_contact_s": first.contact_time_s if first else None,
        "position_of_first_contact_m": first.contact_position_m if first else None,
        "contact_kind": first.contact_kind if first else None,
        "contact_times_s": [e.contact_time_s for e in contacts],
        "a_wz_m_s2": a_wz,
        "a_wy_m_s2": a_wy,
        "a_v_m_s2": a_v,
        "comfort": comfort_label(a_v),
        "worst_p_unsteady": report.worst_p_unsteady,
        "worst_unit": report.worst_unit,
        "p_unsteady_units": [u.p_unsteady for u in report.units],
        "n_samples_after_settle": int(len(allg)),
    }
    return report, metrics


def _clearance(ep: Episode) -> float:
    return float(ep.extra.get("clearance_m", 0.008))


# ------------------------------------------------------------------------------------------
# figures
# ------------------------------------------------------------------------------------------


def _plot_hist(report: STSReport, episodes: list[Episode], settle_s: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from scipy import stats

    om = report.clearance_m * 1e3
    dt = episodes[0].dt_s
    n0 = int(math.ceil(settle_s / dt - 1e-9)) if settle_s > 0 else 0
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for a, (ax, u) in enumerate(zip(axes.flat, report.units, strict=True)):
        x = np.concatenate([e.gap_m[1 + n0 :, a] for e in episodes]) * 1e3
        lim = max(om * 1.3, float(np.max(np.abs(x))) * 1.05 if len(x) else 0.0)
        if len(x):
            ax.hist(x, bins=80, range=(-lim, lim), density=True, alpha=0.6, label="simulated")
        if u.distribution not in ("none", "degenerate") and len(u.distribution_params):
            law = getattr(stats, u.distribution)
            *shape, loc, scale = u.distribution_params
            xs = np.linspace(-lim, lim, 400)
            pdf = law.pdf(xs * 1e-3, *shape, loc=loc, scale=scale) * 1e-3
            ax.plot(xs, pdf, "k-", lw=1.5, label=f"fitted {u.distribution}")
        for s in (-om, om):
            ax.axvline(s, color="r", ls="--", lw=1.2)
        ax.set_title(f"{u.name}: P(unsteady) = {format_probability(u.p_unsteady)}")
        ax.set_xlabel("gap excursion s [mm]  (±Ω dashed)")
        ax.set_ylabel("density [1/mm]")
        if len(x):
            ax.legend(fontsize=7)
        else:
            ax.text(0.5, 0.5, "no samples after settling\n(contact)", ha="center",
                    transform=ax.transAxes)  # fmt: skip
    e0 = episodes[0]
    fig.suptitle(f"{e0.controller} — {e0.scenario} ({e0.magnet})")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _plot_timeseries(ep: Episode, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    om = _clearance(ep) * 1e3
    fig, axes = plt.subplots(4, 1, figsize=(11, 8), sharex=True)
    t = ep.time_s
    step = max(1, len(t) // 20000)
    for a, ax in enumerate(axes):
        ax.plot(t[::step], ep.gap_m[::step, a] * 1e3, lw=0.6, label="gap excursion")
        ax.plot(t[::step], ep.lateral_m[::step, a] * 1e3, lw=0.6, alpha=0.7, label="lateral offset")
        for s in (-om, om):
            ax.axhline(s, color="r", ls="--", lw=0.8)
        ax.set_ylabel(f"{UNIT_NAMES[a]} [mm]")
    axes[0].legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("time [s]")
    title = f"{ep.controller} — {ep.scenario} ({ep.magnet}), seed {ep.seed}"
    if ep.terminated:
        title += f": {ep.contact_kind} contact at t = {ep.contact_time_s:.3f} s"
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


# ------------------------------------------------------------------------------------------
# report
# ------------------------------------------------------------------------------------------


def _fmt(x: Any, nd: int = 3) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a"
    if isinstance(x, float):
        return f"{x:.{nd}f}"
    return str(x)


def summary_table(results: list[dict[str, Any]]) -> str:
    """Markdown table: one row per controller × scenario."""
    lines = [
        "| controller | scenario | worst P(unsteady) | RMS gap [mm] | max abs gap [mm] "
        "| contact episodes | first contact [s] (kind) | mean lateral [mm] "
        "| a_wz W_k [m/s²] | a_wy W_d [m/s²] | comfort (ISO 2631-1) | RMS ΔI [A] |",
        "|---|---|---:|---:|---:|---:|---|---:|---:|---:|---|---:|",
    ]
    for r in results:
        m = r["metrics"]
        tc = m["time_to_first_contact_s"]
        tcs = "none" if tc is None else f"{tc:.3f} ({m['contact_kind']})"
        lines.append(
            f"| {m['controller']} | {m['scenario']} | {format_probability(m['worst_p_unsteady'])} "
            f"| {_fmt(m['rms_gap_mm'])} | {_fmt(m['max_abs_gap_mm'])} "
            f"| {m['n_contact_episodes']}/{m['n_episodes']} | {tcs} "
            f"| {_fmt(m['mean_lateral_mm'])} | {_fmt(m['a_wz_m_s2'])} | {_fmt(m['a_wy_m_s2'])} "
            f"| {m['comfort']} | {_fmt(m['rms_current_dev_A'], 2)} |"
        )
    return "\n".join(lines) + "\n"


def write_outputs(
    results: list[dict[str, Any]], out: Path, settings: dict[str, Any], title: str
) -> dict[str, Path]:
    """report.md, results.json, summary.csv, sts_units.csv into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    md = [f"# {title}", ""]
    md += [f"Command: `{settings.get('command', '')}`", ""]
    md += [
        f"Magnet: **{settings['magnet']}**; distance {settings['distance_km']} km per episode; "
        f"seeds {settings['seeds']}; settling {settings['settle_s']} s discarded before the "
        f"fits; clearance Ω = 8 mm; control interval {settings.get('dt_s', 1e-3)} s; "
        f"wall time {settings.get('wall_s', float('nan')):.1f} s.",
        "",
        "RMS gap = RMS of the gap excursion over all units and post-settling samples; "
        "comfort = ISO 2631-1 frequency-weighted RMS capsule acceleration (W_k vertical, W_d "
        "lateral; a_v = sqrt((1.4 a_wy)² + a_wz²) labels the comfort reaction); RMS ΔI = RMS "
        "coil-current deviation from I0. An episode that ends in contact is kept: its "
        "P(unsteady) is 1 (contact is absorbing) and its time of contact is listed.",
        "",
        "## Summary",
        "",
        summary_table(results),
    ]
    failed = [r for r in results if r["metrics"]["n_contact_episodes"]]
    if failed:
        md += ["### Contacts", ""]
        for r in failed:
            m = r["metrics"]
            times = ", ".join(f"{t:.3f} s" for t in m["contact_times_s"])
            md.append(
                f"- **{m['controller']} / {m['scenario']}** ({m['magnet']}): "
                f"{m['n_contact_episodes']} of {m['n_episodes']} episode(s) ended in "
                f"{m['contact_kind']} contact (at {times}; first at x = "
                f"{_fmt(m['position_of_first_contact_m'], 1)} m) — P(unsteady) = 1."
            )
        md.append("")
    scen = list(dict.fromkeys(r["metrics"]["scenario"] for r in results))
    md += ["## STS tables (form of the paper's Tables 2–3)", ""]
    for sc in scen:
        md += [f"### {sc}", ""]
        for r in results:
            if r["metrics"]["scenario"] != sc:
                continue
            m = r["metrics"]
            md.append(r["table_md"].replace("**", f"**{m['controller']}: ", 1)
                      if r["table_md"].startswith("**") else r["table_md"])  # fmt: skip
            md.append(
                "RMS gap per unit [mm]: "
                + ", ".join(f"{n} {_fmt(v)}" for n, v in zip(UNIT_NAMES, m["rms_gap_units_mm"],
                                                              strict=True))
                + "."
            )  # fmt: skip
            for f in r.get("figures", []):
                md.append(f"![{Path(f).name}]({Path(f).relative_to(out).as_posix()})")
            md.append("")
    paths = {"md": out / "report.md", "json": out / "results.json"}
    paths["md"].write_text("\n".join(md) + "\n")
    payload = {
        "settings": settings,
        "results": [
            {
                "metrics": r["metrics"],
                "sts": r["report"].to_dict(),
                "figures": [Path(f).relative_to(out).as_posix() for f in r.get("figures", [])],
            }
            for r in results
        ],
    }
    paths["json"].write_text(json.dumps(_finite(payload), indent=1) + "\n")
    paths["csv"] = out / "summary.csv"
    keys = [
        "controller", "scenario", "magnet", "speed_kmh", "curve_radius_m", "n_episodes",
        "worst_p_unsteady", "worst_unit", "rms_gap_mm", "max_abs_gap_mm",
        "n_contact_episodes", "time_to_first_contact_s", "position_of_first_contact_m",
        "contact_kind", "mean_lateral_mm", "max_abs_lateral_mm", "a_wz_m_s2", "a_wy_m_s2",
        "a_v_m_s2", "comfort", "rms_current_dev_A", "steps_total", "wall_s",
    ]  # fmt: skip
    with paths["csv"].open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        for r in results:
            w.writerow({k: _finite(r["metrics"][k]) for k in keys})
    paths["units_csv"] = out / "sts_units.csv"
    with paths["units_csv"].open("w", newline="") as fh:
        rows = []
        for r in results:
            for row in r["report"].to_rows():
                rows.append({"controller": r["metrics"]["controller"],
                             "scenario": r["metrics"]["scenario"],
                             "magnet": r["metrics"]["magnet"], **row})  # fmt: skip
        if rows:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    return paths


# ------------------------------------------------------------------------------------------
# evaluation
# ------------------------------------------------------------------------------------------


def run_cases(
    controllers: Sequence[str],
    scenarios: Sequence[str],
    distance_km: float,
    seeds: Sequence[int],
    magnet: str,
    progress: bool,
    env_kwargs: dict[str, Any] | None = None,
    controller_kwargs: dict[str, dict[str, Any]] | None = None,
    desc: str = "evaluate",
) -> dict[tuple[str, str], list[Episode]]:
    """Run every (controller, scenario, seed) episode; a progress bar counts control steps."""
    env_kwargs = dict(env_kwargs or {})
    ck = controller_kwargs or {}
    total = 0
    for sc in scenarios:
        cfg = build_config(sc, magnet=magnet, track_length_m=distance_km * 1000.0)
        dt = env_kwargs.get("control_dt_s") or cfg.base.simulation.control_dt_s
        speed = env_kwargs.get("speed_kmh") or cfg.base.condition.speed_kmh
        total += expected_steps(speed, distance_km, dt) * len(seeds) * len(controllers)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=total, desc=desc, unit="step", unit_scale=True, file=sys.stderr)
    out: dict[tuple[str, str], list[Episode]] = {}
    try:
        for name in controllers:
            for sc in scenarios:
                eps = []
                for seed in seeds:
                    if bar is not None:
                        bar.set_postfix_str(f"{name} {sc} seed {seed}")
                    ep = run_episode(
                        lambda env, n=name: make_controller(n, env, **ck.get(n, {})),
                        sc,
                        seed,
                        distance_km,
                        magnet,
                        env_kwargs,
                        step_callback=bar.update if bar is not None else None,
                    )
                    ep.controller = name
                    ep.extra["clearance_m"] = env_kwargs.get("clearance_m") or 0.008
                    if bar is not None and ep.terminated:  # count the steps never run
                        cfg = build_config(sc, magnet=magnet)
                        n_exp = expected_steps(
                            env_kwargs.get("speed_kmh") or cfg.base.condition.speed_kmh,
                            distance_km,
                            ep.dt_s,
                        )
                        bar.update(max(0, n_exp - ep.n_steps))
                    eps.append(ep)
                out[(name, sc)] = eps
    finally:
        if bar is not None:
            bar.close()
    return out


def evaluate(
    controllers: Sequence[str],
    scenarios: Sequence[str] = ("paper",),
    distance_km: float = 10.0,
    seeds: int | Sequence[int] = 1,
    magnet: str = "repelling",
    out_dir: str | Path | None = "reports",
    settle_s: float = 1.0,
    progress: bool = True,
    *,
    env_kwargs: dict[str, Any] | None = None,
    controller_kwargs: dict[str, dict[str, Any]] | None = None,
    figures: bool = True,
    n_boot: int = 200,
    command: str | None = None,
) -> dict[str, Any]:
    """Evaluate ``controllers`` (registered names) on ``scenarios`` (names or "paper").

    Returns ``{"settings": …, "results": [{"metrics", "report" (STSReport), "table_md",
    "figures"}, …], "paths": {…}}``; files are written into ``out_dir`` unless it is None.
    Invalid arguments raise ``ValueError`` with a message naming them."""
    controllers = list(controllers)
    if not controllers:
        raise ValueError("controllers must not be empty")
    for c in controllers:
        if c not in available_controllers():
            raise ValueError(f"unknown controller {c!r}; available: {available_controllers()}")
    scen = expand_scenarios(scenarios)
    if not scen:
        raise ValueError("scenarios must not be empty")
    if not (
        isinstance(distance_km, int | float) and math.isfinite(distance_km) and distance_km > 0
    ):
        raise ValueError(f"distance_km must be a finite number > 0, got {distance_km!r}")
    seed_list = _seed_list(seeds)
    if magnet not in MAGNETS:
        raise ValueError(f"magnet must be one of {MAGNETS}, got {magnet!r}")
    if not (math.isfinite(settle_s) and settle_s >= 0):
        raise ValueError(f"settle_s must be a finite number >= 0, got {settle_s!r}")
    t0 = time.perf_counter()
    episodes = run_cases(
        controllers, scen, float(distance_km), seed_list, magnet, progress, env_kwargs,
        controller_kwargs,
    )  # fmt: skip
    out = Path(out_dir) if out_dir is not None else None
    fig_dir = out / "figures" if out is not None else None
    if fig_dir is not None and figures:
        fig_dir.mkdir(parents=True, exist_ok=True)
    results = []
    for (name, sc), eps in episodes.items():
        report, metrics = summarise(eps, settle_s, n_boot)
        table = paper_table_markdown(report, f"{name} — {sc} ({magnet})")
        figs: list[str] = []
        if fig_dir is not None and figures:
            stem = f"{name}_{sc}_{magnet}"
            h = fig_dir / f"hist_{stem}.png"
            ts = fig_dir / f"timeseries_{stem}.png"
            _plot_hist(report, eps, settle_s, h)
            _plot_timeseries(eps[0], ts)
            figs = [str(h), str(ts)]
        results.append({"metrics": metrics, "report": report, "table_md": table, "figures": figs})
    settings = {
        "controllers": controllers,
        "scenarios": scen,
        "distance_km": float(distance_km),
        "seeds": seed_list,
        "magnet": magnet,
        "settle_s": float(settle_s),
        "env_kwargs": env_kwargs or {},
        "n_boot": n_boot,
        "wall_s": time.perf_counter() - t0,
        "command": command or "agents.evaluate.evaluate(...)",
    }
    paths: dict[str, Path] = {}
    if out is not None:
        paths = write_outputs(results, out, settings, "Controller evaluation")
    return {
        "settings": settings,
        "results": results,
        "paths": {k: str(v) for k, v in paths.items()},
    }


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m agents.evaluate",
        description="Evaluate controllers on hyperloop scenarios (STS, RMS, contacts, comfort).",
    )
    p.add_argument("--controllers", nargs="+", default=["passive", "pid", "lqr"],
                   help=f"controller names ({', '.join(available_controllers())})")  # fmt: skip
    p.add_argument("--scenarios", nargs="+", default=["paper"],
                   help="'paper' (the four paper scenarios) and/or scenario names: "
                   + ", ".join(sorted(SCENARIOS)))  # fmt: skip
    p.add_argument("--distance-km", type=float, default=10.0, help="distance per episode [km]")
    p.add_argument("--seeds", type=int, default=1, help="number of seeds (0 … n-1)")
    p.add_argument("--magnet", default="repelling", help="repelling | attracting")
    p.add_argument("--settle-s", type=float, default=1.0, help="settling time discarded [s]")
    p.add_argument("--out", type=Path, default=Path("reports"), help="output directory")
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.add_argument("--n-boot", type=int, default=200, help="bootstrap replicates of the CI")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p


def validate_args(parser: argparse.ArgumentParser, args: argparse.Namespace) -> list[str]:
    """parser.error (exit 2 with a message) on invalid arguments; returns the scenarios."""
    unknown = [c for c in args.controllers if c not in available_controllers()]
    if unknown:
        parser.error(f"unknown controller(s) {unknown}; available: {available_controllers()}")
    try:
        scen = expand_scenarios(args.scenarios)
    except ValueError as exc:
        parser.error(str(exc))
    if not (math.isfinite(args.distance_km) and args.distance_km > 0):
        parser.error(f"--distance-km must be > 0, got {args.distance_km}")
    if args.seeds < 1:
        parser.error(f"--seeds must be >= 1, got {args.seeds}")
    if args.magnet not in MAGNETS:
        parser.error(f"--magnet must be one of {list(MAGNETS)}, got {args.magnet!r}")
    if not (math.isfinite(args.settle_s) and args.settle_s >= 0):
        parser.error(f"--settle-s must be >= 0, got {args.settle_s}")
    if args.n_boot < 0:
        parser.error(f"--n-boot must be >= 0, got {args.n_boot}")
    return scen


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    scen = validate_args(parser, args)
    cmd = "python -m agents.evaluate " + " ".join(
        shlex.quote(a) for a in (argv if argv is not None else sys.argv[1:])
    )
    res = evaluate(
        args.controllers, scen, args.distance_km, args.seeds, args.magnet, args.out,
        args.settle_s, progress=not args.no_progress, figures=not args.no_figures,
        n_boot=args.n_boot, command=cmd,
    )  # fmt: skip
    print(summary_table(res["results"]))
    for k, v in res["paths"].items():
        print(f"{k}: {v}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
