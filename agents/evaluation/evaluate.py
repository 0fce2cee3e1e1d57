"""Evaluate controllers over scenarios: STS tables (paper Tables 2–3), RMS excursion,
contacts, ride comfort (ISO 2631-1) and current effort; Markdown + JSON + CSV + PNG.

    python -m agents.evaluate --controllers passive pid lqr --scenarios paper \\
        --distance-km 10 --seeds 5 --out reports/ [--magnet repelling|attracting] [--settle-s 1.0]

``--scenarios paper`` expands to the four paper scenarios; individual names
(``paper-1000-straight`` …, ``random``) are accepted too. Each (controller, scenario, seed)
is one episode of ``HyperloopSuspension-v0`` over ``--distance-km`` (it ends early on
contact; such an episode is reported — time and place of the contact, P(unsteady) = 1 —
never dropped). Seeds: ``--seeds N`` runs from ``--seed0`` (default 1 000 000, the
evaluation range of :mod:`agents.evaluation.seeds`; training uses seeds below 100 000), or
the explicit ``--seed-list``; a learned agent (``ppo`` …, or a saved model) on seeds of the
training range is refused unless ``--allow-training-seeds``.

Files written into ``--out``: ``report.md``, ``results.json``, ``summary.csv`` (one row per
controller × scenario), ``sts_units.csv`` (one row per unit), ``figures/hist_*.png``
(excursion histograms with the fitted density and ±Ω, as the paper's Fig. 5) and
``figures/timeseries_*.png`` (excursions over the run, as Figs. 8–11), named by controller,
scenario and magnet (two controllers whose names give one file name, such as ``/x/a/b`` and
``/x/a_b``, get a short hash of their names: :func:`controller_file_stems`). The pieces:
:mod:`.rollout` (episodes), :mod:`.metrics` (numbers), :mod:`.figures`, :mod:`.report`.

Nothing is lost or mixed: every argument and ``--out`` are checked before the first
episode runs (a path that cannot be written fails at once); a directory that already
holds files is refused unless ``--overwrite`` (``overwrite=True``), which first removes the
files a previous evaluation wrote there (:data:`OUTPUT_FILES`, with its figures) so no
stale figure survives beside the new report; the report files and the figures are
written atomically. One run per directory: the run holds ``--out``'s lock
(:func:`~agents.evaluation.outputs.output_lock`) from the check to the last file, and a
second run on the same directory is refused naming it.
An episode too short to leave :data:`MIN_SETTLED_STEPS` control steps after the settling
time is refused (``--distance-km`` / ``--settle-s``) instead of reporting "n/a".
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import re
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from agents.controllers.registry import (
    controller_problem,
)
from agents.evaluation import seeds as seeding
from agents.evaluation.figures import plot_hist, plot_timeseries
from agents.evaluation.metrics import settle_steps, summarise
from agents.evaluation.outputs import (
    discard_if_empty,
    output_lock,
    prepare_output_dir,
)
from agents.evaluation.report import summary_table, write_outputs
from agents.evaluation.rollout import Episode, episode_config, run_episodes
from hyperloop_env.config import MAGNETS, EnvConfig
from hyperloop_env.physics.model import episode_steps
from hyperloop_env.scenarios import (
    PAPER_SCENARIOS,
    RANDOM_SPEED_RANGE_KMH,
    expand_scenarios,
)
from hyperloop_env.sts import paper_table_markdown

OUTPUT_FILES: tuple[str, ...] = (
    "report.md",
    "results.json",
    "summary.csv",
    "sts_units.csv",
    "figures",
)
"""What an evaluation writes into its output directory (removed first by ``overwrite``)."""

MIN_SETTLED_STEPS = 100
"""Fewest control steps an episode must have after the settling time (0.1 s at the
default 1 ms): the STS fit, RMS and comfort need samples; fewer would be all "n/a"."""

__all__ = [
    "MAGNETS",
    "MIN_SETTLED_STEPS",
    "OUTPUT_FILES",
    "PAPER_SCENARIOS",
    "check_settling",
    "controller_file_stems",
    "episode_configs",
    "evaluate",
    "expand_scenarios",
    "run_cases",
    "summarise",
    "summary_table",
]


def episode_configs(
    scenarios: Sequence[str],
    distance_km: float,
    magnet: str,
    env_kwargs: dict[str, Any] | None = None,
    distance_name: str = "distance_km",
) -> dict[str, EnvConfig]:
    """The episode configuration of each scenario (validated: ``ValueError`` naming
    ``distance_name`` when the distance is what the environment refuses)."""
    out = {}
    for sc in scenarios:
        try:
            out[sc] = episode_config(sc, distance_km, magnet, dict(env_kwargs or {}))
        except ValueError as exc:
            if "track_length_m" not in str(exc):
                raise
            raise ValueError(f"{distance_name}={distance_km:g} is too long ({sc}): {exc}") from None
    return out


def check_settling(
    configs: dict[str, EnvConfig],
    settle_s: float,
    distance_km: float,
    names: tuple[str, str] = ("distance_km", "settle_s"),
) -> None:
    """Refuse episodes that leave fewer than :data:`MIN_SETTLED_STEPS` control steps after
    the settling time (their report would be all "n/a"). ``names`` are the distance and
    settling arguments as the caller's user knows them (``--distance-km``, ``--settle-s``).
    A randomised scenario is checked at the fastest speed it can draw."""
    dist_name, settle_name = names
    for sc, cfg in configs.items():
        res = cfg.resolve()
        p = res.base
        if res.draw_speed:
            p = p.with_(condition=replace(p.condition, speed_kmh=RANDOM_SPEED_RANGE_KMH[1]))
        dt = p.simulation.control_dt_s
        steps = episode_steps(p)
        n0 = settle_steps(settle_s, dt)
        if steps - n0 >= MIN_SETTLED_STEPS:
            continue
        v = p.condition.speed_kmh
        need_km = (n0 + MIN_SETTLED_STEPS) * dt * v / 3.6 / 1000.0
        max_settle = max(0.0, (steps - MIN_SETTLED_STEPS) * dt)
        settle = f"a settling time of {settle_s:g} s"
        lower = ""
        if settle_name:
            settle = f"{settle_name}={settle_s:g} s"
            lower = f" or lower {settle_name} to <= {math.floor(max_settle * 1000) / 1000:g} s"
        raise ValueError(
            f"{settle} leaves too little to evaluate: with "
            f"{dist_name}={distance_km:g} an episode of {sc} at {v:g} km/h lasts "
            f"{steps * dt:.3g} s ({steps} control steps of {dt:g} s), and at least "
            f"{MIN_SETTLED_STEPS} control steps after the settling time are needed for the "
            f"statistics (otherwise every number of the report is n/a); raise {dist_name} to "
            f">= {math.ceil(need_km * 1000) / 1000:g} km{lower}"
        )


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
    ck = controller_kwargs or {}
    configs = episode_configs(scenarios, distance_km, magnet, env_kwargs)
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
                if bar is not None:
                    bar.set_postfix_str(f"{name} {sc}")
                eps = run_episodes(
                    name,
                    configs[sc],
                    seeds,
                    distance_km,
                    None,
                    None,
                    step_callback=bar.update if bar is not None else None,
                    controller_kwargs=ck.get(name, {}),
                )
                for ep in eps:
                    ep.controller = name
                    if bar is not None and ep.terminated:  # count the steps never run
                        bar.update(max(0, steps[sc] - ep.n_steps))
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
    overwrite: bool = False,
    seed0: int = seeding.EVAL_SEED0,
    allow_training_seeds: bool = False,
    workers: int = 1,
) -> dict[str, Any]:
    """Evaluate ``controllers`` (registered names) on ``scenarios`` (names or "paper").

    ``workers``: the (controller, scenario) cases, each with its episodes, STS and figures,
    run in that many spawned worker processes (one compute thread each; 1: in this
    process). The results and files are the same whatever the number: each case is fixed
    by its controller, scenario and seeds, and the report lists them in the order given.

    ``seeds``: a number of episodes per case (seeds ``seed0``, ``seed0 + 1``, …; ``seed0``
    defaults to the evaluation range, :data:`~agents.evaluation.seeds.EVAL_SEED0`) or an
    explicit list of seeds. A learned agent on seeds of the training range is refused
    unless ``allow_training_seeds`` (:func:`agents.evaluation.seeds.check_evaluation_seeds`).

    Returns ``{"settings": …, "results": [{"metrics", "report" (STSReport of the levitation
    gaps), "report_guidance" (of the guidance gaps), "table_md", "table_md_guidance",
    "figures"}, …], "paths": {…}}``; files are written into ``out_dir`` unless it is None.
    Invalid arguments raise ``ValueError`` with a message naming them, before anything
    runs. ``out_dir`` is checked first too (:func:`~agents.evaluation.outputs.prepare_output_dir`):
    a directory that is not writable raises ``OutputDirError`` (a ``ValueError``); one that
    already holds files is refused unless ``overwrite=True``, which removes the files of a
    previous evaluation there (:data:`OUTPUT_FILES`) first; one another run holds raises
    ``OutputLockError`` (an ``OutputDirError``) naming it: the run holds ``out_dir``'s lock
    until its last file is written."""
    controllers = list(controllers)
    if not controllers:
        raise ValueError("controllers must not be empty")
    for c in controllers:  # unknown, not shipped and no path, or the [train] extra missing
        problem = controller_problem(c, (controller_kwargs or {}).get(c))
        if problem:
            raise ValueError(problem)
    scen = expand_scenarios(scenarios)
    if not scen:
        raise ValueError("scenarios must not be empty")
    if not (
        isinstance(distance_km, int | float | np.integer | np.floating)
        and not isinstance(distance_km, bool)
        and math.isfinite(distance_km)
        and distance_km > 0
    ):
        raise ValueError(f"distance_km must be a finite number > 0, got {distance_km!r}")
    if isinstance(workers, bool) or not isinstance(workers, int | np.integer) or workers < 1:
        raise ValueError(f"workers must be an int >= 1, got {workers!r}")
    seed_list = seeding.resolve(seeds, seed0)
    seeding.check_evaluation_seeds(
        controllers, seed_list, allow_training_seeds, names=seeding.API_NAMES
    )
    if magnet not in MAGNETS:
        raise ValueError(f"magnet must be one of {MAGNETS}, got {magnet!r}")
    if not (
        isinstance(settle_s, int | float | np.integer | np.floating)
        and not isinstance(settle_s, bool)
        and math.isfinite(settle_s)
        and settle_s >= 0
    ):
        raise ValueError(f"settle_s must be a finite number >= 0, got {settle_s!r}")
    distance_km, settle_s = float(distance_km), float(settle_s)
    check_settling(episode_configs(scen, distance_km, magnet, env_kwargs), settle_s, distance_km)
    with contextlib.ExitStack() as held:
        out = None
        if out_dir is not None:  # one run per directory, then the usual checks
            held.enter_context(output_lock(out_dir, "evaluation output directory"))
            out = prepare_output_dir(out_dir, overwrite=overwrite, owned=OUTPUT_FILES)
        try:
            return _evaluate(
                controllers,
                scen,
                distance_km,
                seed_list,
                magnet,
                out,
                settle_s,
                progress,
                env_kwargs,
                controller_kwargs,
                figures,
                n_boot,
                command,
                int(workers),
            )
        except BaseException:
            if out is not None:  # nothing written: leave no empty directory behind
                discard_if_empty(out / "figures")
                discard_if_empty(out)
            raise


def _cases_here(
    plan: _Plan, controllers: list[str], progress: bool
) -> tuple[list[dict[str, Any]], float]:
    """Every case in this process: all episodes (:func:`run_cases`), then each case's STS
    and figures."""
    pl = plan
    episodes = run_cases(
        controllers, pl.scenarios, pl.distance_km, pl.seeds, pl.magnet, progress,
        pl.env_kwargs, pl.controller_kwargs,
    )  # fmt: skip
    items = list(episodes.items())
    if progress and items:
        from tqdm import tqdm

        items = tqdm(
            items, desc="STS fits and figures (controller × scenario)", unit="case", file=sys.stderr
        )
    results = [pl.result(name, sc, eps) for (name, sc), eps in items]
    return results, next(iter(episodes.values()))[0].clearance_m


def _cases_on_workers(
    plan: _Plan, controllers: list[str], progress: bool, workers: int
) -> tuple[list[dict[str, Any]], float]:
    """Every case on ``workers`` worker processes (:func:`agents.evaluation.backends.
    run_blocks`), in the order of :func:`run_cases`; progress counts the control steps of
    the finished cases."""
    from agents.evaluation.backends import run_blocks

    pl = plan
    configs = episode_configs(pl.scenarios, pl.distance_km, pl.magnet, pl.env_kwargs)
    cases = [_Case(pl, name, sc) for name in controllers for sc in pl.scenarios]
    planned = [configs[c.scenario].resolve().episode_steps * len(pl.seeds) for c in cases]
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(
            total=sum(planned), desc="evaluate", unit="step", unit_scale=True, file=sys.stderr
        )
    done: dict[int, _CaseDone] = {}
    try:
        for i, res in run_blocks(
            cases,
            workers=workers,
            progress=bar.update if bar is not None else None,
            planned_steps=planned,
            fn=_run_case,
        ):
            done[i] = res
    finally:
        if bar is not None:
            bar.close()
    return [done[i].result for i in range(len(cases))], done[0].clearance_m


def file_stem(name: str) -> str:
    """A controller name as part of a file name (an entry point such as ``pkg.mod:make``
    or a run directory ``runs/x`` has characters a file name cannot hold)."""
    return re.sub(r"[^A-Za-z0-9_.+-]+", "_", name).strip("_") or "controller"


STEM_HASH_CHARS = 8
"""Hex digits of the name's hash that tell apart controllers whose names give one stem."""


