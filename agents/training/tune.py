"""Hyper-parameter search with Ray Tune: ``hyperloop train --tune ...``; a training preset
from its results: ``hyperloop tune agent`` (:func:`preset_from_search`,
:func:`collect_search`).

What is searched (reward weights and a few hyper-parameters of the algorithm, and for
agents with memory the observation options), how a trial is scored, and where everything
goes:

* **Search space** (:data:`SEARCH_SPACES`, by ``--tune-space``): ``ppo`` — the reward
  weights ``gap_weight``, ``guidance_weight``, ``comfort_weight``, ``current_weight``
  (log-uniform) and PPO's ``learning_rate`` (log-uniform), ``n_steps`` per env,
  ``ent_coef`` and the network width (choices); ``ppo-memory`` — the same and the
  observation memory (:data:`OBSERVATIONS`: ``observation_history`` and/or
  ``observation_front_preview``, :mod:`hyperloop_env.observation`); ``sac-memory`` — the
  reward weights, SAC's ``learning_rate``, the network width and the observation memory;
  ``ppo-residual`` (a preset with the option ``residual``) — the reward weights,
  ``learning_rate``, the correction's bound ``scale``, ``log_std_init``, the
  ``privileged_critic`` on or off and the roughness ``curriculum`` (:data:`CURRICULA`) on
  or off; the actor's width stays the preset's.
  ``--tune-trials`` configurations are drawn with a NumPy generator seeded by
  ``--tune-seed`` (so the search is reproducible) and handed to Ray Tune as a grid.
* **Trial**: the preset's training run (``--tune-timesteps`` env steps, the preset's seed,
  i.e. training seeds only) with the sampled values, then the **validation score**.
* **Validation score** (:func:`validation_score`): the paired capacity ratio against LQR,
  the decisive benchmark's measure (:mod:`agents.evaluation.capacity`,
  :func:`agents.evaluation.capacity_stats.compare_paired`). The trained agent and ``lqr``
  (with the same actuators) each get per-seed ``roughness`` capacities on the four paper
  conditions, ``VALIDATION_SEEDS`` **validation seeds** (from :data:`VALIDATION_SEED0`;
  disjoint from the training seeds, which are below 100 000, and from the benchmark's
  evaluation seeds, :data:`agents.evaluation.benchmark.EVAL_SEED0`) × ``VALIDATION_KM``
  km, the headline's search settings. Per condition the ratio is the geometric mean of the
  per-seed ratios agent / LQR; score = mean over the conditions of its logarithm (0: level
  with LQR; > 0: above). A residual run is flown as its residual controller
  (:data:`RESIDUAL_ENTRY`) and scored against its base law instead of LQR. A condition
  whose seeds are all censored for both contributes 0. The reference's capacities are
  computed once per search (and per run scored by
  :func:`agents.training.checkpoint_scores.score_run`).
  Higher is better.
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

__all__ = [
    "VALIDATION_SEED0",
    "capacity_estimate",
    "collect_search",
    "run_search",
    "sample_configs",
]

VALIDATION_SEEDS = 8
VALIDATION_KM = 3.0
VALIDATION_FAMILY = "roughness"

OBSERVATIONS: dict[str, dict[str, Any]] = {
    "h2": {"observation_history": 2},
    "h4": {"observation_history": 4},
    "h8": {"observation_history": 8},
    "fp": {"observation_front_preview": True},
    "h2+fp": {"observation_history": 2, "observation_front_preview": True},
    "h4+fp": {"observation_history": 4, "observation_front_preview": True},
}
"""The observation memory choices of the ``*-memory`` spaces (env keywords)."""

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

CURRICULA: dict[str, dict[str, Any] | None] = {
    "none": None,
    "roughness": {
        "family": "roughness",
        "start": 0.2,
        "stop": 0.8,
        "step": 0.05,
        "hold": 0.9,
        "window": 64,
        "floor": 0.5,
    },
}
"""The curriculum choices of the ``ppo-residual`` space (the option ``curriculum``;
:mod:`agents.training.curriculum`): none, or the roughness rising from 0.1–0.2 to 0.4–0.8
(the guideway's German "low" amplitude factor; the capacities of the classical guided laws
lie between 0.4 and 0.6)."""

SEARCH_SPACES: dict[str, dict[str, tuple[str, Any]]] = {
    "ppo": SEARCH_SPACE,
    "ppo-residual": {
        **{k: SEARCH_SPACE[k] for k in REWARD_KEYS},
        "learning_rate": ("log", (1e-4, 1e-3)),
        "scale": ("choice", (0.3, 0.6, 1.0)),
        "log_std_init": ("choice", (-1.5, -1.0, -0.5)),
        "privileged_critic": ("choice", (False, True)),
        "curriculum": ("choice", tuple(CURRICULA)),
    },
    "ppo-memory": {**SEARCH_SPACE, "observation": ("choice", tuple(OBSERVATIONS))},
    "sac-memory": {
        **{k: SEARCH_SPACE[k] for k in REWARD_KEYS},
        "learning_rate": ("log", (1e-4, 1e-3)),
        "width": ("choice", (64, 128, 256)),
        "observation": ("choice", tuple(OBSERVATIONS)),
    },
}
"""The search spaces (``--tune-space``); the algorithm is the name's first part."""


