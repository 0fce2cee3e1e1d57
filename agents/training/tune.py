"""Hyper-parameter search with Ray Tune: ``python train.py --tune ...``.

What is searched (reward weights and a few PPO hyper-parameters), how a trial is scored,
and where everything goes:

* **Search space** (:data:`SEARCH_SPACE`): the reward weights ``gap_weight``,
  ``guidance_weight``, ``comfort_weight``, ``current_weight`` (log-uniform) and PPO's
  ``learning_rate`` (log-uniform), ``n_steps`` per env, ``ent_coef`` and the network width
  (choices). ``--tune-trials`` configurations are drawn with a NumPy generator seeded by
  ``--tune-seed`` (so the search is reproducible) and handed to Ray Tune as a grid.
* **Trial**: the preset's training run (``--tune-timesteps`` env steps, the preset's seed,
  i.e. training seeds only) with the sampled values, then the **validation score**.
* **Validation score**: the fragility sweep (:mod:`agents.evaluation.fragility`) of the
  trained agent on ``roughness`` at :data:`VALIDATION_LEVELS` over the four paper
  conditions, ``VALIDATION_SEEDS`` runs of ``VALIDATION_KM`` each per level, on the
  **validation seeds** (from :data:`VALIDATION_SEED0`; disjoint from the training seeds,
  which are below 100 000, and from the benchmark's evaluation seeds,
  :data:`agents.evaluation.benchmark.EVAL_SEED0`). Score = mean over the conditions of
  ln θ, θ the fitted median capacity (a degenerate sweep contributes its bound:
  :func:`capacity_estimate`). Higher is better.
* **Execution**: Ray Tune, trials in parallel on this machine by default (one CPU and one
  torch thread each, ``--tune-workers`` at a time), or on a cluster with ``--address``.
  Every trial's run directory, the search space, every trial's score and the chosen
  configuration are written to ``--tune-out`` (``tune_results.json``, ``tune_trials.csv``);
  the shipped agents copy them next to the model.
"""

from __future__ import annotations

import csv
import io
import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from agents.evaluation.benchmark import VALIDATION_SEED0, capacity_estimate
from agents.invocation import invoked_prog

__all__ = [
    "VALIDATION_SEED0",
    "capacity_estimate",
    "collect_search",
    "run_search",
    "sample_configs",
]

VALIDATION_LEVELS: tuple[float, ...] = (0.2, 0.3, 0.4, 0.55, 0.75)
VALIDATION_SEEDS = 4
VALIDATION_KM = 2.0

SEARCH_SPACE: dict[str, tuple[str, Any]] = {
    # name: (kind, values) — kind "log" = log-uniform in (lo, hi), "choice" = one of values
    "gap_weight": ("log", (5.0, 60.0)),
    "guidance_weight": ("log", (0.3, 10.0)),
    "comfort_weight": ("log", (0.3, 5.0)),
    "current_weight": ("log", (0.01, 0.3)),
    "learning_rate": ("log", (1e-4, 1e-3)),
    "n_steps": ("choice", (128, 256, 512)),
    "ent_coef": ("choice", (0.0, 1e-4, 1e-3)),
    "width": ("choice", (64, 128)),
}
REWARD_KEYS = ("gap_weight", "guidance_weight", "comfort_weight", "current_weight")


