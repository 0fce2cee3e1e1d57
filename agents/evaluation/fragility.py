"""Fragility evaluation: how the probability of contact grows with a disturbance's severity.

    python -m agents.fragility --controllers passive pid lqr ppo --conditions paper-1000-straight \\
        --family roughness --levels 0.1 0.15 0.2 0.25 0.3 0.4 0.5 0.7 --seeds 20 \\
        --distance-km 10 --out reports/fragility [--backend local --workers 2 | --backend ray]

For every controller × condition (scenario) × severity level, ``--seeds`` runs (seeds
``--seed0``, ``--seed0`` + 1, …, default from 1 000 000 — the evaluation range of
:mod:`agents.evaluation.seeds` — or the explicit ``--seed-list``; the same for every
controller and level: common random numbers) fly ``--distance-km`` each with the
disturbance family ``--family`` at that severity (``disturbances={family: level}``;
``--with NAME=SEVERITY`` adds fixed ones). A learned agent (``ppo`` …, or a saved model)
on seeds of the training range (< 100 000) is refused unless ``--allow-training-seeds``.
A run ends at its first contact (termination) or at the end of the section. Reported per
controller, condition and level:

* the contact probability per run with a Clopper–Pearson (``--interval exact``, default)
  or Wilson interval, and the contact kinds;
* the contact rate per 100 km: contacts / distance flown, with Garwood's exact Poisson
  interval;
* the paper's P(unsteady) (worst unit, :func:`hyperloop_env.sts.analyse_episodes` on the
  thinned gap signals: fitted law with its block-bootstrap interval, contacts included as
  ``f + (1 − f)·P_fit``) and beside it the empirical exceedance — from the STS sample and,
  exactly, from every sample of the runs; the same P(unsteady) of the guidance gaps
  (lateral offsets against Ω_g) in the JSON/CSV;
* RMS and maximum gap excursion, ISO 2631-1 comfort (W_k, W_d, vibration total value;
  streamed, equal to :mod:`hyperloop_env.comfort` on the full signal).

Per controller and condition, a lognormal fragility function ``Φ(ln(s/θ)/β)`` is fitted by
maximum likelihood to the binary run outcomes (:mod:`.fragility_fit`, Baker 2015) with a
bootstrap of the runs within levels; degenerate data (no contact, all contact, separated
outcomes) are reported as bounds, never as a fit. Figures: one per condition, probability
against severity, data points with their intervals and the fitted curves, one colour per
controller.

Long runs are never stored (:mod:`.streaming`, :mod:`.batch_rollout`): exact counts and
running moments, a streamed ISO filter, and a thinned gap signal for the STS fit, at most
``--max-samples`` samples per unit and controller × condition × level (thinning stride ``k =
ceil(seeds × steps / max_samples)``). Memory: a group holds ``2 signals × 4 units ×
max_samples × 8 B`` of thinned samples (6.4 MB at the default 100 000) while its blocks are
in flight; each group is analysed and its samples dropped as soon as its last block arrives.
A block (``--block-size`` seeds, fewer for long runs so that the environments' guideway
profiles — about 64 B per 0.1 m of track and run — stay under ``--max-block-mb``) runs
batched on the native vector env when the controller
has ``act_batch``, else as single-env episodes (:mod:`.batch_rollout` documents the
protocol). Blocks run here, on local worker processes or on Ray (:mod:`.backends`); results
are identical for any backend and number of workers.

Files written into ``--out`` (checked before any work, every argument first; a non-empty
directory is refused unless ``--overwrite``; the directory is held for the run —
``<out>/.lock`` with the pid, a second run on it is refused naming that pid):
``report.md``, ``results.json``, ``fragility_levels.csv`` (one row per controller ×
condition × level), ``fragility_fits.csv`` (one row per controller × condition) and
``figures/fragility_<condition>.png``.
"""

from __future__ import annotations

