"""The benchmark suite and the headline: ``python -m agents.benchmark``.

The **benchmark suite** (``agents/evaluation/benchmark_suite.json``, written once by
``hyperloop calibrate`` from the passive and PID baselines — never from a learned
agent) names, per disturbance family,

* ``levels``: a few severities (``low``, ``mid``, ``high``) at which the baselines sit in
  the measurable band (contact probability per 10 km between 0.05 and 0.95, or
  P(unsteady) between 1e-4 and 0.5) — the levels at which the paper's P(unsteady) is
  reported;
* ``grid``: the finer severity grid over which the fragility function (median capacity θ)
  is fitted;
* ``fixed``: disturbances held fixed while the family is swept (a coil fault or a sensor
  dropout is felt only on a rough guideway).

**Seeds** are disjoint by purpose (:data:`SEED_RANGES`): training below
:data:`TRAIN_SEED_LIMIT`, the benchmark's evaluation from :data:`EVAL_SEED0`, the Ray Tune
validation from :data:`VALIDATION_SEED0`, the suite's calibration from
:data:`CALIBRATION_SEED0` (defined in :mod:`agents.evaluation.seeds`). The benchmark runs
``--seeds`` seeds from ``--seed0`` (default :data:`EVAL_SEED0`) or the explicit
``--seed-list``; a learned entrant on training seeds is refused unless
``--allow-training-seeds``.

**Entrants** are controller names of :func:`agents.make_controller`; ``name+g`` runs the
controller with ``actuators="levitation+guidance"`` (its guidance loops active). A learned
agent runs with the actuator set it was trained with (``ppo-guidance``: levitation and
guidance). Each family × actuator set is one fragility sweep
(:func:`agents.evaluation.fragility.fragility`, which writes its own report, figures, JSON
and CSV under ``<out>/<family>/<actuators>/``); the **headline** (``headline.md``, ``.json``,
``.csv``) collects, per paper condition and entrant: the median capacity θ with its
interval on each family, the P(unsteady) of the levitation and guidance gaps with their
intervals at the suite's roughness levels, the contact rate per 100 km and the ISO 2631-1
comfort at the reference level (the roughness suite's ``mid`` level).

A capacity interval is the fit's bootstrap percentile interval; when the data have no
finite maximum-likelihood estimate (a sharp threshold between two grid levels) it is the
**bracket** of grid levels that contains θ, marked "bracket". Two entrants' capacities are
**resolved** when their intervals do not overlap.
"""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agents.controllers.registry import GUIDED, LEVITATION
from agents.evaluation import seeds as seeding

# the benchmark's pieces, each in its module, named here too (this module is the study's face)
from agents.evaluation.benchmark_blocks import LEVEL_FIELDS as LEVEL_FIELDS
from agents.evaluation.benchmark_blocks import _finished_block
from agents.evaluation.benchmark_blocks import block_problem as block_problem
from agents.evaluation.benchmark_blocks import settings_seeds as settings_seeds
from agents.evaluation.benchmark_merge import merge_runs as merge_runs
from agents.evaluation.benchmark_report import capacity_estimate as capacity_estimate
from agents.evaluation.benchmark_report import capacity_interval as capacity_interval
from agents.evaluation.benchmark_report import headline as headline
from agents.evaluation.benchmark_report import headline_csv as headline_csv
from agents.evaluation.benchmark_report import headline_markdown as headline_markdown
from agents.evaluation.benchmark_report import readme_table as readme_table
from agents.evaluation.benchmark_report import resolved as resolved
from agents.evaluation.benchmark_report import target_lines as target_lines
from agents.evaluation.benchmark_suite import HEADLINE_FAMILIES as HEADLINE_FAMILIES
from agents.evaluation.benchmark_suite import REFERENCE_FAMILY as REFERENCE_FAMILY
from agents.evaluation.benchmark_suite import SUITE_FILE as SUITE_FILE
from agents.evaluation.benchmark_suite import load_suite as load_suite
from agents.evaluation.benchmark_suite import suite_markdown as suite_markdown
from agents.evaluation.entrants import DEFAULT_ENTRANTS as DEFAULT_ENTRANTS
from agents.evaluation.entrants import default_entrants as default_entrants
from agents.evaluation.entrants import entrant_actuators as entrant_actuators
from agents.evaluation.entrants import entrant_label as entrant_label
from agents.evaluation.entrants import learned_actuators as learned_actuators