def sample_configs(n: int, seed: int) -> list[dict[str, Any]]:
    """``n`` configurations drawn from :data:`SEARCH_SPACE` (reproducible for a seed)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        c: dict[str, Any] = {}
        for name, (kind, vals) in SEARCH_SPACE.items():
            if kind == "log":
                lo, hi = vals
                c[name] = float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
            else:
                c[name] = vals[int(rng.integers(len(vals)))]
                c[name] = float(c[name]) if isinstance(c[name], float) else int(c[name])
        out.append(c)
    return out


def apply_config(cfg: dict[str, Any], trial: dict[str, Any]) -> dict[str, Any]:
    """The training configuration of one trial (``cfg`` from the preset, updated)."""
    out = dict(cfg)
    kw = dict(out.get("env_kwargs") or {})
    for k in REWARD_KEYS:
        kw[k] = float(trial[k])
    out["env_kwargs"] = kw
    out["learning_rate"] = float(trial["learning_rate"])
    out["n_steps"] = int(trial["n_steps"])
    out["ent_coef"] = float(trial["ent_coef"])
    out["net_arch"] = [int(trial["width"])] * 2
    # a PPO batch must divide the rollout: n_steps × n_envs
    rollout = out["n_steps"] * int(out["n_envs"])
    out["batch_size"] = min(int(out["batch_size"]), rollout)
    return out


def validation_score(
    run_dir: str | Path,
    actuators: str = "levitation",
    workers: int = 1,
    levels: tuple[float, ...] = VALIDATION_LEVELS,
    seeds: int = VALIDATION_SEEDS,
    distance_km: float = VALIDATION_KM,
    conditions: tuple[str, ...] | None = None,
) -> tuple[float, dict[str, Any]]:
    """(score, details) of the agent saved in ``run_dir`` (module docstring)."""
    from agents.evaluation.fragility import fragility
    from hyperloop_env.scenarios import PAPER_SCENARIOS

    res = fragility(
        ["ppo"],
        list(conditions or PAPER_SCENARIOS),
        "roughness",
        list(levels),
        seeds=list(range(VALIDATION_SEED0, VALIDATION_SEED0 + seeds)),
        distance_km=distance_km,
        env_kwargs={"actuators": actuators},
        controller_kwargs={"ppo": {"path": str(run_dir)}},
        n_boot=0,
        n_boot_fragility=1,  # the score uses the point estimates only
        workers=workers,
        progress=False,
        figures=False,
    )
    caps = {}
    for f in res["fits"]:
        caps[f["condition"]] = capacity_estimate(f["fit"])
    vals = [math.log(v) for v in caps.values() if v > 0 and math.isfinite(v)]
    score = float(np.mean(vals)) if len(vals) == len(caps) else -math.inf
    contacts = {f"{r['condition']}@{r['level']:g}": r["n_contacts"] for r in res["levels"]}
    return score, {"capacity": caps, "contacts": contacts}


def _trial(config: dict[str, Any]) -> None:  # pragma: no cover - runs in Ray workers
    from ray import tune

    from agents.training.experiment import train

    cfg = apply_config(config["base"], config["trial"])
    cfg["out"] = str(Path(config["root"]) / f"trial_{config['index']:03d}")
    cfg["progress_bar"] = False
    cfg["verbose"] = 0
    import torch

    torch.set_num_threads(1)
    t0 = time.perf_counter()
    train(cfg)
    t_train = time.perf_counter() - t0
    val = config.get("validation") or {}
    score, details = validation_score(
        cfg["out"],
        cfg.get("env_kwargs", {}).get("actuators", "levitation"),
        levels=tuple(val.get("levels", VALIDATION_LEVELS)),
        seeds=int(val.get("seeds", VALIDATION_SEEDS)),
        distance_km=float(val.get("distance_km", VALIDATION_KM)),
        conditions=tuple(val.get("conditions", ())) or None,
    )
    tune.report(
        {
            "score": score,
            "train_s": t_train,
            "wall_s": time.perf_counter() - t0,
            "details": json.dumps(details),
        }
    )


def _trial_entry(config: dict[str, Any]) -> None:  # pragma: no cover - Ray worker
    """The grid puts each configuration under ``"t"``."""
    _trial(config["t"])


def run_search(
    base: dict[str, Any],
    trials: int,
    timesteps: int,
    out: str | Path,
    seed: int = 0,
    workers: int = 2,
    address: str | None = None,
    validation: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Run the search (module docstring); returns and writes ``tune_results.json``.
    ``validation`` may shorten the validation (keys ``levels``, ``seeds``, ``distance_km``,
    ``conditions``; tests only)."""
    import ray
    from ray import tune

    from agents.training.numerics import PINNED

    root = Path(out).resolve()
    root.mkdir(parents=True, exist_ok=True)
    configs = sample_configs(trials, seed)
    base = dict(base)
    base["timesteps"] = int(timesteps)
    base["no_eval"] = True
    env_vars = {**PINNED, "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    ray.init(
        address=address,
        include_dashboard=False,
        log_to_driver=False,
        runtime_env={"env_vars": env_vars},
        ignore_reinit_error=True,
    )
    try:
        space = [
            {
                "index": i,
                "trial": c,
                "base": base,
                "root": str(root),
                "validation": validation or {},
            }
            for i, c in enumerate(configs)
        ]
        tuner = tune.Tuner(
            tune.with_resources(_trial_entry, {"cpu": 1}),
            param_space={"t": tune.grid_search(space)},
            tune_config=tune.TuneConfig(max_concurrent_trials=workers),
            run_config=tune.RunConfig(name="search", storage_path=str(root / "ray"), verbose=1),
        )
        results = tuner.fit()
    finally:
        ray.shutdown()
    rows = []
    for r in results:
        t = r.config["t"]
        m = r.metrics or {}
        rows.append(_row(t, m, str(r.error) if r.error else None))
    return write_results(root, rows, base, trials, timesteps, seed, validation)


