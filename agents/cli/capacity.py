"""``hyperloop capacity``: per-seed capacities of every entrant on common seeds and the
paired verdicts — the project's headline study
(:func:`agents.evaluation.capacity_benchmark.run`)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from agents.cli.common import argv_of, import_from_cwd, new_parser, run
from agents.cli.options import EVALUATION, PARALLEL, add_settings, settings_from_args
from agents.evaluation import capacity_benchmark as cb
from agents.evaluation.benchmark import HEADLINE_FAMILIES, default_entrants
from agents.evaluation.capacity import (
    DEFAULT_CHECK_ABOVE,
    DEFAULT_RATIO,
    DEFAULT_ROWS,
    DEFAULT_STEP,
)
from agents.evaluation.studies import CapacitySpec
from agents.evaluation.studies import run as run_study

SETTINGS = (
    *(n for n in EVALUATION if n not in ("magnet", "actuators", "settle_s", "n_boot")),
    "n_boot_fit",
    "resume",
    *PARALLEL,
)


def build_parser(prog: str = "hyperloop capacity") -> argparse.ArgumentParser:
    ap = new_parser(prog, "Per-seed capacities (incremental dynamic analysis) and paired verdicts.")
    ap.add_argument(
        "--entrants",
        nargs="+",
        default=list(default_entrants()),
        help="controller names; name+g = with the guidance currents (levitation+guidance); "
        "shielded:<name> = behind the safety filter",
    )
    ap.add_argument(
        "--conditions", nargs="+", default=["paper"], help="scenarios ('paper' = the four)"
    )
    ap.add_argument(
        "--families",
        nargs="+",
        default=list(HEADLINE_FAMILIES),
        help="disturbance families whose realisation scales with the severity",
    )
    ap.add_argument(
        "--ratio", type=float, default=DEFAULT_RATIO, help="bracket ratio of the bisection"
    )
    ap.add_argument("--step", type=float, default=DEFAULT_STEP, help="hunt factor")
    ap.add_argument(
        "--check-above",
        type=int,
        default=DEFAULT_CHECK_ABOVE,
        help="check-grid levels flown above a seed's capacity",
    )
    ap.add_argument(
        "--entrant-seeds",
        nargs="+",
        default=None,
        metavar="LABEL=N",
        help="fly these entrants on the first N seeds only (default: the registry's "
        "entrant_seeds: every built-in flies all seeds; LABEL=N with N >= --seeds: all "
        "seeds)",
    )
    ap.add_argument("--rows", type=int, default=DEFAULT_ROWS, help="batch rows per task")
    add_settings(
        ap, SETTINGS, seeds=cb.DEFAULT_SEEDS, distance_km=cb.DEFAULT_DISTANCE_KM,
        out=Path("reports/capacity"),
    )  # fmt: skip
    return ap


def _entrant_seeds(ap: argparse.ArgumentParser, items: list[str] | None) -> dict[str, int] | None:
    if items is None:
        return None
    out = {}
    for item in items:
        lab, sep, k = item.partition("=")
        if not sep or not k.strip().isdigit():
            ap.error(f"--entrant-seeds: expected LABEL=N (N an int), got {item!r}")
        out[lab.strip()] = int(k)
    return out


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop capacity") -> int:
    import_from_cwd()  # a user\'s module:factory beside them, as python -m finds it
    ap = build_parser(prog)
    a = ap.parse_args(argv)
    args = argv_of(argv)
    entrant_seeds = _entrant_seeds(ap, a.entrant_seeds)
    try:
        st = settings_from_args(a, SETTINGS)
    except ValueError as exc:
        ap.error(str(exc))
    from agents.evaluation import seeds as seeding

    try:
        seeds = seeding.seed_list(st.seeds, st.seed0, st.seed_list, min_n=2)
        seeding.check_evaluation_seeds(
            [e[:-2] if e.endswith("+g") else e for e in a.entrants], seeds, st.allow_training_seeds
        )
    except ValueError as exc:
        ap.error(str(exc))
    cmd = " ".join([prog, *args])
    rc, res = run(
        prog,
        args,
        lambda: run_study(
            CapacitySpec(
                tuple(a.entrants),
                tuple(a.conditions),
                tuple(a.families),
                a.ratio,
                a.step,
                a.check_above,
                a.rows,
                entrant_seeds,
            ),
            st,
            command=cmd,
        ),
        "--resume",
    )
    if rc:
        return rc
    h = res["headline"]
    print(
        f"{h['decided']} of {h['pairs']} pairs decided; report in {st.out}/headline.md "
        f"({res['settings']['wall_s'] / 60:.1f} min)",
        file=sys.stdout,
    )
    return 0