# the seed ranges are defined in agents.evaluation.seeds and named here too
from agents.evaluation.seeds import CALIBRATION_SEED0 as CALIBRATION_SEED0
from agents.evaluation.seeds import EVAL_SEED0 as EVAL_SEED0
from agents.evaluation.seeds import SEED_RANGES as SEED_RANGES
from agents.evaluation.seeds import TRAIN_SEED_LIMIT as TRAIN_SEED_LIMIT
from agents.evaluation.seeds import VALIDATION_SEED0 as VALIDATION_SEED0
from hyperloop_env.json_values import json_value

DEFAULT_SEEDS = 8
DEFAULT_DISTANCE_KM = 3.0


# --------------------------------------------------------------------------------------
# the suite
# --------------------------------------------------------------------------------------


# --------------------------------------------------------------------------------------
# entrants
# --------------------------------------------------------------------------------------


# --------------------------------------------------------------------------------------
# capacities and the headline
# --------------------------------------------------------------------------------------


# --------------------------------------------------------------------------------------
# the run
# --------------------------------------------------------------------------------------


def run_benchmark(
    entrants: Sequence[str] = DEFAULT_ENTRANTS,
    conditions: Sequence[str] = ("paper",),
    families: Sequence[str] | None = None,
    seeds: int | Sequence[int] = DEFAULT_SEEDS,
    distance_km: float = DEFAULT_DISTANCE_KM,
    *,
    seed0: int = EVAL_SEED0,
    allow_training_seeds: bool = False,
    suite: str | Path | dict[str, Any] | None = None,
    workers: int = 1,
    backend: str = "local",
    address: str | None = None,
    out_dir: str | Path | None = None,
    overwrite: bool = False,
    resume: bool = False,
    figures: bool = True,
    progress: bool = True,
    n_boot: int = 200,
    n_boot_fragility: int = 1000,
    command: str | None = None,
) -> dict[str, Any]:
    """Run the suite for ``entrants`` and collect the headline (module docstring).

    ``seeds``: a number of runs per level (seeds ``seed0``, ``seed0 + 1``, …; ``seed0``
    defaults to the evaluation range, :data:`EVAL_SEED0`) or an explicit list (at least two
    either way). A learned entrant on seeds of the training range is refused unless
    ``allow_training_seeds`` (:func:`agents.evaluation.seeds.check_evaluation_seeds`).

    ``resume``: continue an interrupted run in ``out_dir``: a family × actuator block whose
    ``results.json`` is there, complete, and was run with the same entrants, conditions,
    levels, seeds, distance, fixed disturbances, actuators and bootstrap sizes is read
    instead of rerun (the results are deterministic in the seeds, so this equals a fresh
    run); a block whose ``results.json`` is missing, unreadable or incomplete is unfinished
    and runs again (a line on stderr names the file and what is wrong); a complete block run
    with other settings is refused before anything runs.

    Every value is checked before anything is created; ``out_dir`` is held for the run
    (:func:`agents.evaluation.outputs.output_lock`); a block's files are written into a
    temporary directory that replaces ``<out>/<family>/<actuators>`` when it is complete,
    so an interrupt (Ctrl-C, SIGTERM) never leaves a half-written block. The headline's
    ``wall_s`` is this run's wall time plus that of the blocks read from a previous one."""
    # ---- every value is checked before anything is created -------------------------------
    s = suite if isinstance(suite, dict) else load_suite(suite)
    fams = _checked_families(s, families)
    seed_list = seeding.resolve(seeds, seed0, min_n=2)
    from hyperloop_env.scenarios import expand_scenarios

    conds = expand_scenarios(list(conditions))
    parsed = [entrant_actuators(e) for e in entrants]
    labels = [entrant_label(b, a) for b, a in parsed]
    if len(set(labels)) != len(labels):
        raise ValueError(f"entrants repeat: {labels}")
    seeding.check_evaluation_seeds(
        [b for b, _ in parsed], seed_list, allow_training_seeds, names=seeding.API_NAMES
    )
    if resume and (out_dir is None or overwrite):
        raise ValueError("resume needs an output directory and excludes overwrite")
    blocks = _plan_blocks(
        s,
        fams,
        parsed,
        labels,
        conds,
        seed_list,
        distance_km,
        allow_training_seeds=allow_training_seeds,
        n_boot=n_boot,
        n_boot_fragility=n_boot_fragility,
    )
    with contextlib.ExitStack() as held:
        out = _open_output(held, out_dir, fams, resume=resume, overwrite=overwrite)
        return _run_blocks(
            out,
            blocks,
            s,
            fams,
            conds,
            labels,
            seed_list,
            distance_km,
            resume=resume,
            allow_training_seeds=allow_training_seeds,
            backend=backend,
            workers=workers,
            address=address,
            figures=figures,
            progress=progress,
            n_boot=n_boot,
            n_boot_fragility=n_boot_fragility,
            command=command,
        )


