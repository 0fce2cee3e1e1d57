#!/usr/bin/env python
"""Score every checkpoint of a training run on the validation set, to pick the one to ship.

    python scripts/score_checkpoints.py runs/shipped-ppo [--actuators levitation]

Each ``checkpoints/model_<N>_steps.zip`` (with its VecNormalize statistics) and the final
``model.zip`` get the Ray Tune search's validation score
(:func:`agents.training.tune.validation_score`: per-seed roughness capacities over the four
paper conditions on the **validation seeds** from 2 000 000, never on the benchmark's
evaluation seeds; score = mean over the conditions of ln(paired capacity ratio against LQR),
LQR's capacities computed once) and a flight check:
the contacts of ``--fly-seeds`` validation seeds (from 2 000 000) × ``--fly-km`` km on each
paper condition at nominal severity (the shipped-agent requirement, issue "Controllers that
set the bar" point 5, on validation seeds; the evaluation seeds confirm it in
``tests/agents/training/test_shipped_flies.py``). The best checkpoint is the highest score
among those with no contact (the highest score overall, marked ``"flies": false``, if none
flies). The scores go to ``<run>/checkpoint_validation.json`` (refused if it exists, unless
``--overwrite``) and a table is printed; the best step count N is what a preset's
``timesteps`` should be set to.
A checkpoint is written at the start of a rollout, after the previous update, so the
checkpoint at N steps is the final model of the same run stopped at ``--timesteps N``.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from agents.evaluation.outputs import atomic_write_text  # noqa: E402
from agents.training.tune import (  # noqa: E402
    VALIDATION_FAMILY,
    VALIDATION_KM,
    VALIDATION_SEED0,
    VALIDATION_SEEDS,
    validation_capacities,
    validation_score,
)
from hyperloop_env.scenarios import PAPER_SCENARIOS  # noqa: E402


def flight_contacts(model: Path, actuators: str, n_seeds: int, km: float) -> dict[str, int]:
    """Episodes ending in contact per paper condition: ``n_seeds`` validation seeds × ``km``
    km at nominal severity on the default track."""
    from agents.controllers.learned import SB3Controller
    from agents.evaluation.rollout import episode_config, run_episodes

    seeds = list(range(VALIDATION_SEED0, VALIDATION_SEED0 + n_seeds))
    out = {}
    for cond in PAPER_SCENARIOS:
        cfg = episode_config(cond, km, None, {"actuators": actuators})
        eps = run_episodes(lambda ctx: SB3Controller(model), cfg, seeds, km, None)
        out[cond] = sum(bool(e.terminated) for e in eps)
    return out


CKPT = re.compile(r"model_(\d+)_steps\.zip")


def models(run: Path) -> list[tuple[int, Path]]:
    """(steps, model file) of every checkpoint and the final model, by steps."""
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


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", type=Path, help="a train.py run directory")
    ap.add_argument(
        "--actuators", default=None, help="the run's actuator set (default: from training_log.json)"
    )
    ap.add_argument("--min-steps", type=int, default=0, help="skip earlier checkpoints")
    ap.add_argument("--fly-seeds", type=int, default=20, help="validation seeds per condition")
    ap.add_argument("--fly-km", type=float, default=10.0, help="flight-check distance [km]")
    ap.add_argument("--overwrite", action="store_true")
    ap.add_argument(
        "--out",
        type=Path,
        default=None,
        help="where the scores go (default <run>/checkpoint_validation.json; another path "
        "scores a shipped agent without touching its folder)",
    )
    args = ap.parse_args(argv)
    out = args.out or args.run / "checkpoint_validation.json"
    if args.fly_seeds < 0:
        ap.error("--fly-seeds must be >= 0 (0: no flight check)")
    if out.exists() and not args.overwrite:
        ap.error(f"{out} exists (pass --overwrite)")
    found = [(s, p) for s, p in models(args.run) if s >= args.min_steps]
    if not found:
        ap.error(f"{args.run}: no checkpoints or final model")
    acts = args.actuators
    log = json.loads((args.run / "training_log.json").read_text())
    if acts is None:
        acts = log.get("env_kwargs", {}).get("actuators", "levitation")
    baseline = validation_capacities("lqr", acts)
    rows = []
    for steps, path in found:
        t0 = time.perf_counter()
        score, details = validation_score(path, acts, baseline=baseline, algo=log.get("algo"))
        contacts = (
            flight_contacts(path, acts, args.fly_seeds, args.fly_km) if args.fly_seeds else {}
        )
        rows.append(
            {
                "steps": steps,
                "model": str(path.relative_to(args.run)),
                "score": score,
                **details,
                "contacts": contacts,
                "flies": (not any(contacts.values())) if args.fly_seeds else None,
                "wall_s": time.perf_counter() - t0,
            }
        )
        ratios = ", ".join(f"{c['ratio']:.3g}" for c in details["conditions"].values())
        touch = sum(contacts.values())
        print(f"{steps:>9d}  score {score:7.3f}  ratio {ratios}  contacts {touch}", flush=True)
    flying = [r for r in rows if r["flies"]]
    best = max(flying or rows, key=lambda r: r["score"])
    doc = {
        "run": str(args.run),
        "actuators": acts,
        "validation": {
            "family": VALIDATION_FAMILY,
            "seeds": [VALIDATION_SEED0, VALIDATION_SEED0 + VALIDATION_SEEDS - 1],
            "distance_km": VALIDATION_KM,
            "score": "mean over the paper conditions of ln(paired capacity ratio / LQR)",
            "lqr_capacities": baseline,
            "flight_check": {
                "seeds": [VALIDATION_SEED0, VALIDATION_SEED0 + args.fly_seeds - 1],
                "distance_km": args.fly_km,
                "conditions": list(PAPER_SCENARIOS),
            },
            "best": "highest score among the checkpoints without contact",
        },
        "checkpoints": rows,
        "best": best,
    }
    atomic_write_text(out, json.dumps(doc, indent=1) + "\n")
    print(f"best: {best['steps']} steps (score {best['score']:.3f}); wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