def controller_file_stems(names: Sequence[str]) -> dict[str, str]:
    """Each controller's part of its figures' file names: :func:`file_stem`, unless that
    stem is another controller's too (``/x/a/b`` and ``/x/a_b``; ``pid`` and ``PID``, one
    file on a case-insensitive file system) — then the stem and a short hash of the full
    name (``x_a_b-1f0c…``). Deterministic: it depends on the names only, not their order."""
    unique = sorted(set(names))
    stems = {n: file_stem(n) for n in unique}
    clash = _clashing(stems)
    for n in clash:
        digest = hashlib.sha256(n.encode("utf-8")).hexdigest()
        stems[n] = f"{stems[n]}-{digest[:STEM_HASH_CHARS]}"
    width = STEM_HASH_CHARS
    while _clashing(stems):  # a hash prefix shared or a name that looks like a hashed stem
        width += 4
        for n in clash | _clashing(stems):
            digest = hashlib.sha256(n.encode("utf-8")).hexdigest()
            stems[n] = f"{file_stem(n)}-{digest[:width]}"
    return stems


def _clashing(stems: dict[str, str]) -> set[str]:
    """The names whose stem another name has too (compared case-insensitively)."""
    seen: dict[str, list[str]] = {}
    for n, s in stems.items():
        seen.setdefault(s.casefold(), []).append(n)
    return {n for group in seen.values() if len(group) > 1 for n in group}


