"""The decisive benchmark: per-seed capacities of every entrant on common seeds, paired
verdicts — ``python -m agents.capacity``.

For each paper condition, each family of :data:`HEADLINE_FAMILIES` whose realisation
scales with the severity (the disturbance's
:attr:`~hyperloop_env.disturbances.base.Disturbance.scales_with_severity`) and each
entrant, the capacity of every evaluation seed is searched by incremental dynamic analysis
(:mod:`agents.evaluation.capacity`). All entrants fly the **same seeds** (common random
numbers), so the comparison of two entrants is paired: per seed the ratio of their
capacities. From the capacities (:mod:`agents.evaluation.capacity_stats`):

* the **fragility** of each entrant: the empirical distribution of its capacities (with a
  DKW band) and the lognormal fit (median θ, dispersion β, right-censoring by maximum
  likelihood, bootstrap intervals); the binary-outcome MLE at the suite's grid levels on the
  same seeds as a cross-check;
* the **verdict matrix**: for each pair, the ratio of median capacities (geometric mean of
  the per-seed ratios) with a paired bootstrap 95 % interval, the Wilcoxon signed-rank
  p-value and a verdict — "A above B", "B above A", "equivalent" (interval inside ±5 %) or
  "undecided";
* **P(contact | s)** at the suite's levels from the capacity distribution (the fraction of
  seeds whose capacity is at most s, and the lognormal fit's value): the paper's contact
  probability seen from the capacities.

Search settings per family (:func:`family_searches`): start at the suite's ``mid`` level,
hunt by ×1.5, fill to a bracket ratio of 1.02, lower bound = the suite grid's smallest
level / 4, upper bound = its largest × 4 (right-censored above), check grid = the suite's
grid (at most 2 levels above the capacity).

Seeds: the evaluation range from :data:`~agents.evaluation.benchmark.EVAL_SEED0` by default
(``--seed0`` / ``--seed-list``); a learned agent is refused on seeds inside its training range
(:data:`~agents.evaluation.benchmark.TRAIN_SEED_LIMIT`) unless
``--allow-training-seeds``. An entrant whose registry entry sets ``entrant_seeds = N``
(``mpc``: 16, its QPs cost several physics steps per step) flies the first N of the seeds
only (``--entrant-seeds LABEL=N`` sets or overrides it); its pairs are paired on those N
seeds, and ``settings.entrant_seeds`` of ``headline.json`` records it.
"""

from __future__ import annotations

import contextlib
import json
import math
import shutil
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from agents.evaluation import capacity_stats as cs
from agents.evaluation import seeds as seeding
from agents.evaluation.benchmark import (
    DEFAULT_ENTRANTS,
    EVAL_SEED0,
    HEADLINE_FAMILIES,
    entrant_actuators,
    entrant_label,
    load_suite,
)
from agents.evaluation.capacity import (
    DEFAULT_CHECK_ABOVE,
    DEFAULT_RATIO,
    DEFAULT_ROWS,
    DEFAULT_STEP,
    CapacityTask,
    FamilySearch,
    contact_kinds,
    run_task,
)
from agents.evaluation.capacity_report import (  # the report's renderers, re-exported
    TARGET_DECIDED as TARGET_DECIDED,
)
from agents.evaluation.capacity_report import capacity_table as capacity_table
from agents.evaluation.capacity_report import compact_verdicts as compact_verdicts
from agents.evaluation.capacity_report import cost_table as cost_table
from agents.evaluation.capacity_report import csv_text, markdown
from agents.evaluation.capacity_report import readme_block as readme_block
from agents.evaluation.capacity_report import verdict_table as verdict_table
from agents.evaluation.figures import plot_capacities
from agents.evaluation.published import fingerprint
from hyperloop_env.disturbances import DISTURBANCES
from hyperloop_env.json_values import json_value
from hyperloop_env.threads import one_blas_thread

DEFAULT_SEEDS = 32
DEFAULT_DISTANCE_KM = 3.0
BOUND_FACTOR = 4.0
"""Search bounds: the suite grid's smallest level / 4 and its largest × 4."""
OWNED = ("headline.md", "headline.json", "headline.csv", "capacities.json", "figures")
"""The report files a run writes into its output directory (``--overwrite`` removes them)."""


