"""``hyperloop checkpoints``: score every checkpoint of a training run on the validation set
and name the one to ship (:mod:`agents.training.checkpoint_scores`)."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from agents.cli.common import argv_of, new_parser, run
from agents.cli.options import add_settings

SETTINGS = ("actuators", "overwrite", "workers")


def build_parser(prog: str = "hyperloop checkpoints") -> argparse.ArgumentParser:
    from agents.training import checkpoint_scores as cs

    ap = new_parser(
        prog,
        "Score every checkpoint of a training run (and its final model) on the validation\n"
        "seeds — the agent search's score, paired capacity ratio against LQR — with a flight\n"
        "check; the best one that flies is the step count a preset's timesteps should take.",
        epilog="--actuators: by default the run's own (its training_log.json). --overwrite: "
        "replace an existing scores file. --workers: each model's capacity tasks and flights "
        "on that many processes (the same scores whatever the number).",
    )
    ap.add_argument("run", type=Path, help="a training run directory (hyperloop train --out)")
    ap.add_argument(
        "--min-steps", type=int, default=0, help="skip earlier checkpoints (default: %(default)s)"
    )
    ap.add_argument(
        "--fly-seeds",
        type=int,
        default=cs.DEFAULT_FLY_SEEDS,
        help="validation seeds per condition of the flight check, 0: none (default: %(default)s)",
    )
    ap.add_argument(
        "--fly-km",
        type=float,
        default=cs.DEFAULT_FLY_KM,
        help="flight-check distance [km] (default: %(default)s)",
    )
    ap.add_argument(
        "--scores-file",
        type=Path,
        default=None,
        metavar="PATH",
        help=f"where the scores go (default: <run>/{cs.SCORES_FILE}; another path scores a "
        "shipped agent without touching its folder)",
    )
    add_settings(ap, SETTINGS)
    ap.set_defaults(actuators=None)
    return ap


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop checkpoints") -> int:
    from agents.training import checkpoint_scores as cs

    ap = build_parser(prog)
    a = ap.parse_args(argv)
    args = argv_of(argv)
    out = a.scores_file or a.run / cs.SCORES_FILE
    if a.fly_seeds < 0:
        ap.error("--fly-seeds must be >= 0 (0: no flight check)")
    if a.workers < 1:
        ap.error(f"--workers must be an integer >= 1, got {a.workers}")
    if out.exists() and not a.overwrite:
        ap.error(f"{out} exists (pass --overwrite)")

    def show(row: dict[str, Any]) -> None:
        ratios = ", ".join(f"{c['ratio']:.3g}" for c in row["conditions"].values())
        touch = sum(row["contacts"].values())
        print(
            f"{row['steps']:>9d}  score {row['score']:7.3f}  ratio {ratios}  contacts {touch}",
            flush=True,
        )

    rc, doc = run(
        prog,
        args,
        lambda: cs.score_run(
            a.run, a.actuators, a.min_steps, a.fly_seeds, a.fly_km, show, workers=a.workers
        ),
    )
    if rc:
        return rc
    best = doc["best"]
    path = cs.write_scores(doc, out)
    print(f"best: {best['steps']} steps (score {best['score']:.3f}); wrote {path}")
    return 0
