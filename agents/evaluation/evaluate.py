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
``figures/timeseries_*.png`` (excursions over the run, as Figs. 8–11). The pieces:
:mod:`.rollout` (episodes), :mod:`.metrics` (numbers), :mod:`.figures`, :mod:`.report`.
"""

from __future__ import annotations

import argparse
import math
import shlex
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents.controllers import available_controllers, make_controller
from agents.evaluation.figures import plot_hist, plot_timeseries
from agents.evaluation.metrics import summarise
from agents.evaluation.report import summary_table, write_outputs
from agents.evaluation.rollout import Episode, episode_config, run_episode
from hyperloop_env.config import MAGNETS
from hyperloop_env.physics.actuators import ActuatorSet
from hyperloop_env.scenarios import PAPER_SCENARIOS, SCENARIOS, expand_scenarios
from hyperloop_env.sts import paper_table_markdown

__all__ = [
    "MAGNETS",
    "PAPER_SCENARIOS",
    "evaluate",
    "expand_scenarios",
    "main",
    "run_cases",
    "summarise",
    "summary_table",
]


def _seed_list(seeds: int | Sequence[int]) -> list[int]:
    if isinstance(seeds, int | np.integer) and not isinstance(seeds, bool):
        if seeds < 1:
            raise ValueError(f"seeds must be >= 1, got {seeds!r}")
        return list(range(int(seeds)))
    lst = [int(s) for s in seeds]
    if not lst:
        raise ValueError("seeds must not be empty")
    return lst


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
    configs = {sc: episode_config(sc, distance_km, magnet, env_kwargs) for sc in scenarios}
    steps = {sc: cfg.resolve().episode_steps for sc, cfg in configs.items()}
    total = sum(steps.values()) * len(seeds) * len(controllers)
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
                        configs[sc],
                        seed,
                        distance_km,
                        None,
                        None,
                        step_callback=bar.update if bar is not None else None,
                    )
                    ep.controller = name
                    if bar is not None and ep.terminated:  # count the steps never run
                        bar.update(max(0, steps[sc] - ep.n_steps))
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

    Returns ``{"settings": …, "results": [{"metrics", "report" (STSReport of the levitation
    gaps), "report_guidance" (of the guidance gaps), "table_md", "table_md_guidance",
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
        report, metrics, guidance = summarise(eps, settle_s, n_boot)
        table = paper_table_markdown(report, f"{name} — {sc} ({magnet}): levitation gap s")
        table_g = paper_table_markdown(
            guidance, f"{name} — {sc} ({magnet}): guidance gap z (lateral offset)"
        )
        figs: list[str] = []
        if fig_dir is not None and figures:
            stem = f"{name}_{sc}_{magnet}"
            h = fig_dir / f"hist_{stem}.png"
            hg = fig_dir / f"hist_guidance_{stem}.png"
            ts = fig_dir / f"timeseries_{stem}.png"
            plot_hist(report, eps, settle_s, h)
            plot_hist(guidance, eps, settle_s, hg, signal="guidance")
            plot_timeseries(eps[0], ts)
            figs = [str(h), str(hg), str(ts)]
        results.append({"metrics": metrics, "report": report, "table_md": table,
                        "report_guidance": guidance, "table_md_guidance": table_g,
                        "figures": figs})  # fmt: skip
    settings = {
        "controllers": controllers,
        "scenarios": scen,
        "distance_km": float(distance_km),
        "seeds": seed_list,
        "magnet": magnet,
        "clearance_m": next(iter(episodes.values()))[0].clearance_m,
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
    p.add_argument("--actuators", default="levitation",
                   help="levitation (default: the four levitation coil currents) or "
                   "levitation+guidance (the guidance pairs actuated too)")  # fmt: skip
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
    try:
        ActuatorSet.parse(args.actuators)
    except ValueError as exc:
        parser.error(f"--actuators: {exc}")
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
        n_boot=args.n_boot, command=cmd, env_kwargs={"actuators": args.actuators},
    )  # fmt: skip
    print(summary_table(res["results"]))
    for k, v in res["paths"].items():
        print(f"{k}: {v}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