import contextlib
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from agents.controllers import available_controllers
from agents.controllers.registry import (
    controller_problem,
)
from agents.evaluation import seeds as seeding
from agents.evaluation.backends import run_blocks
from agents.evaluation.batch_rollout import BlockResult, BlockSpec, RunResult, max_steps
from agents.evaluation.figures import plot_fragility as plot_fragility  # its old home
from agents.evaluation.fragility_fit import (
    binomial_interval,
    fit_fragility,
    poisson_rate_interval,
)
from agents.evaluation.outputs import (
    discard_if_empty,
    output_lock,
    prepare_output_dir,
)
from agents.evaluation.rollout import episode_config
from agents.evaluation.streaming import merge_moments, moments_summary
from hyperloop_env.comfort import comfort_label
from hyperloop_env.config import MAGNETS, EnvConfig
from hyperloop_env.disturbances import DISTURBANCES, make_disturbance
from hyperloop_env.physics.units import UNIT_NAMES
from hyperloop_env.scenarios import expand_scenarios
from hyperloop_env.sts import STSReport, analyse_episodes

OWNED = ("report.md", "results.json", "fragility_levels.csv", "fragility_fits.csv", "figures")
DEFAULT_MAX_SAMPLES = 100_000
DEFAULT_BLOCK_SIZE = 16
DEFAULT_MAX_BLOCK_MB = 2048.0
PROFILE_BYTES_PER_POINT = 64
"""Memory per guideway-profile grid point and run held by the environment (the
simulator's precomputed (3, n) profile and the transient arrays that generate it; measured
with ``speed/bench_fragility.py --part memory``: one 1000 km run, n = 2^24 points,
peak RSS 1257 MB against 216 MB for 1 km, i.e. about 65 B per point). The profile grows
with the distance (0.1 m grid, rounded up to a power of two), so blocks of long runs are
made smaller to keep a block under ``max_block_mb``."""