@dataclass(frozen=True)
class _Plan:
    """What every case of one evaluation shares (picklable: sent to worker processes)."""

    scenarios: tuple[str, ...]
    distance_km: float
    seeds: tuple[int, ...]
    magnet: str
    settle_s: float
    n_boot: int
    env_kwargs: dict[str, Any] | None
    controller_kwargs: dict[str, dict[str, Any]]
    fig_dir: Path | None  # None: no figures
    stems: dict[str, str]  # controller_file_stems

    def result(self, name: str, sc: str, eps: list[Episode]) -> dict[str, Any]:
        """One case's STS, metrics, tables and figures."""
        report, metrics, guidance = summarise(eps, self.settle_s, self.n_boot)
        m = self.magnet
        table = paper_table_markdown(report, f"{name} — {sc} ({m}): levitation gap s")
        table_g = paper_table_markdown(
            guidance, f"{name} — {sc} ({m}): guidance gap z (lateral offset)"
        )
        figs: list[str] = []
        if self.fig_dir is not None:
            stem = f"{self.stems[name]}_{sc}_{m}"
            h = self.fig_dir / f"hist_{stem}.png"
            hg = self.fig_dir / f"hist_guidance_{stem}.png"
            ts = self.fig_dir / f"timeseries_{stem}.png"
            plot_hist(report, eps, self.settle_s, h)
            plot_hist(guidance, eps, self.settle_s, hg, signal="guidance")
            plot_timeseries(eps[0], ts)
            figs = [str(h), str(hg), str(ts)]
        return {
            "metrics": metrics,
            "report": report,
            "table_md": table,
            "report_guidance": guidance,
            "table_md_guidance": table_g,
            "figures": figs,
        }