def space_algo(space: str) -> str:
    if space not in SEARCH_SPACES:
        raise ValueError(f"tune space must be one of {list(SEARCH_SPACES)}, got {space!r}")
    return space.split("-")[0]


def sample_configs(n: int, seed: int, space: str = "ppo") -> list[dict[str, Any]]:
    """``n`` configurations drawn from ``SEARCH_SPACES[space]`` (reproducible for a seed)."""
    rng = np.random.default_rng(seed)
    space_algo(space)
    out = []
    for _ in range(n):
        c: dict[str, Any] = {}
        for name, (kind, vals) in SEARCH_SPACES[space].items():
            if kind == "log":
                lo, hi = vals
                c[name] = float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
            else:
                v = vals[int(rng.integers(len(vals)))]
                c[name] = (
                    v if isinstance(v, str | bool) else float(v) if isinstance(v, float) else int(v)
                )
        out.append(c)
    return out


def apply_config(cfg: dict[str, Any], trial: dict[str, Any]) -> dict[str, Any]:
    """The training configuration of one trial (``cfg`` from the preset, updated): the
    reward weights and observation memory into ``env_kwargs``, the algorithm's keys."""
    out = dict(cfg)
    kw = dict(out.get("env_kwargs") or {})
    for k in REWARD_KEYS:
        kw[k] = float(trial[k])
    if "observation" in trial:
        kw.pop("observation_history", None)
        kw.pop("observation_front_preview", None)
        kw.update(OBSERVATIONS[trial["observation"]])
    out["env_kwargs"] = kw
    out["learning_rate"] = float(trial["learning_rate"])
    if "width" in trial:
        out["net_arch"] = [int(trial["width"])] * 2
    if "scale" in trial:  # the residual's bound; the preset names the base law
        if out.get("residual") is None:
            raise ValueError("the ppo-residual space needs a preset with the option residual")
        out["residual"] = {**out["residual"], "scale": float(trial["scale"])}
    for key in ("log_std_init", "privileged_critic"):
        if key in trial:
            out[key] = trial[key]
    if "curriculum" in trial:
        out["curriculum"] = CURRICULA[trial["curriculum"]]
    if "n_steps" in trial:
        out["n_steps"] = int(trial["n_steps"])
        out["ent_coef"] = float(trial["ent_coef"])
        # a PPO batch must divide the rollout: n_steps × n_envs
        rollout = out["n_steps"] * int(out["n_envs"])
        out["batch_size"] = min(int(out["batch_size"]), rollout)
    return out


def validation_capacities(
    controller: str,
    actuators: str = "levitation",
    seeds: int = VALIDATION_SEEDS,
    distance_km: float = VALIDATION_KM,
    conditions: tuple[str, ...] | None = None,
    controller_kwargs: dict[str, Any] | None = None,
    rows: int = 32,
    workers: int = 1,
) -> dict[str, dict[str, list[Any]]]:
    """Per-seed ``roughness`` capacities of ``controller`` on the validation seeds:
    ``{condition: {"seeds", "capacity", "censored"}}`` (the headline's search settings,
    without its STS runs). ``workers``: the conditions' capacity tasks on that many worker
    processes (:func:`~agents.evaluation.backends.results_in_order`; inside a
    :func:`~agents.evaluation.backends.shared_pool` its pool); the same capacities
    whatever the number."""
    from dataclasses import replace

    from agents.evaluation.backends import results_in_order
    from agents.evaluation.benchmark import load_suite
    from agents.evaluation.capacity import CapacityTask, capacities, run_task
    from agents.evaluation.capacity_benchmark import family_searches
    from agents.evaluation.rollout import episode_config
    from hyperloop_env.scenarios import PAPER_SCENARIOS

    fam = family_searches(load_suite(), [VALIDATION_FAMILY])[VALIDATION_FAMILY]
    fam = replace(fam, levels=())
    seed_list = tuple(range(VALIDATION_SEED0, VALIDATION_SEED0 + int(seeds)))
    conds = tuple(conditions or PAPER_SCENARIOS)
    tasks = [
        CapacityTask(
            controller=controller,
            config=episode_config(cond, distance_km, None, {"actuators": actuators}),
            families=(fam,),
            seeds=seed_list,
            rows=rows,
            controller_kwargs=dict(controller_kwargs or {}),
            sts_stride=0,
        )
        for cond in conds
    ]
    out = {}
    for cond, res in zip(conds, results_in_order(tasks, run_task, workers), strict=True):
        searches = sorted(res.by_family(VALIDATION_FAMILY), key=lambda s: s.seed)
        cap, cens = capacities(searches)
        out[cond] = {
            "seeds": [s.seed for s in searches],
            "capacity": [float(c) for c in cap],
            "censored": [bool(c) for c in cens],
        }
    return out