def _checked_families(s: dict[str, Any], families: Sequence[str] | None) -> list[str]:
    """The families to run (default: the suite's): in the suite, distinct, and with the
    reference family among them."""
    fams = list(families) if families else list(s["families"])
    for f in fams:
        if f not in s["families"]:
            raise ValueError(f"--families: {f!r} is not in the suite ({sorted(s['families'])})")
    if len(set(fams)) != len(fams):
        raise ValueError(f"--families repeat: {fams}")
    if REFERENCE_FAMILY not in fams:
        raise ValueError(
            f"--families must include {REFERENCE_FAMILY!r} (the headline's reference family)"
        )
    return fams


def _plan_blocks(
    s: dict[str, Any],
    fams: list[str],
    parsed: list[tuple[str, str]],
    labels: list[str],
    conds: list[str],
    seed_list: list[int],
    distance_km: float,
    *,
    allow_training_seeds: bool,
    n_boot: int,
    n_boot_fragility: int,
) -> list[_Block]:
    """One block per family × actuator set that has entrants, each checked as its fragility
    sweep will be run."""
    from agents.evaluation.fragility import DEFAULT_BLOCK_SIZE, DEFAULT_MAX_SAMPLES, check_args

    blocks: list[_Block] = []
    for fam in fams:
        spec = s["families"][fam]
        levels = sorted({*map(float, spec["grid"]), *map(float, spec["levels"])})
        for act in (LEVITATION, GUIDED):
            group = [(b, lab) for (b, a), lab in zip(parsed, labels, strict=True) if a == act]
            if not group:
                continue
            ctrls = [b for b, _ in group]
            check_args(
                ctrls,
                conds,
                fam,
                levels,
                seed_list,
                distance_km,
                "repelling",
                1.0,
                DEFAULT_BLOCK_SIZE,
                DEFAULT_MAX_SAMPLES,
                "exact",
                allow_training_seeds=allow_training_seeds,
                n_boot=n_boot,
                n_boot_fragility=n_boot_fragility,
                fixed=spec["fixed"] or None,
                env_kwargs={"actuators": act},
            )
            blocks.append(_Block(fam, act, group, levels, dict(spec["fixed"])))
    return blocks


