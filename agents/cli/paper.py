"""``hyperloop paper``: reproduce the paper's study with this model — the passive STS
tables of the four conditions, the radius sweep and the critical radius
(:func:`agents.evaluation.reproduce_paper.run`)."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from agents.cli.common import argv_of, import_from_cwd, new_parser, run
from agents.cli.options import add_settings, settings_from_args

SETTINGS = (
    "seeds",
    "seed0",
    "seed_list",
    "allow_training_seeds",
    "distance_km",
    "magnet",
    "settle_s",
    "out",
    "overwrite",
    "progress",
    "workers",
)


def build_parser(prog: str = "hyperloop paper") -> argparse.ArgumentParser:
    from agents.evaluation import reproduce_paper as rp

    ap = new_parser(prog, rp.__doc__ or "")
    ap.add_argument("--sweep-km", type=float, default=2.0, help="per sweep/bisection run [km]")
    ap.add_argument(
        "--bracket-rel",
        type=float,
        default=0.01,
        help="bisection stops when hi/lo - 1 is below this (default 1 %%)",
    )
    add_settings(ap, SETTINGS, seeds=1, distance_km=10.0, out=Path("reports/paper"))
    return ap


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop paper") -> int:
    import_from_cwd()  # a user\'s module:factory beside them, as python -m finds it
    from agents.evaluation import reproduce_paper as rp
    from agents.evaluation import seeds as seeding
    from agents.evaluation.studies import run as run_study

    ap = build_parser(prog)
    a = ap.parse_args(argv)
    args = argv_of(argv)
    try:
        st = settings_from_args(a, SETTINGS)
        spec = rp.PaperSpec(
            seeds=tuple(seeding.seed_list(st.seeds, st.seed0, st.seed_list)),
            distance_km=st.distance_km,
            sweep_km=a.sweep_km,
            settle_s=st.settle_s,
            magnet=st.magnet,
            bracket_rel=a.bracket_rel,
            allow_training_seeds=st.allow_training_seeds,
        )
    except ValueError as exc:
        ap.error(str(exc))
    rc, _ = run(
        prog,
        args,
        lambda: run_study(spec, st, command=" ".join([prog, *args])),
    )
    if not rc:
        print(f"wrote {st.out / 'report.md'}")
    return rc
