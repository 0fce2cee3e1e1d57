"""Every checkpoint of a training run scored on the validation set, to pick the one to ship
(``hyperloop checkpoints``).

Each ``checkpoints/model_<N>_steps.zip`` (with its VecNormalize statistics) and the final
``model.zip`` (:func:`models`) get the agent search's validation score
(:func:`agents.training.tune.validation_score`: per-seed roughness capacities over the four
paper conditions on the **validation seeds** from
:data:`~agents.evaluation.seeds.VALIDATION_SEED0`, never on the benchmark's evaluation
seeds; score = mean over the conditions of ln(paired capacity ratio against LQR), LQR's
capacities computed once) and a flight check (:func:`flight_contacts`): the contacts of
``fly_seeds`` validation seeds × ``fly_km`` km on each paper condition at nominal severity
(the shipped-agent requirement, on validation seeds; the evaluation seeds confirm it in
``tests/agents/training/test_shipped_flies.py``). The best checkpoint is the highest score
among those with no contact (the highest score overall, marked ``"flies": false``, if none
flies); its step count N is what a preset's ``timesteps`` should be set to. A checkpoint is
written at the start of a rollout, after the previous update, so the checkpoint at N steps
is the final model of the same run stopped at ``--timesteps N``.
"""

from __future__ import annotations

import json
import re
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agents.training.tune import (
    VALIDATION_FAMILY,
    VALIDATION_KM,
    VALIDATION_SEED0,
    VALIDATION_SEEDS,
)

__all__ = [
    "DEFAULT_FLY_KM",
    "DEFAULT_FLY_SEEDS",
    "SCORES_FILE",
    "FlightTask",
    "flight_contacts",
    "fly",
    "models",
    "score_run",
    "write_scores",
]

SCORES_FILE = "checkpoint_validation.json"
"""The scores' file name in the run directory (the default destination)."""
DEFAULT_FLY_SEEDS = 20
"""Validation seeds per condition of the flight check (0: no flight check)."""
DEFAULT_FLY_KM = 10.0
"""Distance of each flight-check run [km]."""

CKPT = re.compile(r"model_(\d+)_steps\.zip")


def models(run: Path) -> list[tuple[int, Path]]:
    """(steps, model file) of every checkpoint and the final model, by steps (the final
    model replaces a checkpoint of the same step count)."""
    out = []
    for p in sorted((run / "checkpoints").glob("model_*_steps.zip")):
        m = CKPT.fullmatch(p.name)
        if m:
            out.append((int(m.group(1)), p))
    log = run / "training_log.json"
    if (run / "model.zip").is_file() and log.is_file():
        steps = int(json.loads(log.read_text())["num_timesteps"])
        out = [(s, p) for s, p in out if s != steps] + [(steps, run / "model.zip")]
    return sorted(out)


@dataclass(frozen=True)
class FlightTask:
    """The flight check of one model on one paper condition: ``seeds`` × ``km`` km at
    nominal severity on the default track."""

    model: str
    actuators: str
    condition: str
    seeds: tuple[int, ...]
    km: float


@dataclass(frozen=True)
class FlightResult:
    contacts: int  # episodes ending in contact
    steps: int  # control steps flown


def fly(task: FlightTask, progress: Any = None) -> FlightResult:
    """Fly one :class:`FlightTask` (module level: the workers of
    :func:`~agents.evaluation.backends.run_blocks` call it)."""
    from agents.controllers.learned import SB3Controller
    from agents.evaluation.rollout import episode_config, run_episodes

    cfg = episode_config(task.condition, task.km, None, {"actuators": task.actuators})
    eps = run_episodes(lambda ctx: SB3Controller(task.model), cfg, list(task.seeds), task.km, None)
    return FlightResult(sum(bool(e.terminated) for e in eps), sum(e.n_steps for e in eps))


def flight_contacts(
    model: Path, actuators: str, n_seeds: int, km: float, workers: int = 1
) -> dict[str, int]:
    """Episodes ending in contact per paper condition: ``n_seeds`` validation seeds × ``km``
    km at nominal severity on the default track; the conditions on ``workers`` worker
    processes (the same counts whatever the number)."""
    from agents.evaluation.backends import results_in_order
    from hyperloop_env.scenarios import PAPER_SCENARIOS

    seeds = tuple(range(VALIDATION_SEED0, VALIDATION_SEED0 + n_seeds))
    tasks = [FlightTask(str(model), actuators, c, seeds, km) for c in PAPER_SCENARIOS]
    done = results_in_order(tasks, fly, workers)
    return {t.condition: r.contacts for t, r in zip(tasks, done, strict=True)}