def family_searches(
    suite: dict[str, Any],
    families: Sequence[str],
    *,
    ratio: float = DEFAULT_RATIO,
    step: float = DEFAULT_STEP,
    check_above: int = DEFAULT_CHECK_ABOVE,
) -> dict[str, FamilySearch]:
    """The search of each family from the suite (module docstring)."""
    out = {}
    for fam in families:
        if fam not in suite["families"]:
            raise ValueError(f"families: {fam!r} is not in the suite ({sorted(suite['families'])})")
        if not (cls := DISTURBANCES[fam]).scales_with_severity:
            raise ValueError(
                f"families: {fam!r} does not scale with the severity ({cls.scaling_note}); "
                "it keeps the grid design (python -m agents.benchmark)"
            )
        spec = suite["families"][fam]
        grid = sorted(map(float, spec["grid"]))
        out[fam] = FamilySearch(
            family=fam,
            start=float(spec["levels"][len(spec["levels"]) // 2]),
            lower=grid[0] / BOUND_FACTOR,
            upper=grid[-1] * BOUND_FACTOR,
            step=step,
            ratio=ratio,
            check=tuple(grid),
            check_above=check_above,
            levels=tuple(sorted(float(v) for v in spec["levels"])),
            fixed=tuple(sorted((k, float(v)) for k, v in (spec.get("fixed") or {}).items())),
        )
    return out


def reduced_seeds(
    entrants: Sequence[str], n_seeds: int, given: dict[str, int] | None = None
) -> dict[str, int]:
    """{label: N} of the entrants that fly the first N of the ``n_seeds`` seeds only:
    ``given`` (labels of ``entrants``, N an int >= 2) or, if None, the registry entries'
    ``entrant_seeds``; an N at or above ``n_seeds`` is dropped (the entrant flies them all)."""
    from agents.controllers.registry import controller_spec

    labels = {entrant_label(*entrant_actuators(e)): e for e in entrants}
    if given is None:
        given = {}
        for lab, e in labels.items():
            spec = controller_spec(entrant_actuators(e)[0])
            if spec is not None and spec.entrant_seeds is not None:
                given[lab] = spec.entrant_seeds
    out = {}
    for lab, k in given.items():
        if lab not in labels:
            raise ValueError(f"entrant_seeds: {lab!r} is not an entrant ({sorted(labels)})")
        if isinstance(k, bool) or not isinstance(k, int | np.integer) or k < 2:
            raise ValueError(f"entrant_seeds[{lab!r}] must be an int >= 2, got {k!r}")
        if k < n_seeds:
            out[lab] = int(k)
    return out


def plan(
    entrants: Sequence[str],
    conditions: Sequence[str],
    families: Sequence[str],
    seeds: Sequence[int],
    distance_km: float,
    suite: dict[str, Any],
    *,
    rows: int = DEFAULT_ROWS,
    magnet: str | None = None,
    ratio: float = DEFAULT_RATIO,
    step: float = DEFAULT_STEP,
    check_above: int = DEFAULT_CHECK_ABOVE,
    entrant_seeds: dict[str, int] | None = None,
) -> tuple[list[CapacityTask], list[str]]:
    """One task per entrant × condition (all families; the seeds, or the first
    ``entrant_seeds[label]`` of them); returns (tasks, labels)."""
    from agents.evaluation.rollout import episode_config

    parsed = [entrant_actuators(e) for e in entrants]
    labels = [entrant_label(b, a) for b, a in parsed]
    if len(set(labels)) != len(labels):
        raise ValueError(f"entrants repeat: {labels}")
    fs = family_searches(suite, families, ratio=ratio, step=step, check_above=check_above)
    tasks = []
    for (base, act), lab in zip(parsed, labels, strict=True):
        for cond in conditions:
            cfg = episode_config(cond, distance_km, magnet, {"actuators": act})
            tasks.append(
                CapacityTask(
                    controller=base,
                    config=cfg,
                    families=tuple(fs[f] for f in families),
                    seeds=tuple(int(s) for s in seeds[: (entrant_seeds or {}).get(lab)]),
                    rows=rows,
                    key=(lab, cond),
                )
            )
    return tasks, labels


def collect(records: Sequence[dict[str, Any]]) -> tuple[dict[str, Any], dict[str, Any]]:
    """(capacities[condition][family][entrant] = per-seed results (every run kept),
    sts[condition][family][entrant] = the paper's STS at the family's start level and at
    each of the suite's levels), from the tasks' records
    (:func:`agents.evaluation.capacity_store.task_record`)."""
    out: dict[str, Any] = {}
    sts: dict[str, Any] = {}
    for r in records:
        lab, cond = r["key"]
        for s in r["searches"]:
            cell = out.setdefault(cond, {}).setdefault(s["family"], {}).setdefault(lab, [])
            cell.append(s)
        for fam, st in r["sts"].items():
            sts.setdefault(cond, {}).setdefault(fam, {})[lab] = st
    return out, sts


def analyse(
    caps: dict[str, Any],
    labels: Sequence[str],
    suite: dict[str, Any],
    *,
    n_boot: int = 1000,
    seed: int = 0,
    sts: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Fragility per entrant and the verdict matrix per condition and family."""
    out: dict[str, Any] = {}
    for cond, fams in caps.items():
        for fam, ents in fams.items():
            levels = [float(x) for x in suite["families"][fam]["levels"]]
            grid = [float(x) for x in suite["families"][fam]["grid"]]
            cell: dict[str, Any] = {"entrants": {}, "levels": levels}
            arrays = {}  # (capacities, censored, seeds): pairs on their common seeds
            for lab in labels:
                st = (sts or {}).get(cond, {}).get(fam, {}).get(lab)
                rows = sorted(ents[lab], key=lambda d: d["seed"])
                c = np.array([d["capacity"] for d in rows])
                cens = np.array([d["censored"] == "right" for d in rows])
                arrays[lab] = (c, cens, [d["seed"] for d in rows])
                fit = cs.fit_capacity_lognormal(c, cens, n_boot=n_boot, seed=seed)
                ecdf = cs.empirical_cdf(c, cens)
                th, be = fit.get("theta"), fit.get("beta")
                cell["entrants"][lab] = {
                    "seeds": [d["seed"] for d in rows],
                    "capacity": c.tolist(),
                    "censored": cens.tolist(),
                    "left_censored": int(sum(d["censored"] == "left" for d in rows)),
                    "non_monotone": int(sum(d["non_monotone"] for d in rows)),
                    "runs": int(sum(len(d["runs"]) for d in rows)),
                    "fit": fit,
                    "ecdf": ecdf,
                    "binary_fit": cs.binary_outcome_fit(c, cens, grid),
                    "contact_at_capacity": contact_kinds(rows),
                    "sts_at_start": (st or {}).get("start"),
                    "sts_at_levels": (st or {}).get("levels"),
                    "p_contact": [
                        {
                            "severity": s,
                            "empirical": float(cs.p_contact_empirical(s, c, cens)),
                            "lognormal": (
                                None if th is None or not be else float(cs.p_contact(s, th, be))
                            ),
                        }
                        for s in levels
                    ],
                }
            cell["verdicts"] = cs.verdict_matrix(arrays, n_boot=max(n_boot, 2000), seed=seed)
            cell["decided_fraction"] = cs.decided_fraction(cell["verdicts"])
            out.setdefault(cond, {})[fam] = cell
    return out


def run(
    entrants: Sequence[str] = DEFAULT_ENTRANTS,
    conditions: Sequence[str] = ("paper",),
    families: Sequence[str] = HEADLINE_FAMILIES,
    seeds: Sequence[int] | None = None,
    distance_km: float = DEFAULT_DISTANCE_KM,
    *,
    workers: int = 1,
    backend: str = "local",
    address: str | None = None,
    rows: int = DEFAULT_ROWS,
    ratio: float = DEFAULT_RATIO,
    step: float = DEFAULT_STEP,
    check_above: int = DEFAULT_CHECK_ABOVE,
    n_boot: int = 1000,
    suite: str | Path | dict[str, Any] | None = None,
    out_dir: str | Path | None = None,
    overwrite: bool = False,
    resume: bool = False,
    allow_training_seeds: bool = False,
    progress: bool = True,
    figures: bool = True,
    command: str | None = None,
    entrant_seeds: dict[str, int] | None = None,
) -> dict[str, Any]:
    """Search, analyse and (with ``out_dir``) write the headline (module docstring);
    ``entrant_seeds``: {label: N} entrants flown on the first N seeds only (None: the
    registry's ``entrant_seeds``, :func:`reduced_seeds`).

    Every value is checked before ``out_dir`` is created. ``out_dir`` is held for the run
    (:func:`agents.evaluation.outputs.output_lock`); each task's results are kept in it as
    the task finishes and the report is published whole at the end
    (:mod:`agents.evaluation.capacity_store`). ``resume``: continue an interrupted run in
    ``out_dir`` — its finished tasks are read back, the others flown; the result is the
    one an uninterrupted run gives. Results never depend on ``workers`` or ``backend``."""
    from hyperloop_env.scenarios import expand_scenarios

    s = suite if isinstance(suite, dict) else load_suite(suite)
    conds = expand_scenarios(list(conditions))
    seed_list = _checked_seeds(
        entrants,
        seeds,
        distance_km,
        allow_training_seeds=allow_training_seeds,
        backend=backend,
        workers=workers,
        address=address,
    )
    if resume and (out_dir is None or overwrite):
        raise ValueError("resume needs an output directory and excludes overwrite")
    reduced = reduced_seeds(entrants, len(seed_list), entrant_seeds)
    tasks, labels = plan(
        entrants,
        conds,
        families,
        seed_list,
        distance_km,
        s,
        rows=rows,
        ratio=ratio,
        step=step,
        check_above=check_above,
        entrant_seeds=reduced,
    )
    with one_blas_thread(), contextlib.ExitStack() as held:
        out, earlier = _open_out(held, out_dir, tasks, overwrite, resume)
        t0 = time.perf_counter()
        records = _fly(tasks, out, earlier, workers, backend, address, progress)
        wall = time.perf_counter() - t0 + earlier
        caps, sts = collect(records)
        if progress:
            print("analysing (bootstrap intervals, verdicts)…", file=sys.stderr)
        analysis = analyse(caps, labels, s, n_boot=n_boot, sts=sts)
        settings = _run_settings(
            labels,
            conds,
            families,
            seed_list,
            reduced,
            distance_km,
            s,
            records,
            rows=rows,
            ratio=ratio,
            step=step,
            check_above=check_above,
            n_boot=n_boot,
            wall=wall,
            workers=workers,
            backend=backend,
            command=command,
        )
        settings["fingerprint"] = fingerprint(settings)  # what makes another run comparable
        doc = {"settings": settings, "headline": summary(analysis, labels)}
        result = {**doc, "analysis": analysis, "capacities": caps}
        if out is not None:
            _write_report(out, doc, analysis, caps, labels, figures, progress)
    return result


def _checked_seeds(
    entrants: Sequence[str],
    seeds: Sequence[int] | None,
    distance_km: float,
    *,
    allow_training_seeds: bool,
    backend: str,
    workers: int,
    address: str | None,
) -> list[int]:
    """The run's seeds (default: :data:`DEFAULT_SEEDS` from the evaluation range), with the
    distance, the entrants' seed policy and the backend checked (ValueError naming them)."""
    from agents.evaluation.backends import check_backend

    seed_list = seeding.seed_list(
        DEFAULT_SEEDS if seeds is None else None,
        EVAL_SEED0,
        None if seeds is None else list(seeds),
        min_n=2,
        names=seeding.API_NAMES,
    )
    if not (
        isinstance(distance_km, int | float) and math.isfinite(distance_km) and distance_km > 0
    ):
        raise ValueError(f"distance_km must be a positive number, got {distance_km!r}")
    seeding.check_evaluation_seeds(
        [entrant_actuators(e)[0] for e in entrants],
        seed_list,
        allow_training_seeds,
        names=seeding.API_NAMES,
    )
    check_backend(backend, workers, address)
    return seed_list


def _run_settings(
    labels: list[str],
    conds: list[str],
    families: Sequence[str],
    seed_list: list[int],
    reduced: dict[str, int],
    distance_km: float,
    s: dict[str, Any],
    records: list[dict[str, Any]],
    *,
    rows: int,
    ratio: float,
    step: float,
    check_above: int,
    n_boot: int,
    wall: float,
    workers: int,
    backend: str,
    command: str | None,
) -> dict[str, Any]:
    """The run's settings record (headline.json's ``settings``, before its fingerprint)."""
    return {
        "entrants": labels,
        "conditions": conds,
        "families": list(families),
        "seeds": len(seed_list),
        "seed_range": [min(seed_list), max(seed_list)],
        "seed_list": list(seed_list),
        "entrant_seeds": reduced,
        "distance_km": float(distance_km),
        "ratio": ratio,
        "step": step,
        "check_above": check_above,
        "rows": rows,
        "n_boot": n_boot,
        "searches": {
            f: _search_dict(fs)
            for f, fs in family_searches(
                s, families, ratio=ratio, step=step, check_above=check_above
            ).items()
        },
        "wall_s": wall,
        "workers": workers,
        "backend": backend,
        "steps": int(sum(r["steps"] for r in records)),
        "run_steps": int(sum(r["run_steps"] for r in records)),
        "tasks": [_task_row(r, len(families)) for r in records],
        "command": command or "agents.evaluation.capacity_benchmark.run(...)",
    }


def _open_out(
    held: contextlib.ExitStack,
    out_dir: str | Path | None,
    tasks: Sequence[CapacityTask],
    overwrite: bool,
    resume: bool,
) -> tuple[Path | None, float]:
    """Lock and check the output directory and record the run in it (``run.json``);
    (the directory, the wall time [s] of the run's earlier attempts)."""
    if out_dir is None:
        return None, 0.0
    from agents.evaluation import capacity_store as store
    from agents.evaluation.outputs import output_lock, partial_dirs, prepare_output_dir

    held.enter_context(output_lock(out_dir, "capacity output directory"))
    if resume:
        out = Path(out_dir)
    else:
        out = prepare_output_dir(
            out_dir,
            overwrite=overwrite,
            owned=(*OWNED, store.RUN_FILE, store.TASKS_DIR),
            flag="--resume to continue it (its finished tasks are kept), or --overwrite to "
            "delete it and start again",
        )
    for q in [*partial_dirs(out), *partial_dirs(out / store.TASKS_DIR)]:
        shutil.rmtree(q, ignore_errors=True)  # leftovers of a killed run (we hold the lock)
    return out, store.open_run(out, [store.task_spec(t) for t in tasks], resume)


def _fly(
    tasks: Sequence[CapacityTask],
    out: Path | None,
    earlier: float,
    workers: int,
    backend: str,
    address: str | None,
    progress: bool,
) -> list[dict[str, Any]]:
    """Every task's record, in plan order: read back from ``out`` where an earlier attempt
    (``earlier`` seconds of wall time) finished it, else flown and saved as it finishes."""
    from agents.evaluation import capacity_store as store
    from agents.evaluation.backends import run_blocks

    specs = [store.task_spec(t) for t in tasks]
    records: list[dict[str, Any] | None] = [None] * len(tasks)
    if out is not None:
        for i, rec in store.finished_tasks(out, specs).items():
            records[i] = rec
    todo = [i for i, r in enumerate(records) if r is None]
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(
            total=len(tasks),
            initial=len(tasks) - len(todo),
            desc="capacity searches (entrant × condition)",
            unit="task",
            file=sys.stderr,
        )
    t0 = time.perf_counter()
    todo_tasks = [tasks[i] for i in todo]
    for j, res in run_blocks(
        todo_tasks, backend=backend, workers=workers, address=address, fn=run_task
    ):
        i = todo[j]
        rec = store.task_record(res)
        if out is not None:
            store.save_task(out, i, specs[i], rec)
            store.write_run(out, specs, earlier + time.perf_counter() - t0)
        records[i] = rec
        if bar is not None:
            bar.update(1)
            bar.set_postfix_str(f"{res.key[0]} {res.key[1]} {res.wall_s:.0f} s")
    if bar is not None:
        bar.close()
    return [r for r in records if r is not None]


def _task_row(r: dict[str, Any], n_families: int) -> dict[str, Any]:
    return {
        "entrant": r["key"][0],
        "condition": r["key"][1],
        "seeds": len(r["searches"]) // max(1, n_families),
        "wall_s": r["wall_s"],
        "sts_s": r["sts_s"],
        "steps": r["steps"],
        "run_steps": r["run_steps"],
    }


REPORT_FILES = ("capacities.json", "figures", "headline.csv", "headline.md", "headline.json")
"""The report's files in the order they are published (headline.json, read first, last)."""


def _write_report(
    out: Path,
    doc: dict[str, Any],
    analysis: dict[str, Any],
    caps: dict[str, Any],
    labels: Sequence[str],
    figures: bool,
    progress: bool,
) -> None:
    """The report, staged and published whole (:func:`outputs.publish_report`)."""
    from agents.evaluation.outputs import publish_report

    with publish_report(out, REPORT_FILES) as stage:
        (stage / "capacities.json").write_text(
            json.dumps(json_value({"settings": doc["settings"], "capacities": caps})) + "\n"
        )
        (stage / "headline.json").write_text(
            json.dumps(json_value({**doc, "analysis": _slim(analysis)}), indent=1) + "\n"
        )
        (stage / "headline.md").write_text(markdown(doc, analysis))
        (stage / "headline.csv").write_text(csv_text(doc))
        (stage / "figures").mkdir()
        if figures:
            if progress:
                print("figures…", file=sys.stderr)
            plot_capacities(analysis, labels, stage / "figures")


def _search_dict(fs: FamilySearch) -> dict[str, Any]:
    return {
        "start": fs.start,
        "lower": fs.lower,
        "upper": fs.upper,
        "step": fs.step,
        "ratio": fs.ratio,
        "check": list(fs.check),
        "check_above": fs.check_above,
        "fixed": dict(fs.fixed),
        "levels": list(fs.levels),
    }


def _slim(analysis: dict[str, Any]) -> dict[str, Any]:
    """The analysis without the ECDF arrays (they are in capacities.json's data)."""
    out: dict[str, Any] = {}
    for cond, fams in analysis.items():
        for fam, cell in fams.items():
            ents = {
                lab: {k: v for k, v in e.items() if k != "ecdf"}
                for lab, e in cell["entrants"].items()
            }
            out.setdefault(cond, {})[fam] = {**cell, "entrants": ents}
    return out


def summary(analysis: dict[str, Any], labels: Sequence[str]) -> dict[str, Any]:
    """The headline numbers: per condition, family and entrant the median capacity (fit
    and empirical) with intervals; per condition and family the verdicts."""
    rows = []
    verdicts = []
    n_pairs = n_decided = 0
    for cond, fams in analysis.items():
        for fam, cell in fams.items():
            for lab in labels:
                e = cell["entrants"][lab]
                f = e["fit"]
                rows.append(
                    {
                        "condition": cond,
                        "family": fam,
                        "entrant": lab,
                        "theta": f.get("theta"),
                        "theta_ci": f.get("theta_ci"),
                        "beta": f.get("beta"),
                        "beta_ci": f.get("beta_ci"),
                        "median_empirical": f.get("median_empirical"),
                        "median_empirical_ci": f.get("median_empirical_ci"),
                        "status": f.get("status"),
                        "n": len(e["capacity"]),
                        "n_censored": int(sum(e["censored"])),
                        "left_censored": e["left_censored"],
                        "non_monotone": e["non_monotone"],
                        "binary_theta": e["binary_fit"].get("theta"),
                        "p_contact": e["p_contact"],
                        "sts_at_start": _sts_short(e.get("sts_at_start")),
                        "sts_at_levels": [_sts_short(x) for x in e.get("sts_at_levels") or []],
                    }
                )
            for v in cell["verdicts"]:
                verdicts.append(
                    {
                        "condition": cond,
                        "family": fam,
                        **{
                            k: v[k]
                            for k in (
                                *("a", "b", "verdict", "ratio", "lo", "hi", "p_value"),
                                *("n", "reason"),
                            )
                        },
                    }
                )
                n_pairs += 1
                n_decided += v["verdict"] != "undecided"
    return {
        "capacities": rows,
        "verdicts": verdicts,
        "pairs": n_pairs,
        "decided": n_decided,
        "decided_fraction": (n_decided / n_pairs) if n_pairs else None,
    }


def _sts_short(st: dict[str, Any] | None) -> dict[str, Any] | None:
    if not st:
        return None
    return {
        "severity": st["severity"],
        "n_runs": st["n_runs"],
        "n_contacts": st["n_contacts"],
        "p_unsteady": st["gap"]["p_unsteady"],
        "p_unsteady_ci": st["gap"]["p_unsteady_ci"],
        "p_unsteady_guidance": st["guidance"]["p_unsteady"],
        "p_unsteady_guidance_ci": st["guidance"]["p_unsteady_ci"],
    }