def block_rows(config: EnvConfig, block_size: int, max_block_mb: float) -> int:
    """Seeds per block: ``block_size``, reduced so that the runs' guideway profiles stay
    under ``max_block_mb`` (at least one run)."""
    from hyperloop_env.physics.model import profile_grid

    n, _ = profile_grid(config.resolve().base)
    per_row = n * PROFILE_BYTES_PER_POINT / 2**20
    return max(1, min(block_size, int(max_block_mb // per_row)))


@dataclass(frozen=True)
class Group:
    """One controller × condition × level: its configuration and thinning stride."""

    index: int
    controller: str
    condition: str
    level: float
    config: EnvConfig
    thin_stride: int
    planned_steps_per_run: int


@dataclass
class Plan:
    groups: list[Group]
    blocks: list[BlockSpec]
    block_group: list[int]
    planned_steps: list[int]
    seeds: list[int] = field(default_factory=list)


def _level_disturbances(family: str, level: float, fixed: dict[str, float]) -> dict[str, Any]:
    d = {name: make_disturbance(name, sev) for name, sev in fixed.items()}
    d[family] = make_disturbance(family, level)
    return d


def make_plan(
    controllers: Sequence[str],
    conditions: Sequence[str],
    family: str,
    levels: Sequence[float],
    seeds: Sequence[int],
    distance_km: float,
    *,
    magnet: str = "repelling",
    fixed: dict[str, float] | None = None,
    env_kwargs: dict[str, Any] | None = None,
    controller_kwargs: dict[str, dict[str, Any]] | None = None,
    settle_s: float = 1.0,
    block_size: int = DEFAULT_BLOCK_SIZE,
    max_samples: int = DEFAULT_MAX_SAMPLES,
    batched: bool | None = None,
    chunk_steps: int = 1024,
    max_block_mb: float = DEFAULT_MAX_BLOCK_MB,
) -> Plan:
    """The groups and the blocks of seeds (fixed by the arguments alone — never by the
    backend or the number of workers)."""
    fixed = dict(fixed or {})
    ck = controller_kwargs or {}
    groups: list[Group] = []
    blocks: list[BlockSpec] = []
    owner: list[int] = []
    planned: list[int] = []
    seeds = [int(s) for s in seeds]
    for ctrl in controllers:
        for cond in conditions:
            for li, level in enumerate(levels):
                kw = dict(env_kwargs or {})
                kw["disturbances"] = _level_disturbances(family, float(level), fixed)
                cfg = episode_config(cond, distance_km, magnet, kw)
                steps = max_steps(cfg)
                stride = max(1, math.ceil(len(seeds) * steps / max_samples))
                g = Group(len(groups), ctrl, cond, float(level), cfg, stride, steps)
                groups.append(g)
                rows = block_rows(cfg, block_size, max_block_mb)
                for b in range(0, len(seeds), rows):
                    block = tuple(seeds[b : b + rows])
                    blocks.append(
                        BlockSpec(
                            controller=ctrl,
                            config=cfg,
                            seeds=block,
                            settle_s=settle_s,
                            thin_stride=stride,
                            controller_kwargs=dict(ck.get(ctrl, {})),
                            chunk_steps=chunk_steps,
                            batched=batched,
                            key=(ctrl, cond, li, b // rows),
                        )
                    )
                    owner.append(g.index)
                    planned.append(steps * len(block))
    return Plan(groups, blocks, owner, planned, seeds)


# --------------------------------------------------------------------------------------
# aggregation of one group
# --------------------------------------------------------------------------------------


def _mean_finite(vals: list[float]) -> float:
    v = [x for x in vals if math.isfinite(x)]
    return float(np.mean(v)) if v else math.nan


def _contact_fields(runs: list[RunResult], interval: str) -> dict[str, Any]:
    """The group's contacts: P(contact) per run with its interval, kinds, positions and the
    rate per 100 km."""
    n = len(runs)
    k = sum(r.terminated for r in runs)
    kinds: dict[str, int] = {}
    for r in runs:
        if r.contact_kind:
            kinds[r.contact_kind] = kinds.get(r.contact_kind, 0) + 1
    dist_km = sum(r.distance_m for r in runs) / 1e3
    rate, rlo, rhi = poisson_rate_interval(k, dist_km / 100.0)
    first = min(
        (r for r in runs if r.terminated), key=lambda r: r.contact_position_m or 0.0, default=None
    )
    return {
        "n_contacts": k,
        "p_contact": k / n,
        "p_contact_ci": list(binomial_interval(k, n, interval)),
        "interval": interval,
        "contact_kinds": kinds,
        "first_contact_position_m": first.contact_position_m if first else None,
        "contact_positions_m": [r.contact_position_m for r in runs if r.terminated],
        "distance_km": dist_km,
        "contact_rate_per_100km": rate,
        "contact_rate_per_100km_ci": [rlo, rhi],
    }


def _worst_unit_fields(report: STSReport) -> dict[str, Any]:
    """The levitation gaps' STS: the worst unit's P(unsteady), fit and exceedance."""
    worst = max(report.units, key=lambda u: u.p_unsteady if math.isfinite(u.p_unsteady) else -1)
    return {
        "p_unsteady": report.worst_p_unsteady,
        "unit": report.worst_unit,
        "p_unsteady_ci": list(worst.p_unsteady_ci),
        "p_unsteady_fit": worst.p_unsteady_fit,
        "p_unsteady_fit_ci": list(worst.p_unsteady_fit_ci),
        "distribution": worst.distribution,
        "empirical_exceedance": worst.empirical_exceedance,
        "empirical_exceedance_ci": list(worst.empirical_exceedance_ci),
    }


def _moment_fields(runs: list[RunResult], b0: BlockResult) -> dict[str, Any]:
    """The group's exact counts and moments: exceedance counts at the block's levels, RMS
    and maximum gap, RMS lateral offset and current deviation."""
    om = b0.clearance_m
    gap = moments_summary(merge_moments([r.gap for r in runs]))
    lat = moments_summary(merge_moments([r.lateral for r in runs]))
    cur = moments_summary(merge_moments([r.current_dev for r in runs]))
    gm = merge_moments([r.gap for r in runs])
    n_post = int(gm["n"][0])
    rms_all = math.sqrt(float(gm["sumsq"].sum()) / gm["n"].sum()) if n_post else math.nan
    exceed = np.sum([r.exceed for r in runs], axis=0)
    exceed_any = np.sum([r.exceed_any for r in runs], axis=0)
    levels_m = b0.exceed_levels_m
    at_om = [j for j, lv in enumerate(levels_m) if abs(lv - om) < 1e-15]
    exc_exact = float(exceed_any[at_om[0]] / n_post) if at_om and n_post else math.nan
    return {
        "exceedance_any_unit_exact": exc_exact,
        "exceedance_levels_mm": [lv * 1e3 for lv in levels_m],
        "exceedance_counts_any_unit": exceed_any.tolist(),
        "exceedance_counts_units": exceed.tolist(),
        "n_samples_after_settle": n_post,
        "rms_gap_mm": rms_all * 1e3,
        "rms_gap_units_mm": (gap["rms"] * 1e3).tolist(),
        "std_gap_units_mm": (gap["std"] * 1e3).tolist(),
        "max_abs_gap_mm": float(gm["maxabs"].max()) * 1e3 if n_post else math.nan,
        "rms_lateral_mm": float(np.sqrt(np.mean(lat["rms"] ** 2))) * 1e3,
        "rms_current_dev_A": float(np.sqrt(np.mean(cur["rms"] ** 2))),
    }


def _comfort_fields(runs: list[RunResult]) -> dict[str, Any]:
    """The runs' mean ISO 2631-1 weighted accelerations and the comfort label."""
    a_wz = _mean_finite([r.a_wz_m_s2 for r in runs])
    a_wy = _mean_finite([r.a_wy_m_s2 for r in runs])
    a_v = _mean_finite([r.a_v_m_s2 for r in runs])
    return {
        "a_wz_m_s2": a_wz,
        "a_wy_m_s2": a_wy,
        "a_v_m_s2": a_v,
        "comfort": comfort_label(a_v),
    }


def summarise_group(
    g: Group,
    blocks: list[BlockResult],
    *,
    interval: str = "exact",
    n_boot: int = 200,
    settle_s: float = 1.0,
) -> dict[str, Any]:
    """Every number of one controller × condition × level from its blocks (in block
    order, so the result does not depend on the order they finished in)."""
    runs: list[RunResult] = [r for b in blocks for r in b.runs]
    b0 = blocks[0]
    dt = b0.dt_s
    report = analyse_episodes(
        [(r.thinned_gap, r.terminated) for r in runs],
        dt * g.thin_stride,
        settle_s=settle_s,
        n_boot=n_boot,
        clearance_m=b0.clearance_m,
    )
    guidance = analyse_episodes(
        [(r.thinned_lateral, r.terminated) for r in runs],
        dt * g.thin_stride,
        settle_s=settle_s,
        n_boot=n_boot,
        clearance_m=b0.lateral_clearance_m,
    )
    return {
        "controller": g.controller,
        "condition": g.condition,
        "level": g.level,
        "n_runs": len(runs),
        "seeds": [r.seed for r in runs],
        **_contact_fields(runs, interval),
        **_worst_unit_fields(report),
        **_moment_fields(runs, b0),
        **_comfort_fields(runs),
        "p_unsteady_guidance": guidance.worst_p_unsteady,
        "unit_guidance": guidance.worst_unit,
        "sts": report.to_dict(),
        "sts_guidance": guidance.to_dict(),
        "thin_stride": g.thin_stride,
        "n_thinned_samples": int(sum(r.thinned_gap.shape[0] for r in runs)),  # per signal
        "steps": int(sum(r.n_steps for r in runs)),
        "batched": bool(b0.batched),
        "wall_s": float(sum(b.wall_s for b in blocks)),
    }


# --------------------------------------------------------------------------------------
# the sweep
# --------------------------------------------------------------------------------------


def check_args(
    controllers: Sequence[str],
    conditions: Sequence[str],
    family: str,
    levels: Sequence[float],
    seeds: int | Sequence[int],
    distance_km: float,
    magnet: str,
    settle_s: float,
    block_size: int,
    max_samples: int,
    interval: str,
    max_block_mb: float = DEFAULT_MAX_BLOCK_MB,
    seed0: int = seeding.EVAL_SEED0,
    allow_training_seeds: bool = False,
    *,
    n_boot: int = 200,
    n_boot_fragility: int = 1000,
    fixed: dict[str, float] | None = None,
    env_kwargs: dict[str, Any] | None = None,
) -> tuple[list[str], list[float], list[int]]:
    """Every argument of a sweep, checked before anything is created or run (ValueError
    naming the argument)."""
    if not controllers:
        raise ValueError("controllers must not be empty")
    for c in controllers:
        problem = controller_problem(c)
        if problem and c not in available_controllers():
            raise ValueError(problem)
    repeated = sorted({c for c in controllers if list(controllers).count(c) > 1})
    if repeated:
        raise ValueError(
            f"controllers repeat: {', '.join(repeated)} (each is computed once; "
            "give every controller once)"
        )
    for name, v, lo in (("--n-boot", n_boot, 0), ("--n-boot-fragility", n_boot_fragility, 1)):
        if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < lo:
            raise ValueError(
                f"{name} (n_boot{'_fragility' if lo else ''}) must be an integer >= {lo}, got {v!r}"
            )
    cond = expand_scenarios(list(conditions))
    if not cond:
        raise ValueError("conditions must not be empty")
    if family not in DISTURBANCES:
        raise ValueError(f"unknown disturbance family {family!r}; valid: {list(DISTURBANCES)}")
    lv = [float(x) for x in levels]
    if not lv:
        raise ValueError("levels must not be empty")
    if len(set(lv)) != len(lv):
        raise ValueError(f"levels must be distinct, got {lv}")
    for x in lv:
        make_disturbance(family, x)  # raises ValueError naming the field
    seed_list = seeding.resolve(seeds, seed0)
    seeding.check_evaluation_seeds(
        controllers, seed_list, allow_training_seeds, names=seeding.API_NAMES
    )
    if not (
        isinstance(distance_km, int | float) and math.isfinite(distance_km) and distance_km > 0
    ):
        raise ValueError(f"distance_km must be a finite number > 0, got {distance_km!r}")
    if magnet not in MAGNETS:
        raise ValueError(f"magnet must be one of {MAGNETS}, got {magnet!r}")
    if not (math.isfinite(settle_s) and settle_s >= 0):
        raise ValueError(f"settle_s must be a finite number >= 0, got {settle_s!r}")
    if block_size < 1:
        raise ValueError(f"block_size must be >= 1, got {block_size!r}")
    if not max_block_mb > 0:
        raise ValueError(f"max_block_mb must be > 0, got {max_block_mb!r}")
    if max_samples < 100:
        raise ValueError(f"max_samples must be >= 100, got {max_samples!r}")
    if interval not in ("exact", "wilson"):
        raise ValueError(f"interval must be 'exact' or 'wilson', got {interval!r}")
    for name in fixed or {}:
        if name == family:
            raise ValueError(f"--with {name}: that is the swept family")
        make_disturbance(name, fixed[name])  # type: ignore[index]
    _check_settle(cond, float(distance_km), magnet, env_kwargs, float(settle_s))
    return cond, lv, seed_list


def _check_settle(
    conditions: list[str],
    distance_km: float,
    magnet: str,
    env_kwargs: dict[str, Any] | None,
    settle_s: float,
) -> None:
    """Refuse a settling time that is not shorter than a run (every statistic would be
    n/a): the shortest run of each condition (a randomised speed at its fastest)."""
    from dataclasses import replace

    from agents.evaluation.evaluate import episode_configs
    from agents.evaluation.metrics import settle_steps
    from hyperloop_env.physics.model import episode_steps

    configs = episode_configs(conditions, distance_km, magnet, env_kwargs, "--distance-km")
    for sc, cfg in configs.items():
        res = cfg.resolve()
        p = res.base
        if res.draw_speed and res.scenario.random is not None:
            top = res.scenario.random.speed_range_kmh[1]
            p = p.with_(condition=replace(p.condition, speed_kmh=top))
        dt = p.simulation.control_dt_s
        steps = episode_steps(p)
        if settle_steps(settle_s, dt) >= steps:
            raise ValueError(
                f"--settle-s (settle_s) = {settle_s:g} s is not shorter than a run: with "
                f"--distance-km {distance_km:g} a run of {sc} lasts {steps * dt:.3g} s, so no "
                "sample would be left after settling and every statistic would be n/a; lower "
                "--settle-s or raise --distance-km"
            )


def fragility(
    controllers: Sequence[str],
    conditions: Sequence[str],
    family: str,
    levels: Sequence[float],
    seeds: int | Sequence[int] = 10,
    distance_km: float = 10.0,
    *,
    magnet: str = "repelling",
    fixed: dict[str, float] | None = None,
    env_kwargs: dict[str, Any] | None = None,
    controller_kwargs: dict[str, dict[str, Any]] | None = None,
    settle_s: float = 1.0,
    block_size: int = DEFAULT_BLOCK_SIZE,
    max_samples: int = DEFAULT_MAX_SAMPLES,
    max_block_mb: float = DEFAULT_MAX_BLOCK_MB,
    batched: bool | None = None,
    interval: str = "exact",
    n_boot: int = 200,
    n_boot_fragility: int = 1000,
    backend: str = "local",
    workers: int = 1,
    address: str | None = None,
    out_dir: str | Path | None = None,
    overwrite: bool = False,
    figures: bool = True,
    progress: bool = True,
    command: str | None = None,
    seed0: int = seeding.EVAL_SEED0,
    allow_training_seeds: bool = False,
) -> dict[str, Any]:
    """Run a fragility sweep (module docstring); returns ``{"settings", "levels",
    "fits", "paths"}`` and writes the files into ``out_dir`` unless it is None. The
    output directory is checked before any computation.

    ``seeds``: runs per level (seeds ``seed0``, ``seed0 + 1``, …; ``seed0`` defaults to the
    evaluation range, :data:`~agents.evaluation.seeds.EVAL_SEED0`) or an explicit list. A
    learned agent on seeds of the training range is refused unless ``allow_training_seeds``
    (:func:`agents.evaluation.seeds.check_evaluation_seeds`)."""
    cond, lv, seed_list = check_args(
        controllers,
        conditions,
        family,
        levels,
        seeds,
        distance_km,
        magnet,
        settle_s,
        block_size,
        max_samples,
        interval,
        max_block_mb,
        seed0,
        allow_training_seeds,
        n_boot=n_boot,
        n_boot_fragility=n_boot_fragility,
        fixed=fixed,
        env_kwargs=env_kwargs,
    )
    for c in controllers:  # not shipped and no path, or the [train] extra missing
        problem = controller_problem(c, (controller_kwargs or {}).get(c))
        if problem:
            raise ValueError(problem)
    with contextlib.ExitStack() as held:
        out = None
        if out_dir is not None:  # one run per directory, then the usual checks
            held.enter_context(output_lock(out_dir, "fragility output directory"))
            out = prepare_output_dir(out_dir, overwrite=overwrite, owned=OWNED)
        return _sweep(
            out,
            controllers,
            cond,
            family,
            lv,
            seed_list,
            distance_km,
            magnet=magnet,
            fixed=fixed,
            env_kwargs=env_kwargs,
            controller_kwargs=controller_kwargs,
            settle_s=settle_s,
            block_size=block_size,
            max_samples=max_samples,
            max_block_mb=max_block_mb,
            batched=batched,
            interval=interval,
            n_boot=n_boot,
            n_boot_fragility=n_boot_fragility,
            backend=backend,
            workers=workers,
            address=address,
            figures=figures,
            progress=progress,
            command=command,
        )


def _sweep(
    out: Path | None,
    controllers: Sequence[str],
    cond: list[str],
    family: str,
    lv: list[float],
    seed_list: list[int],
    distance_km: float,
    *,
    magnet: str,
    fixed: dict[str, float] | None,
    env_kwargs: dict[str, Any] | None,
    controller_kwargs: dict[str, dict[str, Any]] | None,
    settle_s: float,
    block_size: int,
    max_samples: int,
    max_block_mb: float,
    batched: bool | None,
    interval: str,
    n_boot: int,
    n_boot_fragility: int,
    backend: str,
    workers: int,
    address: str | None,
    figures: bool,
    progress: bool,
    command: str | None,
) -> dict[str, Any]:
    """:func:`fragility` after its checks (``out``: the checked output directory)."""
    t0 = time.perf_counter()
    try:
        plan = make_plan(
            list(controllers),
            cond,
            family,
            lv,
            seed_list,
            float(distance_km),
            magnet=magnet,
            fixed=fixed,
            env_kwargs=env_kwargs,
            controller_kwargs=controller_kwargs,
            settle_s=settle_s,
            block_size=block_size,
            max_samples=max_samples,
            batched=batched,
            max_block_mb=max_block_mb,
        )
        rows = _execute(plan, backend, workers, address, progress, interval, n_boot, settle_s)
    except BaseException:
        if out is not None:
            discard_if_empty(out)
        raise
    fits = fit_all(rows, list(controllers), cond, n_boot_fragility)
    unit = DISTURBANCES[family].severity_unit
    settings = {
        "controllers": list(controllers),
        "conditions": cond,
        "family": family,
        "severity_unit": unit,
        "levels": lv,
        "seeds": seed_list,
        "distance_km": float(distance_km),
        "magnet": magnet,
        "fixed_disturbances": dict(fixed or {}),
        "env_kwargs": env_kwargs or {},
        "settle_s": float(settle_s),
        "block_size": int(block_size),
        "max_block_mb": float(max_block_mb),
        "max_samples": int(max_samples),
        "interval": interval,
        "n_boot_sts": int(n_boot),
        "n_boot_fragility": int(n_boot_fragility),
        "backend": backend,
        "workers": int(workers),
        "wall_s": time.perf_counter() - t0,
        "command": command or "agents.evaluation.fragility.fragility(...)",
        "memory_bound": (
            f"thinned STS samples: at most {max_samples} per unit, signal (levitation and "
            f"guidance gap) and controller × condition × level "
            f"({2 * len(UNIT_NAMES) * max_samples * 8 / 1e6:.1f} MB), freed when the "
            "group is analysed"
        ),
    }
    res = {"settings": settings, "levels": rows, "fits": fits, "paths": {}}
    if out is not None:
        from agents.evaluation.fragility_report import write_outputs

        res["paths"] = write_outputs(res, out, figures)
    return res


def _execute(
    plan: Plan,
    backend: str,
    workers: int,
    address: str | None,
    progress: bool,
    interval: str,
    n_boot: int,
    settle_s: float,
) -> list[dict[str, Any]]:
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(
            total=sum(plan.planned_steps),
            desc="fragility",
            unit="step",
            unit_scale=True,
            file=sys.stderr,
        )
    need = [0] * len(plan.groups)
    for gi in plan.block_group:
        need[gi] += 1
    got: dict[int, dict[int, BlockResult]] = {}
    rows: dict[int, dict[str, Any]] = {}
    try:
        for i, res in run_blocks(
            plan.blocks,
            backend,
            workers,
            address,
            bar.update if bar is not None else None,
            plan.planned_steps,
        ):
            gi = plan.block_group[i]
            got.setdefault(gi, {})[i] = res
            if len(got[gi]) == need[gi]:
                blocks = [got[gi][j] for j in sorted(got[gi])]
                g = plan.groups[gi]
                if bar is not None:
                    bar.set_postfix_str(f"{g.controller} {g.condition} {g.level:g}")
                rows[gi] = summarise_group(
                    g, blocks, interval=interval, n_boot=n_boot, settle_s=settle_s
                )
                del got[gi]  # free the thinned samples
    finally:
        if bar is not None:
            bar.close()
    return [rows[i] for i in range(len(plan.groups))]


def fit_all(
    rows: list[dict[str, Any]], controllers: list[str], conditions: list[str], n_boot: int
) -> list[dict[str, Any]]:
    fits = []
    for ci, ctrl in enumerate(controllers):
        for di, cond in enumerate(conditions):
            rs = sorted(
                (r for r in rows if r["controller"] == ctrl and r["condition"] == cond),
                key=lambda r: r["level"],
            )
            f = fit_fragility(
                [r["level"] for r in rs],
                [r["n_runs"] for r in rs],
                [r["n_contacts"] for r in rs],
                n_boot=n_boot,
                rng=np.random.default_rng([ci, di]),
            )
            fits.append({"controller": ctrl, "condition": cond, "fit": f, "summary": f.summary()})
    return fits


# --------------------------------------------------------------------------------------
# outputs
# --------------------------------------------------------------------------------------


# --------------------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------------------