def validation_score(
    run_dir: str | Path,
    actuators: str = "levitation",
    seeds: int = VALIDATION_SEEDS,
    distance_km: float = VALIDATION_KM,
    conditions: tuple[str, ...] | None = None,
    baseline: dict[str, dict[str, list[Any]]] | None = None,
    algo: str | None = None,
    residual: dict[str, Any] | None = None,
    workers: int = 1,
) -> tuple[float, dict[str, Any]]:
    """(score, details) of the agent saved in ``run_dir`` (module docstring): the mean
    over the conditions of ln(paired capacity ratio agent / reference). The reference is
    LQR, or for a residual run (``residual``: its record) the base law it corrects.
    ``baseline``: the reference's :func:`validation_capacities` with the same arguments
    (computed if not given); ``workers``: as there."""
    from agents.evaluation.capacity_stats import compare_paired

    args = (actuators, seeds, distance_km, conditions)
    if baseline is None:
        baseline = validation_capacities(reference_controller(residual), *args, workers=workers)
    kind = RESIDUAL_ENTRY if residual is not None else (algo or "ppo")
    agent = validation_capacities(
        kind, *args, controller_kwargs={"path": str(run_dir)}, workers=workers
    )
    logs, per = [], {}
    for cond, a in agent.items():
        b = baseline[cond]
        if a["seeds"] != b["seeds"]:
            raise ValueError(f"baseline seeds of {cond} differ from the agent's")
        cmp = compare_paired(a["capacity"], a["censored"], b["capacity"], b["censored"], n_boot=500)
        ratio = cmp.get("ratio")
        logs.append(math.log(ratio) if ratio else 0.0)
        per[cond] = {
            "ratio": ratio,
            "interval": [cmp.get("lo"), cmp.get("hi")],
            "verdict": cmp.get("verdict"),
            "capacity": a["capacity"],
            "censored": a["censored"],
            "lqr_capacity": b["capacity"],
        }
    return float(np.mean(logs)), {"conditions": per}


RESIDUAL_ENTRY = "agents.controllers.residual:make_residual"
"""The controller a residual run is scored as: its base law plus the saved correction."""


def reference_controller(residual: dict[str, Any] | None) -> str:
    """The controller a trial is scored against: ``lqr``, or a residual's base law."""
    return "lqr" if residual is None else str(residual["base"])


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
    score, details = validation_score(
        cfg["out"],
        cfg.get("env_kwargs", {}).get("actuators", "levitation"),
        **_validation_args(config.get("validation")),
        baseline=config.get("baseline"),
        algo=cfg["algo"],
        residual=cfg.get("residual"),
    )
    tune.report(
        {
            "score": score,
            "train_s": t_train,
            "wall_s": time.perf_counter() - t0,
            "details": json.dumps(details),
        }
    )