def _open_output(
    held: contextlib.ExitStack,
    out_dir: str | Path | None,
    fams: list[str],
    *,
    resume: bool,
    overwrite: bool,
) -> Path | None:
    """Lock ``out_dir`` for the run (released by ``held``) and check it: resumable, or new
    or empty unless ``overwrite``. None without an output directory."""
    if out_dir is None:
        return None
    from agents.evaluation.outputs import output_lock, prepare_output_dir

    held.enter_context(output_lock(out_dir, "benchmark output directory"))
    if resume:
        out = Path(out_dir)
        _check_resumable(out, fams)
        return out
    return prepare_output_dir(
        out_dir,
        overwrite=overwrite,
        owned=("headline.md", "headline.json", "headline.csv", *fams),
        flag="--resume to continue it (its finished blocks are kept), or "
        "--overwrite to delete it and start again",
    )


def _check_resumable(out: Path, families: Sequence[str]) -> None:
    """``--resume`` continues a benchmark run: refuse a folder holding anything a run of
    these families does not write (a user's files are never replaced), or a report
    without a family folder (not a run of this tool); an empty folder starts the run."""
    from agents.evaluation.outputs import OutputDirError, entries, partial_dirs

    hint = "resume into the folder of an interrupted benchmark run, or choose a new --out"
    blocks = {LEVITATION.replace("+", "-"), GUIDED.replace("+", "-")}
    found = entries(out)
    for q in found:
        inside = []
        if q.name in families and q.is_dir():
            leftovers = set(partial_dirs(q))
            inside = [x for x in q.iterdir() if x.name not in blocks and x not in leftovers]
        elif q.name not in ("headline.md", "headline.json", "headline.csv") or q.is_dir():
            inside = [q]
        if inside:
            raise OutputDirError(
                f"--resume: {out} is not a benchmark run of these families: it holds "
                f"{inside[0]}, which such a run does not write ({hint})"
            )
    if found and not any(q.is_dir() for q in found):
        raise OutputDirError(
            f"--resume: {out} is not a benchmark run: it holds no block of its families ({hint})"
        )


@dataclass(frozen=True)
class _Block:
    """One family × actuator set of a benchmark run (one fragility sweep)."""

    family: str
    actuators: str
    group: list[tuple[str, str]]  # (controller, entrant label)
    levels: list[float]
    fixed: dict[str, Any]

    @property
    def controllers(self) -> list[str]:
        return [b for b, _ in self.group]

    def dir(self, out: Path) -> Path:
        return out / self.family / self.actuators.replace("+", "-")


def _clear_leftovers(out: Path, fams: list[str]) -> None:
    """Remove the partial block directories of a killed run (this run holds the directory's
    lock)."""
    import shutil

    from agents.evaluation.outputs import partial_dirs

    for fam in fams:
        for q in partial_dirs(out / fam):
            shutil.rmtree(q, ignore_errors=True)


def _finished_blocks(
    out: Path,
    blocks: list[_Block],
    conds: list[str],
    seed_list: list[int],
    distance_km: float,
    *,
    n_boot: int,
    n_boot_fragility: int,
) -> dict[int, dict[str, Any]]:
    """The results of every block a previous run finished with these settings, by index
    (a block run with other settings is refused)."""
    done: dict[int, dict[str, Any]] = {}
    for k, b in enumerate(blocks):
        doc = _finished_block(
            b.dir(out),
            b.controllers,
            conds,
            b.levels,
            seed_list,
            distance_km,
            b.fixed,
            actuators=b.actuators,
            n_boot=n_boot,
            n_boot_fragility=n_boot_fragility,
        )
        if doc is not None:
            done[k] = doc
    return done


