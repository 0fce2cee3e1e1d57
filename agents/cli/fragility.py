"""``hyperloop fragility``: the contact probability per run against one disturbance
family's severity, the lognormal fragility fit, the paper's STS and comfort per level
(:func:`agents.evaluation.fragility.fragility`)."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from agents.cli.common import argv_of, import_from_cwd, new_parser, run
from agents.cli.evaluate import add_controllers, check_controllers
from agents.cli.options import EVALUATION, PARALLEL, add_settings, settings_from_args
from agents.evaluation.fragility import (
    DEFAULT_BLOCK_SIZE,
    DEFAULT_MAX_BLOCK_MB,
    DEFAULT_MAX_SAMPLES,
)

SETTINGS = (*EVALUATION, "n_boot_fit", *PARALLEL)


def build_parser(prog: str = "hyperloop fragility") -> argparse.ArgumentParser:
    from hyperloop_env.disturbances import DISTURBANCES

    ap = new_parser(
        prog,
        "Fragility of controllers against a disturbance family: contact probability per run "
        "vs severity, lognormal fragility fit, STS, comfort.",
    )
    add_controllers(ap, ("paper-1000-straight",))
    ap.add_argument(
        "--family", default="roughness", help=f"disturbance family ({', '.join(DISTURBANCES)})"
    )
    ap.add_argument(
        "--levels", nargs="+", type=float, required=True, help="severity levels (the family's unit)"
    )
    ap.add_argument(
        "--with",
        dest="fixed",
        action="append",
        default=[],
        metavar="NAME=SEVERITY",
        help="a fixed extra disturbance (repeatable)",
    )
    ap.add_argument(
        "--interval",
        default="exact",
        choices=("exact", "wilson"),
        help="binomial interval: Clopper-Pearson (exact) or Wilson",
    )
    ap.add_argument(
        "--block-size",
        type=int,
        default=DEFAULT_BLOCK_SIZE,
        help="seeds per block (one batched vector env; fixes the results)",
    )
    ap.add_argument(
        "--max-block-mb",
        type=float,
        default=DEFAULT_MAX_BLOCK_MB,
        help="memory budget of one block's guideway profiles [MB]",
    )
    ap.add_argument(
        "--max-samples",
        type=int,
        default=DEFAULT_MAX_SAMPLES,
        help="thinned STS samples per unit and group",
    )
    ap.add_argument(
        "--no-batch",
        action="store_true",
        help="single-env episodes even for controllers with act_batch",
    )
    add_settings(ap, SETTINGS, seeds=10, distance_km=10.0, out=Path("reports/fragility"))
    return ap


def parse_fixed(items: list[str], ap: argparse.ArgumentParser) -> dict[str, float]:
    """``--with NAME=SEVERITY`` items as {name: severity}."""
    out: dict[str, float] = {}
    for it in items:
        name, sep, val = it.partition("=")
        if not sep:
            ap.error(f"--with expects NAME=SEVERITY, got {it!r}")
        try:
            out[name] = float(val)
        except ValueError:
            ap.error(f"--with {name}: severity must be a number, got {val!r}")
    return out


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop fragility") -> int:
    import_from_cwd()  # a user\'s module:factory beside them, as python -m finds it
    from agents.evaluation import seeds as seeding
    from agents.evaluation.studies import FragilitySpec
    from agents.evaluation.studies import run as run_study

    ap = build_parser(prog)
    a = ap.parse_args(argv)
    args = argv_of(argv)
    fixed = parse_fixed(a.fixed, ap)
    try:
        st = settings_from_args(a, SETTINGS)
        check_controllers(a.controllers)
        seeds = seeding.seed_list(st.seeds, st.seed0, st.seed_list)
        seeding.check_evaluation_seeds(a.controllers, seeds, st.allow_training_seeds)
    except ValueError as exc:
        ap.error(str(exc))
    rc, res = run(
        prog,
        args,
        lambda: run_study(
            FragilitySpec(
                tuple(a.controllers),
                a.family,
                tuple(a.levels),
                tuple(a.conditions),
                fixed,
                a.interval,
                a.block_size,
                a.max_samples,
                a.max_block_mb,
                False if a.no_batch else None,
            ),
            st,
            command=" ".join([prog, *args]),
        ),
    )
    if rc:
        return rc
    for f in res["fits"]:
        print(f"{f['controller']:>8} {f['condition']}: {f['summary']}")
    for k, v in res["paths"].items():
        print(f"{k}: {v}")
    return 0
