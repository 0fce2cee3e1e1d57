"""The preview weight α of ``lqr-preview``: a scan on validation seeds, the best α stored in
``agents/controllers/lqr_preview_weight.json`` (``hyperloop tune preview``).

Every candidate α flies the validation set of the agent search's score
(:mod:`agents.training.tune`: the ``roughness`` capacity search of the headline, per-seed
capacities on the validation seeds from :data:`~agents.evaluation.seeds.VALIDATION_SEED0`,
never evaluation seeds) at the four paper conditions beside plain ``lqr`` on the same
seeds; its score is the mean over the conditions of ln(paired capacity ratio
lqr-preview / lqr) (:func:`agents.evaluation.capacity_stats.compare_paired`). The best α
is written with the whole table and the command that produced it;
:data:`agents.controllers.lqr_preview.PREVIEW_WEIGHT` must equal it
(``tests/agents/controllers/test_lqr_preview.py`` checks that).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from agents.training.tune import VALIDATION_KM

__all__ = ["DEFAULT_SEEDS", "DEFAULT_WEIGHTS", "WEIGHT_FILE", "check", "scan", "write_weight"]

DEFAULT_WEIGHTS = (0.25, 0.5, 0.75, 1.0)
DEFAULT_SEEDS = 16
"""Validation seeds per condition."""
DEFAULT_DISTANCE_KM = VALIDATION_KM
WEIGHT_FILE = Path(__file__).resolve().parents[1] / "controllers" / "lqr_preview_weight.json"
METHOD = (
    "mean over the four paper conditions of ln(paired roughness capacity ratio "
    "lqr-preview / lqr) on validation seeds (agents.training.tune's score)"
)


def check(weights: Sequence[float], seeds: int) -> None:
    """``ValueError`` for weights outside [0, 2] (or none) or fewer than 2 seeds."""
    if not weights or any(not 0.0 <= w <= 2.0 for w in weights):
        raise ValueError("--weights must be numbers in [0, 2]")
    if seeds < 2:
        raise ValueError("--validation-seeds must be >= 2")


def scan(
    weights: Sequence[float],
    seeds: int = DEFAULT_SEEDS,
    distance_km: float = DEFAULT_DISTANCE_KM,
    command: str = "",
    on_row: Callable[[dict[str, Any]], None] | None = None,
    workers: int = 1,
) -> dict[str, Any]:
    """Score every α of ``weights`` (module docstring); returns the document of
    ``lqr_preview_weight.json``: method, ``command``, the seeds' range, the distance, the
    best ``weight``, the ``scan`` (per α: score and per condition the paired ratio, its
    interval and verdict) and the wall time. ``on_row(row)`` is called after each α.
    ``workers``: the conditions' capacity tasks on that many processes of one pool (the
    same document whatever the number, apart from the wall time)."""
    from agents.evaluation.backends import check_backend, shared_pool

    check(weights, seeds)
    check_backend("local", workers)
    with shared_pool(workers):
        return _scan(weights, seeds, distance_km, command, on_row, workers)


def _scan(
    weights: Sequence[float],
    seeds: int,
    distance_km: float,
    command: str,
    on_row: Callable[[dict[str, Any]], None] | None,
    workers: int,
) -> dict[str, Any]:
    from agents.evaluation.capacity_stats import compare_paired
    from agents.training.tune import validation_capacities

    t0 = time.perf_counter()
    kw = {"seeds": seeds, "distance_km": distance_km, "workers": workers}
    base = validation_capacities("lqr", **kw)
    rows = []
    for w in weights:
        caps = validation_capacities("lqr-preview", controller_kwargs={"preview_weight": w}, **kw)
        per = {}
        for cond, a in caps.items():
            b = base[cond]
            c = compare_paired(a["capacity"], a["censored"], b["capacity"], b["censored"])
            per[cond] = {
                "ratio": c.get("ratio"),
                "interval": [c.get("lo"), c.get("hi")],
                "verdict": c.get("verdict"),
            }
        score = sum(math.log(p["ratio"]) for p in per.values()) / len(per)
        row = {"weight": w, "score": score, "conditions": per}
        rows.append(row)
        if on_row is not None:
            on_row(row)
    best = max(rows, key=lambda r: r["score"])
    first = base[next(iter(base))]["seeds"]
    return {
        "method": METHOD,
        "command": command,
        "seeds": [min(first), max(first)],
        "distance_km": distance_km,
        "weight": best["weight"],
        "scan": rows,
        "wall_s": round(time.perf_counter() - t0, 1),
    }


def write_weight(doc: dict[str, Any], out: str | Path = WEIGHT_FILE) -> Path:
    """Write ``doc`` (:func:`scan`) to ``out`` atomically; returns the path."""
    from agents.evaluation.outputs import atomic_write_text

    atomic_write_text(out, json.dumps(doc, indent=2) + "\n")
    return Path(out)