def _validation_args(val: dict[str, Any] | None) -> dict[str, Any]:
    """The validation's settings (``seeds``, ``distance_km``, ``conditions``), the
    defaults unless a test shortens them."""
    val = val or {}
    return {
        "seeds": int(val.get("seeds", VALIDATION_SEEDS)),
        "distance_km": float(val.get("distance_km", VALIDATION_KM)),
        "conditions": tuple(val.get("conditions", ())) or None,
    }


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
    space: str = "ppo",
) -> dict[str, Any]:
    """Run the search (module docstring) over ``SEARCH_SPACES[space]``; returns and writes
    ``tune_results.json``. ``validation`` may shorten the validation (keys ``seeds``,
    ``distance_km``, ``conditions``; tests only)."""
    import ray
    from ray import tune

    from agents.training.numerics import PINNED

    algo = space_algo(space)
    if base.get("algo", "ppo") != algo:
        raise ValueError(f"tune space {space!r} trains {algo}, the preset {base.get('algo')}")
    root = Path(out).resolve()
    root.mkdir(parents=True, exist_ok=True)
    configs = sample_configs(trials, seed, space)
    actuators = (base.get("env_kwargs") or {}).get("actuators", "levitation")
    reference = reference_controller(base.get("residual"))
    baseline = validation_capacities(reference, actuators, **_validation_args(validation))
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
        grid = [
            {
                "index": i,
                "trial": c,
                "base": base,
                "root": str(root),
                "validation": validation or {},
                "baseline": baseline,
                "space": space,
            }
            for i, c in enumerate(configs)
        ]
        tuner = tune.Tuner(
            # an overlapped PPO trial runs its updates on a second process: two CPUs
            tune.with_resources(_trial_entry, {"cpu": 2 if base.get("overlap_updates") else 1}),
            param_space={"t": tune.grid_search(grid)},
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
    return write_results(root, rows, base, trials, timesteps, seed, validation, space, baseline)


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
    space: str = "ppo",
    baseline: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Write ``tune_results.json`` and ``tune_trials.csv`` (atomically) and return the
    payload: search space, every trial's row, the best trial and its training config, and
    LQR's validation capacities (the score's reference)."""
    from agents.evaluation.outputs import atomic_write_text

    rows = sorted(rows, key=lambda r: r["index"])
    scored = [r for r in rows if math.isfinite(r["score"])]
    if not scored:
        raise ValueError(f"{root}: no trial has a finite validation score")
    best = max(scored, key=lambda r: r["score"])
    ref = reference_controller(base.get("residual"))
    payload = {
        "space": space,
        "search_space": {
            k: {"kind": v[0], "values": list(v[1])} for k, v in SEARCH_SPACES[space].items()
        },
        "trials_requested": trials,
        "trials_finished": sum(1 for r in rows if r["error"] is None),
        "timesteps_per_trial": int(timesteps),
        "search_seed": seed,
        "validation": {
            "family": VALIDATION_FAMILY,
            "seeds": [VALIDATION_SEED0, VALIDATION_SEED0 + VALIDATION_SEEDS - 1],
            "distance_km": VALIDATION_KM,
            "conditions": "the four paper conditions",
            "score": f"mean over the conditions of ln(paired capacity ratio agent / {ref})",
            **(validation or {}),
        },
        "reference_controller": ref,
        # the reference's validation capacities (the key's name from when it was always LQR)
        "lqr_capacities" if ref == "lqr" else "reference_capacities": baseline,
        "base": {k: v for k, v in base.items() if k not in ("resume", "overwrite")},
        "command": base.get("command"),
        "trials": rows,
        "best": best,
        "chosen_training_config": apply_config(base, best),
    }
    atomic_write_text(root / "tune_results.json", json.dumps(payload, indent=1, default=str) + "\n")
    buf = io.StringIO()
    cols = ["index", *SEARCH_SPACES[space], "score", "train_s", "wall_s", "error"]
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
    found: dict[int, tuple[dict[str, Any], dict[str, Any] | None]] = {}
    configs: list[dict[str, Any]] | None = None
    for d in sorted(search.iterdir()):
        params = d / "params.json"
        if not params.is_file():
            continue
        t = json.loads(params.read_text())["t"]
        if configs is None:
            configs = sample_configs(trials, seed, t.get("space", "ppo"))
        i = int(t["index"])
        if i >= trials or t["trial"] != configs[i]:
            raise ValueError(f"{d}: trial {i} does not match --trials {trials} / seed {seed}")
        lines = (d / "result.json").read_text().split("\n") if (d / "result.json").is_file() else []
        lines = [x for x in lines if x.strip()]
        found[i] = (t, json.loads(lines[-1]) if lines else None)
    if not found or configs is None:
        raise ValueError(f"{search}: no trial directories")
    first = next(iter(found.values()))[0]
    base = first["base"]
    rows = []
    for i, c in enumerate(configs):
        t, m = found.get(i, ({"index": i, "trial": c}, None))
        if m is None or "score" not in m:
            state = "started" if i in found else "never started"
            rows.append(_row(t, {}, f"not finished: the search stopped ({state})"))
        else:
            rows.append(_row(t, m, None))
    return write_results(
        root,
        rows,
        base,
        trials,
        int(base["timesteps"]),
        seed,
        first.get("validation") or None,
        first.get("space", "ppo"),
        first.get("baseline"),
    )


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
        if k in chosen:
            preset[k] = chosen[k]
    preset["out"] = f"runs/{out_name}"
    if timesteps is not None:
        preset["timesteps"] = int(timesteps)
    path = PRESET_DIR / f"{out_name}.json"
    atomic_write_text(path, json.dumps(preset, indent=2) + "\n")
    return path