def _row(t: dict[str, Any], m: dict[str, Any], error: str | None) -> dict[str, Any]:
    """One trial's row: its configuration, score, times, validation details, error."""
    return {
        "index": t["index"],
        **t["trial"],
        "score": m.get("score", -math.inf),
        "train_s": m.get("train_s"),
        "wall_s": m.get("wall_s"),
        "details": json.loads(m.get("details") or "{}"),
        "error": error,
    }


def write_results(
    root: Path,
    rows: list[dict[str, Any]],
    base: dict[str, Any],
    trials: int,
    timesteps: int,
    seed: int,
    validation: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Write ``tune_results.json`` and ``tune_trials.csv`` (atomically) and return the
    payload: search space, every trial's row, the best trial and its training config."""
    from agents.evaluation.outputs import atomic_write_text

    rows = sorted(rows, key=lambda r: r["index"])
    scored = [r for r in rows if math.isfinite(r["score"])]
    if not scored:
        raise ValueError(f"{root}: no trial has a finite validation score")
    best = max(scored, key=lambda r: r["score"])
    payload = {
        "search_space": {k: {"kind": v[0], "values": list(v[1])} for k, v in SEARCH_SPACE.items()},
        "trials_requested": trials,
        "trials_finished": sum(1 for r in rows if r["error"] is None),
        "timesteps_per_trial": int(timesteps),
        "search_seed": seed,
        "validation": {
            "family": "roughness",
            "levels": list(VALIDATION_LEVELS),
            "seeds": [VALIDATION_SEED0, VALIDATION_SEED0 + VALIDATION_SEEDS - 1],
            "distance_km": VALIDATION_KM,
            "conditions": "the four paper conditions",
            "score": "mean over the conditions of ln θ",
            **(validation or {}),
        },
        "base": {k: v for k, v in base.items() if k not in ("resume", "overwrite")},
        "command": base.get("command"),
        "trials": rows,
        "best": best,
        "chosen_training_config": apply_config(base, best),
    }
    atomic_write_text(root / "tune_results.json", json.dumps(payload, indent=1, default=str) + "\n")
    buf = io.StringIO()
    cols = ["index", *SEARCH_SPACE, "score", "train_s", "wall_s", "error"]
    w = csv.DictWriter(buf, fieldnames=cols, extrasaction="ignore")
    w.writeheader()
    w.writerows(rows)
    atomic_write_text(root / "tune_trials.csv", buf.getvalue())
    return payload


def collect_search(out: str | Path, trials: int, seed: int = 0) -> dict[str, Any]:
    """Write ``tune_results.json`` of a search that was stopped before the end (machine
    restart, Ctrl-C) from what it left on disk: each finished trial's ``result.json``
    under ``<out>/ray/search/``. Trials that did not finish keep their configuration
    (regenerated from ``trials`` and ``seed``, checked against the started ones) with
    score -inf and ``error`` saying so; the best is chosen among the finished ones."""
    root = Path(out).resolve()
    search = root / "ray" / "search"
    if not search.is_dir():
        raise ValueError(f"{search}: no Ray Tune search here")
    configs = sample_configs(trials, seed)
    found: dict[int, tuple[dict[str, Any], dict[str, Any] | None]] = {}
    for d in sorted(search.iterdir()):
        params = d / "params.json"
        if not params.is_file():
            continue
        t = json.loads(params.read_text())["t"]
        i = int(t["index"])
        if i >= trials or t["trial"] != configs[i]:
            raise ValueError(f"{d}: trial {i} does not match --trials {trials} / seed {seed}")
        lines = (d / "result.json").read_text().split("\n") if (d / "result.json").is_file() else []
        lines = [x for x in lines if x.strip()]
        found[i] = (t, json.loads(lines[-1]) if lines else None)
    if not found:
        raise ValueError(f"{search}: no trial directories")
    base = next(iter(found.values()))[0]["base"]
    rows = []
    for i, c in enumerate(configs):
        t, m = found.get(i, ({"index": i, "trial": c}, None))
        if m is None or "score" not in m:
            state = "started" if i in found else "never started"
            rows.append(_row(t, {}, f"not finished: the search stopped ({state})"))
        else:
            rows.append(_row(t, m, None))
    return write_results(root, rows, base, trials, int(base["timesteps"]), seed)


SEARCHED_KEYS = ("env_kwargs", "learning_rate", "n_steps", "ent_coef", "net_arch", "batch_size")


def preset_from_search(
    results: str | Path, base_preset: str, out_name: str, timesteps: int | None = None
) -> Path:
    """Write ``agents/training/presets/<out_name>.json``: the base preset with the search's
    chosen configuration (the searched keys of ``tune_results.json``'s
    ``chosen_training_config``), ``out`` = ``runs/<out_name>``."""
    from agents.evaluation.outputs import atomic_write_text
    from agents.training.presets import PRESET_DIR, load_preset

    doc = json.loads(Path(results).read_text())
    chosen = doc["chosen_training_config"]
    preset = load_preset(base_preset)
    for k in SEARCHED_KEYS:
        preset[k] = chosen[k]
    preset["out"] = f"runs/{out_name}"
    if timesteps is not None:
        preset["timesteps"] = int(timesteps)
    path = PRESET_DIR / f"{out_name}.json"
    atomic_write_text(path, json.dumps(preset, indent=2) + "\n")
    return path


def main(argv: list[str] | None = None) -> int:
    import argparse

    ap = argparse.ArgumentParser(
        prog=invoked_prog("python -m agents.training.tune"),
        description="Write a training preset from a finished search (train.py --tune).",
    )
    ap.add_argument(
        "results",
        type=Path,
        help="tune_results.json of the search (with --collect: its --tune-out)",
    )
    ap.add_argument("--base", help="the preset the search started from")
    ap.add_argument("--name", help="name of the new preset")
    ap.add_argument("--timesteps", type=int, default=None)
    ap.add_argument(
        "--collect",
        type=int,
        metavar="TRIALS",
        default=None,
        help="write tune_results.json of a stopped search (its --tune-trials)",
    )
    ap.add_argument("--tune-seed", type=int, default=0, help="the search's --tune-seed")
    args = ap.parse_args(argv)
    if args.collect is not None:
        try:
            doc = collect_search(args.results, args.collect, args.tune_seed)
        except ValueError as exc:
            ap.error(str(exc))
        print(
            f"wrote {args.results / 'tune_results.json'}: {doc['trials_finished']} of "
            f"{args.collect} trials finished, best #{doc['best']['index']} "
            f"(score {doc['best']['score']:.3f})"
        )
        return 0
    if not args.base or not args.name:
        ap.error("--base and --name are required (unless --collect)")
    path = preset_from_search(args.results, args.base, args.name, args.timesteps)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