def score_run(
    run: Path,
    actuators: str | None = None,
    min_steps: int = 0,
    fly_seeds: int = DEFAULT_FLY_SEEDS,
    fly_km: float = DEFAULT_FLY_KM,
    on_row: Callable[[dict[str, Any]], None] | None = None,
    workers: int = 1,
) -> dict[str, Any]:
    """Score every model of the run directory ``run`` from ``min_steps`` steps on (module
    docstring); ``actuators`` by default the run's own (its ``training_log.json``). Returns
    the scores' document (the run, the actuators, the validation set, one row per model,
    the best); ``on_row(row)`` is called after each model. ``workers``: each model's
    capacity tasks and flights on that many worker processes, all on one pool
    (:func:`~agents.evaluation.backends.shared_pool`); the same document whatever the
    number, apart from the wall times. ``ValueError`` before any work for ``fly_seeds`` <
    0, a bad ``workers`` or a run without checkpoints or final model."""
    from agents.evaluation.backends import check_backend, shared_pool

    if fly_seeds < 0:
        raise ValueError("--fly-seeds must be >= 0 (0: no flight check)")
    check_backend("local", workers)
    with shared_pool(workers):
        return _score_run(run, actuators, min_steps, fly_seeds, fly_km, on_row, workers)


def _score_run(
    run: Path,
    actuators: str | None,
    min_steps: int,
    fly_seeds: int,
    fly_km: float,
    on_row: Callable[[dict[str, Any]], None] | None,
    workers: int,
) -> dict[str, Any]:
    from agents.training.tune import validation_capacities, validation_score
    from hyperloop_env.scenarios import PAPER_SCENARIOS

    found = [(s, p) for s, p in models(run) if s >= min_steps]
    if not found:
        raise ValueError(f"{run}: no checkpoints or final model")
    log = json.loads((run / "training_log.json").read_text())
    acts = actuators
    if acts is None:
        acts = log.get("env_kwargs", {}).get("actuators", "levitation")
    baseline = validation_capacities("lqr", acts, workers=workers)
    rows = []
    for steps, path in found:
        t0 = time.perf_counter()
        score, details = validation_score(
            path, acts, baseline=baseline, algo=log.get("algo"), workers=workers
        )
        contacts = flight_contacts(path, acts, fly_seeds, fly_km, workers) if fly_seeds else {}
        row = {
            "steps": steps,
            "model": str(path.relative_to(run)),
            "score": score,
            **details,
            "contacts": contacts,
            "flies": (not any(contacts.values())) if fly_seeds else None,
            "wall_s": time.perf_counter() - t0,
        }
        rows.append(row)
        if on_row is not None:
            on_row(row)
    flying = [r for r in rows if r["flies"]]
    best = max(flying or rows, key=lambda r: r["score"])
    return {
        "run": str(run),
        "actuators": acts,
        "validation": {
            "family": VALIDATION_FAMILY,
            "seeds": [VALIDATION_SEED0, VALIDATION_SEED0 + VALIDATION_SEEDS - 1],
            "distance_km": VALIDATION_KM,
            "score": "mean over the paper conditions of ln(paired capacity ratio / LQR)",
            "lqr_capacities": baseline,
            "flight_check": {
                "seeds": [VALIDATION_SEED0, VALIDATION_SEED0 + fly_seeds - 1],
                "distance_km": fly_km,
                "conditions": list(PAPER_SCENARIOS),
            },
            "best": "highest score among the checkpoints without contact",
        },
        "checkpoints": rows,
        "best": best,
    }


def write_scores(doc: dict[str, Any], out: Path) -> Path:
    """Write ``doc`` (:func:`score_run`) to ``out`` atomically; returns the path."""
    from agents.evaluation.outputs import atomic_write_text

    atomic_write_text(out, json.dumps(doc, indent=1) + "\n")
    return Path(out)
