"""Ride comfort of controllers on common evaluation seeds, compared pairwise (``hyperloop
compare comfort``).

Per condition and seed, every controller flies the same run (the scenario's own
irregularity, evaluation seeds from 1 000 000 by default, ``distance_km`` km); its ISO
2631-1 comfort is the W_k-weighted RMS vertical acceleration a_wz [m/s²] of the capsule
after the 1 s settling time (:func:`hyperloop_env.comfort.ride_comfort`; a run that
touched is left out of both sides of a pair). Each controller is compared with the
reference on the common seeds by :func:`agents.evaluation.capacity_stats.compare_paired`
applied to a_wz (the geometric mean of the per-seed ratios, paired bootstrap 95 %
interval, Wilcoxon test, verdict with the ±5 % equivalence band). Lower a_wz is a smoother
ride, so "W_k no worse than the reference" means the verdict is ``below`` or
``equivalent``. :func:`run` writes ``comfort.json`` and ``comfort.md`` (refused if they
exist, unless ``overwrite``); :func:`comfort_table` recomputes the rows from the per-seed
values a ``comfort.json`` keeps.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from agents.evaluation import seeds as seeding
from agents.evaluation.capacity_stats import compare_paired
from agents.evaluation.outputs import atomic_write_text, output_lock
from agents.evaluation.settings import check_setting
from hyperloop_env.scenarios import PAPER_SCENARIOS

SETTLE_S = 1.0
DEFAULT_SEEDS = 32
DEFAULT_DISTANCE_KM = 3.0
DEFAULT_REFERENCE = "lqr"
FILES = ("comfort.json", "comfort.md")


@dataclass(frozen=True)
class ComfortSpec:
    """What a comfort comparison flies: the ``controllers`` and the ``reference`` on every
    condition, the ``seeds`` (at least two), ``distance_km`` per run; checked on
    construction (``ValueError`` naming the flag)."""

    controllers: tuple[str, ...]
    seeds: tuple[int, ...]
    reference: str = DEFAULT_REFERENCE
    conditions: tuple[str, ...] = PAPER_SCENARIOS
    distance_km: float = DEFAULT_DISTANCE_KM
    allow_training_seeds: bool = False

    def __post_init__(self) -> None:
        if not self.controllers:
            raise ValueError("--controllers: name at least one controller")
        if not self.conditions:
            raise ValueError("--conditions: name at least one condition")
        if len(self.seeds) < 2:
            raise ValueError(f"--seeds must be >= 2, got {len(self.seeds)}")
        v = self.distance_km
        check_setting("distance_km", v, required=True)
        from agents.evaluation.entrants import entrant_actuators
        from agents.evaluation.evaluate import check_settling, episode_configs

        for c in self.names:  # one line before any run, not a traceback mid-comparison
            entrant_actuators(c)  # a controller, or name+g with the guidance pairs

        cfgs = episode_configs(self.conditions, v, None, None, "--distance-km")
        check_settling(cfgs, SETTLE_S, v, ("--distance-km", "--settle-s"))
        seeding.check_evaluation_seeds(self.names, list(self.seeds), self.allow_training_seeds)

    @property
    def names(self) -> list[str]:
        """The reference first, then the other controllers (each once)."""
        return list(dict.fromkeys([self.reference, *self.controllers]))


@dataclass(frozen=True)
class RideTask:
    """The comfort runs of one entrant on one condition: ``seeds`` × ``km`` km."""

    controller: str
    condition: str
    seeds: tuple[int, ...]
    km: float


@dataclass(frozen=True)
class RideResult:
    a_wz: list[float | None]  # per seed, None: the run touched
    steps: int  # control steps flown


def fly_ride(task: RideTask, progress: Any = None) -> RideResult:
    """W_k-weighted RMS heave acceleration [m/s²] per seed of one :class:`RideTask` (None:
    the run touched). ``controller`` is an entrant
    (:func:`agents.evaluation.entrants.entrant_actuators`): a controller name flies the
    levitation currents, ``name+g`` the guidance currents too, a learned agent the actuator
    set it was trained with — as in the capacity runs. Module level: the workers of
    :func:`~agents.evaluation.backends.run_blocks` call it."""
    from agents.evaluation.entrants import entrant_actuators
    from agents.evaluation.rollout import run_episodes
    from hyperloop_env.comfort import ride_comfort

    base, actuators = entrant_actuators(task.controller)
    out: list[float | None] = []
    eps = run_episodes(
        base, task.condition, list(task.seeds), task.km, None, {"actuators": actuators}
    )
    for e in eps:
        if e.terminated:
            out.append(None)
        else:
            out.append(
                ride_comfort(e.acc_m_s2[1:, 0], e.acc_m_s2[1:, 1], e.dt_s, SETTLE_S).a_wz_m_s2
            )
    return RideResult(out, sum(e.n_steps for e in eps))


def a_wz(controller: str, condition: str, seeds: list[int], km: float) -> list[float | None]:
    """:func:`fly_ride` of one entrant on one condition, in this process."""
    return fly_ride(RideTask(controller, condition, tuple(seeds), km)).a_wz


def ride_table(
    conditions: Sequence[str],
    entrants: Sequence[str],
    seeds: Sequence[int],
    km: float,
    *,
    workers: int = 1,
    backend: str = "local",
    address: str | None = None,
    log: Callable[[str], None] | None = None,
) -> tuple[dict[str, dict[str, list[float | None]]], float]:
    """``({condition: {entrant: a_wz per seed}}, wall time [s])``: every entrant's
    :func:`fly_ride` on every condition, one task each on ``workers`` processes (or Ray:
    :func:`~agents.evaluation.backends.run_blocks`); the same values whatever the number.
    ``log`` gets a line as each condition is done."""
    from agents.evaluation.backends import run_blocks

    tasks = [RideTask(e, c, tuple(seeds), km) for c in conditions for e in entrants]
    left = dict.fromkeys(conditions, len(entrants))
    got: list[list[float | None]] = [[] for _ in tasks]
    t0 = time.perf_counter()
    elapsed = 0.0
    for i, res in run_blocks(tasks, backend, workers, address, fn=fly_ride):
        got[i] = res.a_wz
        cond = tasks[i].condition
        left[cond] -= 1
        elapsed = time.perf_counter() - t0  # one reading: the log line and the wall time
        if log is not None and not left[cond]:
            log(f"{cond}: done ({elapsed:.0f} s)")
    per = {c: {e: got[k * len(entrants) + j] for j, e in enumerate(entrants)}
           for k, c in enumerate(conditions)}  # fmt: skip
    return per, elapsed


def compare(a: list[float | None], b: list[float | None]) -> dict[str, Any]:
    """``a`` paired with ``b`` on the seeds where neither touched (none: ``undecided``,
    no ratio)."""
    if len(a) != len(b):
        raise ValueError(f"a has {len(a)} seeds, b has {len(b)}: pair them on the same seeds")
    keep = [i for i in range(len(a)) if a[i] is not None and b[i] is not None]
    if not keep:
        none = dict.fromkeys(("ratio", "lo", "hi", "p_value"))
        return {"n": 0, **none, "verdict": "undecided"}
    x = np.array([a[i] for i in keep])
    y = np.array([b[i] for i in keep])
    no = np.zeros(len(keep), dtype=bool)
    res = compare_paired(x, no, y, no)
    return {"n": len(keep), **{k: res[k] for k in ("ratio", "lo", "hi", "p_value", "verdict")}}


def comfort_table(
    per: dict[str, dict[str, list[float | None]]], reference: str
) -> list[dict[str, Any]]:
    """The rows of ``comfort.json`` from the per-seed a_wz (condition → controller → per
    seed; the reference first): mean a_wz, contacts, and the paired ratio to the
    reference."""
    rows = []
    for cond, by in per.items():
        ref = by[reference]
        for c, vals_all in by.items():
            vals = [v for v in vals_all if v is not None]
            row: dict[str, Any] = {
                "condition": cond,
                "controller": c,
                "a_wz_mean_m_s2": float(np.mean(vals)) if vals else None,
                "contacts": sum(v is None for v in vals_all),
            }
            if c != reference:
                row["vs_reference"] = compare(vals_all, ref)
            rows.append(row)
    return rows


def comfort_compare(
    spec: ComfortSpec,
    command: str | None = None,
    log: Callable[[str], None] | None = None,
    workers: int = 1,
) -> dict[str, Any]:
    """Fly the comparison (module docstring) on ``workers`` processes (the same values
    whatever the number); the document ``comfort.json`` holds. ``log`` gets one line per
    condition."""
    seeds = list(spec.seeds)
    per, elapsed = ride_table(
        spec.conditions, spec.names, seeds, spec.distance_km, workers=workers, log=log
    )
    return {
        "command": command or "agents.evaluation.comparisons.comfort.run(...)",
        "reference": spec.reference,
        "seeds": [seeds[0], seeds[-1]],
        "distance_km": spec.distance_km,
        "settle_s": SETTLE_S,
        "wall_s": elapsed,
        "rows": comfort_table(per, spec.reference),
        "a_wz_per_seed": per,
    }


def comfort_markdown(doc: dict[str, Any]) -> str:
    """``comfort.md``: the table of a :func:`comfort_compare` document."""
    ref = doc["reference"]
    first, last = doc["seeds"]
    n = len(next(iter(doc["a_wz_per_seed"].values()))[ref])
    md = [
        f"W_k-weighted RMS heave acceleration a_wz [m/s²], mean over {n} seeds "
        f"({first}–{last}) × {doc['distance_km']:g} km, and the paired ratio to "
        f"`{ref}` (lower is smoother; runs that touched are left out of both "
        "sides: `comfort.json` counts them):",
        "",
        f"| condition | controller | a_wz [m/s²] | / `{ref}` (paired) [95 %] | verdict |",
        "|---|---|---:|---|---|",
    ]
    for r in doc["rows"]:
        v = r.get("vs_reference")
        cmp = f"{v['ratio']:.3f} [{v['lo']:.3f}, {v['hi']:.3f}]" if v else "—"
        mean = f"{r['a_wz_mean_m_s2']:.4f}" if r["a_wz_mean_m_s2"] is not None else "n/a"
        verdict = (
            {"A above B": "rougher", "B above A": "smoother"}.get(v["verdict"], v["verdict"])
            if v
            else ""
        )
        md.append(f"| {r['condition']} | {r['controller']} | {mean} | {cmp} | {verdict} |")
    return "\n".join(md) + "\n"


def run(
    spec: ComfortSpec,
    out_dir: str | Path,
    *,
    overwrite: bool = False,
    command: str | None = None,
    log: Callable[[str], None] | None = None,
    workers: int = 1,
) -> dict[str, Any]:
    """The comparison into ``out_dir`` (``comfort.json``, ``comfort.md``; refused with
    ``FileExistsError`` before any run if they exist, unless ``overwrite``; held for the
    run: :func:`~agents.evaluation.outputs.output_lock`) on ``workers`` processes; returns
    the document."""
    from agents.evaluation.backends import check_backend

    check_backend("local", workers)
    out = Path(out_dir)
    files = [out / name for name in FILES]
    with output_lock(out, "comfort comparison output directory"):
        if any(f.exists() for f in files) and not overwrite:
            raise FileExistsError(f"{out} holds a comfort comparison (pass --overwrite)")
        doc = comfort_compare(spec, command, log, workers)
        atomic_write_text(files[0], json.dumps(doc, indent=1) + "\n")
        atomic_write_text(files[1], comfort_markdown(doc))
    return doc
