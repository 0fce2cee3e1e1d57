"""``hyperloop compare``: comparisons of controllers from published results, one mode each —
``target`` (is a learned agent resolved above every classical controller, with a ride no
rougher?), ``comfort`` (ride comfort on common seeds, paired with a reference), ``shield``
(the safety filter's effect: capacity, interventions, comfort) and ``cost`` (what each
entrant of a headline run cost) — :mod:`agents.evaluation.comparisons`."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from agents.cli.common import argv_of, import_from_cwd, new_parser, run
from agents.cli.options import add_settings, settings_from_args
from agents.evaluation.comparisons import comfort, target

TARGET_SETTINGS = ("out", "overwrite")
COMFORT_SETTINGS = ("seeds", "seed0", "allow_training_seeds", "distance_km", "out", "overwrite")
COMFORT_SETTINGS += ("progress", "workers")
SHIELD_SETTINGS = ("seeds", "seed0", "distance_km", "out", "overwrite", "workers")
HEADLINE = Path("docs") / "benchmark" / "headline.json"
"""The published headline run of a checkout (``cost``'s default)."""


def _first_line(doc: str | None) -> str:
    return (doc or "").split("\n\n")[0].replace("``", "")


def _mode(sub: Any, name: str, prog: str, doc: str | None, help: str) -> argparse.ArgumentParser:
    """One ``hyperloop compare`` mode's parser (its module docstring as the description)."""
    return sub.add_parser(
        name,
        prog=f"{prog} {name}",
        help=help,
        description=doc,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        allow_abbrev=False,
    )


def build_parser(prog: str = "hyperloop compare") -> argparse.ArgumentParser:
    from agents.evaluation.comparisons import cost
    from hyperloop_env.scenarios import PAPER_SCENARIOS

    ap = new_parser(prog, _first_line(__doc__))
    sub = ap.add_subparsers(dest="mode", required=True, metavar="{target,comfort,shield,cost}")

    t = _mode(
        sub,
        "target",
        prog,
        target.__doc__,
        "learned agents against classical controllers: capacity and comfort",
    )
    t.add_argument("--learned", nargs="+", required=True, help="learned agents")
    t.add_argument(
        "--classical",
        nargs="+",
        default=(),
        help="classical controllers (default: every classical headline entrant with the "
        "learned agents' actuators, passive aside: pid lqr lqr-preview mpc, or pid+g lqr+g "
        "lqr-preview+g with the guidance pairs)",
    )
    t.add_argument(
        "--runs",
        nargs="+",
        type=Path,
        required=True,
        metavar="HEADLINE_JSON",
        help="capacity runs (headline.json of hyperloop capacity / headline) on the same seeds",
    )
    t.add_argument(
        "--comfort",
        type=Path,
        default=None,
        metavar="COMFORT_JSON",
        help="the comfort.json of hyperloop compare comfort on the same seeds",
    )
    add_settings(t, TARGET_SETTINGS, out=Path("reports") / "target")
    t.set_defaults(parser=t)

    c = _mode(
        sub,
        "comfort",
        prog,
        comfort.__doc__,
        "ride comfort (ISO 2631-1 W_k) on common seeds, paired with a reference",
    )
    c.add_argument("--controllers", nargs="+", required=True, help="controllers to compare")
    c.add_argument(
        "--reference",
        default=comfort.DEFAULT_REFERENCE,
        help="the controller each one is paired with (default: %(default)s)",
    )
    c.add_argument(
        "--conditions",
        "--scenarios",
        dest="conditions",
        nargs="+",
        default=list(PAPER_SCENARIOS),
        help="'paper' (the four paper conditions, the default) and/or scenario names",
    )
    add_settings(
        c, COMFORT_SETTINGS, seeds=comfort.DEFAULT_SEEDS, distance_km=comfort.DEFAULT_DISTANCE_KM,
        out=Path("reports") / "comfort",
    )  # fmt: skip
    c.set_defaults(parser=c)

    _add_shield(sub, prog)

    k = _mode(
        sub,
        "cost",
        prog,
        cost.__doc__,
        "worker time per entrant and per seed of a headline run (Markdown)",
    )
    k.add_argument(
        "headline",
        nargs="?",
        type=Path,
        default=HEADLINE,
        metavar="HEADLINE_JSON",
        help=f"a headline run's headline.json (default: {HEADLINE}, in a checkout)",
    )
    k.set_defaults(parser=k)
    return ap


def _add_shield(sub: Any, prog: str) -> None:
    from agents.evaluation.comparisons import shield
    from hyperloop_env.scenarios import PAPER_SCENARIOS

    s = _mode(
        sub,
        "shield",
        prog,
        shield.__doc__,
        "the safety filter's effect: capacity with and without it, interventions, comfort",
    )
    s.add_argument(
        "--capacity",
        type=Path,
        nargs="+",
        metavar="HEADLINE_JSON",
        help="headline.json of hyperloop capacity runs on the same seeds whose entrants are "
        "controllers and their shielded: versions (required unless --render-only)",
    )
    s.add_argument(
        "--conditions",
        nargs="+",
        default=list(PAPER_SCENARIOS),
        help="conditions of the interventions and comfort runs (default: the paper's four)",
    )
    s.add_argument(
        "--severities",
        type=float,
        nargs="+",
        default=[0.3],
        help="roughness severities of the interventions runs, besides the scenario's own "
        "(default: %(default)s)",
    )
    s.add_argument(
        "--render-only",
        action="store_true",
        help="rewrite shield.md from the shield.json in --out (no flights)",
    )
    add_settings(s, SHIELD_SETTINGS, seeds=8, distance_km=3.0, out=Path("reports") / "shield")
    s.set_defaults(parser=s)


def _shield(
    a: argparse.Namespace, sub: argparse.ArgumentParser, prog: str, args: list[str], command: str
) -> int:
    from agents.evaluation.comparisons import shield

    try:
        st = settings_from_args(a, SHIELD_SETTINGS)
    except ValueError as exc:
        sub.error(str(exc))
    if a.render_only:
        rc, path = run(prog, args, lambda: shield.render_only(st.out))
        if not rc:
            print(f"wrote {path}")
        return rc
    if not a.capacity:
        sub.error("--capacity is required (unless --render-only)")
    rc, _ = run(
        prog,
        args,
        lambda: shield.run(
            a.capacity, st.out, conditions=a.conditions, seeds=st.seeds, seed0=st.seed0,
            distance_km=st.distance_km, severities=a.severities, command=command,
            overwrite=st.overwrite, workers=st.workers,
        ),
    )  # fmt: skip
    if not rc:
        print(f"wrote {st.out / 'shield.md'}")
    return rc


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop compare") -> int:
    import_from_cwd()  # a user's module:factory beside them, as python -m finds it
    args = argv_of(argv)
    ap = build_parser(prog)
    a = ap.parse_args(args)
    sub: argparse.ArgumentParser = a.parser
    mode_prog = f"{prog} {a.mode}"
    command = " ".join([prog, *args])
    if a.mode == "target":
        try:
            st = settings_from_args(a, TARGET_SETTINGS)
            tspec = target.TargetSpec(
                tuple(a.learned), tuple(a.classical), tuple(a.runs), a.comfort
            )
        except ValueError as exc:
            sub.error(str(exc))
        rc, doc = run(
            mode_prog,
            args,
            lambda: target.run(tspec, st.out, overwrite=st.overwrite, command=command),
        )
        if not rc:
            print(target.target_markdown(doc), end="")
        return rc
    if a.mode == "comfort":
        from agents.evaluation import seeds as seeding
        from hyperloop_env.scenarios import expand_scenarios

        try:
            st = settings_from_args(a, COMFORT_SETTINGS)
            cspec = comfort.ComfortSpec(
                controllers=tuple(a.controllers),
                seeds=tuple(seeding.seed_list(st.seeds, st.seed0, None, min_n=2)),
                reference=a.reference,
                conditions=tuple(expand_scenarios(a.conditions)),
                distance_km=st.distance_km,
                allow_training_seeds=st.allow_training_seeds,
            )
        except ValueError as exc:
            sub.error(str(exc))
        log = (lambda line: print(line, flush=True)) if st.progress else None
        rc, doc = run(
            mode_prog,
            args,
            lambda: comfort.run(
                cspec, st.out, overwrite=st.overwrite, command=command, log=log, workers=st.workers
            ),
        )
        if not rc:
            print(comfort.comfort_markdown(doc), end="")
        return rc
    if a.mode == "shield":
        return _shield(a, sub, mode_prog, args, command)
    from agents.evaluation.comparisons import cost

    rc, table = run(mode_prog, args, lambda: cost.headline_cost(a.headline))
    if not rc:
        print(table, end="")
    return rc