@dataclass(frozen=True)
class _Case:
    """One (controller, scenario) case of an evaluation, as a worker process runs it."""

    plan: _Plan
    name: str
    scenario: str


@dataclass(frozen=True)
class _CaseDone:
    result: dict[str, Any]
    clearance_m: float
    steps: int  # control steps flown (run_blocks' progress)


def _run_case(case: _Case, progress: Any = None) -> _CaseDone:  # runs in worker processes
    """The episodes of one case (as :func:`run_cases` runs them), then its result;
    ``progress`` (run_blocks' signature) is not used: the pool counts finished cases."""
    pl, sc = case.plan, case.scenario
    eps = run_cases(
        [case.name], [sc], pl.distance_km, pl.seeds, pl.magnet, False, pl.env_kwargs,
        pl.controller_kwargs,
    )[(case.name, sc)]  # fmt: skip
    return _CaseDone(pl.result(case.name, sc, eps), eps[0].clearance_m, sum(e.n_steps for e in eps))


def _evaluate(
    controllers: list[str],
    scen: list[str],
    distance_km: float,
    seed_list: list[int],
    magnet: str,
    out: Path | None,
    settle_s: float,
    progress: bool,
    env_kwargs: dict[str, Any] | None,
    controller_kwargs: dict[str, dict[str, Any]] | None,
    figures: bool,
    n_boot: int,
    command: str | None,
    workers: int = 1,
) -> dict[str, Any]:
    t0 = time.perf_counter()
    fig_dir = out / "figures" if out is not None and figures else None
    stems = controller_file_stems(controllers)
    if fig_dir is not None:
        fig_dir.mkdir(parents=True, exist_ok=True)
    plan = _Plan(
        tuple(scen), distance_km, tuple(seed_list), magnet, settle_s, n_boot, env_kwargs,
        controller_kwargs or {}, fig_dir, stems,
    )  # fmt: skip
    if min(workers, len(controllers) * len(scen)) > 1:
        results, clearance = _cases_on_workers(plan, controllers, progress, workers)
    else:
        results, clearance = _cases_here(plan, controllers, progress)
    if fig_dir is not None and results:
        from agents.evaluation.report import plot_comparison

        plot_comparison(results, fig_dir / "comparison.png")
    settings = {
        "controllers": controllers,
        "scenarios": scen,
        "distance_km": distance_km,
        "seeds": seed_list,
        "magnet": magnet,
        "clearance_m": clearance,
        "settle_s": settle_s,
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