def _fly_block(
    b: _Block,
    out: Path | None,
    conds: list[str],
    seed_list: list[int],
    distance_km: float,
    *,
    allow_training_seeds: bool,
    backend: str,
    workers: int,
    address: str | None,
    figures: bool,
    progress: bool,
    n_boot: int,
    n_boot_fragility: int,
    command: str | None,
) -> dict[str, Any]:
    """Run one block's fragility sweep, write its files (whole or not at all) and return its
    JSON document."""
    from agents.evaluation.fragility import fragility
    from agents.evaluation.fragility_report import to_json, write_outputs
    from agents.evaluation.outputs import atomic_dir

    res = fragility(
        b.controllers,
        conds,
        b.family,
        b.levels,
        seeds=seed_list,
        allow_training_seeds=allow_training_seeds,
        distance_km=distance_km,
        fixed=b.fixed or None,
        env_kwargs={"actuators": b.actuators},
        n_boot=n_boot,
        n_boot_fragility=n_boot_fragility,
        backend=backend,
        workers=workers,
        address=address,
        out_dir=None,
        progress=progress,
        command=command,
    )
    if out is not None:  # the block appears whole or not at all
        sub = b.dir(out)
        with atomic_dir(sub) as tmp:
            paths = write_outputs(res, tmp, figures)
        res["paths"] = {k_: str(sub / Path(v).relative_to(tmp)) for k_, v in paths.items()}
    return to_json(res)


def _write_headline(
    out: Path,
    h: dict[str, Any],
    s: dict[str, Any],
    fams: list[str],
    conds: list[str],
    settings: dict[str, Any],
) -> None:
    """headline.md, headline.json and headline.csv into ``out``."""
    from agents.evaluation.outputs import atomic_write_text

    atomic_write_text(out / "headline.md", headline_markdown(h, s, fams, conds, settings))
    atomic_write_text(
        out / "headline.json",
        json.dumps(json_value({"settings": settings, "headline": h}), indent=1) + "\n",
    )
    atomic_write_text(out / "headline.csv", headline_csv(h, fams))


def _run_blocks(
    out: Path | None,
    blocks: list[_Block],
    s: dict[str, Any],
    fams: list[str],
    conds: list[str],
    labels: list[str],
    seed_list: list[int],
    distance_km: float,
    *,
    resume: bool,
    allow_training_seeds: bool,
    backend: str,
    workers: int,
    address: str | None,
    figures: bool,
    progress: bool,
    n_boot: int,
    n_boot_fragility: int,
    command: str | None,
) -> dict[str, Any]:
    t0 = time.perf_counter()
    done: dict[int, dict[str, Any]] = {}
    if out is not None:
        _clear_leftovers(out, fams)
    if resume and out is not None:  # every finished block, or a refusal, before any runs
        done = _finished_blocks(
            out,
            blocks,
            conds,
            seed_list,
            distance_km,
            n_boot=n_boot,
            n_boot_fragility=n_boot_fragility,
        )
    sweeps: dict[str, dict[str, dict[str, Any]]] = {}
    raw: dict[str, dict[str, Any]] = {}
    for k, b in enumerate(blocks):
        if k in done:
            doc = done[k]
        else:
            doc = _fly_block(
                b,
                out,
                conds,
                seed_list,
                distance_km,
                allow_training_seeds=allow_training_seeds,
                backend=backend,
                workers=workers,
                address=address,
                figures=figures,
                progress=progress,
                n_boot=n_boot,
                n_boot_fragility=n_boot_fragility,
                command=command,
            )
        raw.setdefault(b.family, {})[b.actuators] = doc
        for c, lab in b.group:
            sweeps.setdefault(b.family, {})[lab] = {
                "fits": [f for f in doc["fits"] if f["controller"] == c],
                "levels": [r for r in doc["levels"] if r["controller"] == c],
            }
    h = json_value(headline(sweeps, s, labels, conds))
    earlier = sum(float(d["settings"]["wall_s"]) for d in done.values())
    settings = {
        "entrants": labels,
        "conditions": conds,
        "families": fams,
        "seeds": len(seed_list),
        "seed_range": [min(seed_list), max(seed_list)],
        "seed_list": seed_list,
        "distance_km": float(distance_km),
        "suite": {f: s["families"][f] for f in fams},
        "wall_s": time.perf_counter() - t0 + earlier,
        "n_boot": n_boot,
        "n_boot_fragility": n_boot_fragility,
        "command": command or "agents.evaluation.benchmark.run_benchmark(...)",
    }
    result = {"settings": settings, "headline": h, "sweeps": raw}
    if out is not None:
        _write_headline(out, h, s, fams, conds, settings)
    return result
