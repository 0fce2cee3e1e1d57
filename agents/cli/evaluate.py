"""``hyperloop evaluate``: controllers on the paper's conditions or any scenario — the
paper's STS, RMS gaps, contacts and ride comfort (:func:`agents.evaluation.evaluate.evaluate`)."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from agents.cli.common import argv_of, import_from_cwd, new_parser, run
from agents.cli.options import EVALUATION, add_settings, settings_from_args
from agents.evaluation.settings import Settings

SETTINGS = (*EVALUATION, "workers")


def add_controllers(ap: argparse.ArgumentParser, conditions: Sequence[str] = ("paper",)) -> None:
    """``--controllers`` and ``--conditions`` (alias ``--scenarios``), as evaluate and
    fragility take them."""
    from agents.controllers.registry import default_controllers, offered_controllers
    from hyperloop_env.scenarios import SCENARIOS

    ap.add_argument(
        "--controllers",
        nargs="+",
        default=default_controllers(),
        help=f"controller names ({', '.join(offered_controllers())}), 'package.module:factory' "
        "or the path of a saved model.zip; shielded:<name> = any of them behind the safety "
        "filter",
    )
    ap.add_argument(
        "--conditions",
        "--scenarios",
        dest="conditions",
        nargs="+",
        default=list(conditions),
        help="'paper' (the four paper conditions) and/or scenario names: "
        + ", ".join(sorted(SCENARIOS)),
    )


def build_parser(prog: str = "hyperloop evaluate") -> argparse.ArgumentParser:
    ap = new_parser(
        prog, "Evaluate controllers on hyperloop scenarios (STS, RMS, contacts, comfort)."
    )
    add_controllers(ap)
    add_settings(ap, SETTINGS, seeds=1, distance_km=10.0, out=Path("reports"))
    return ap


def check_controllers(names: Sequence[str]) -> None:
    """``ValueError`` (one line, before any work: not a traceback mid-run) for a controller
    that cannot be built here (unknown, not shipped, an extra missing)."""
    from agents.controllers.registry import controller_problem

    for c in names:
        problem = controller_problem(c)
        if problem:
            raise ValueError(problem)


def check(ap: argparse.ArgumentParser, a: argparse.Namespace) -> tuple[Settings, list[str]]:
    """The settings and the conditions, every value checked before anything runs
    (``ap.error``: one line, exit 2)."""
    from agents.evaluation import seeds as seeding
    from agents.evaluation.evaluate import check_settling, episode_configs
    from hyperloop_env.scenarios import expand_scenarios

    try:
        st = settings_from_args(a, SETTINGS)
        check_controllers(a.controllers)
        conds = expand_scenarios(a.conditions)
        a.seed_values = seeding.seed_list(st.seeds, st.seed0, st.seed_list)
        seeding.check_evaluation_seeds(a.controllers, a.seed_values, st.allow_training_seeds)
        configs = episode_configs(
            conds, st.distance_km, st.magnet, {"actuators": st.actuators}, "--distance-km"
        )
        check_settling(configs, st.settle_s, st.distance_km, ("--distance-km", "--settle-s"))
    except ValueError as exc:
        ap.error(str(exc))
    return st, conds


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop evaluate") -> int:
    import_from_cwd()  # a user\'s module:factory beside them, as python -m finds it
    from dataclasses import replace

    from agents.evaluation.report import summary_table
    from agents.evaluation.studies import EvaluateSpec
    from agents.evaluation.studies import run as run_study

    ap = build_parser(prog)
    a = ap.parse_args(argv)
    args = argv_of(argv)
    st, conds = check(ap, a)
    rc, res = run(
        prog,
        args,
        lambda: run_study(
            EvaluateSpec(tuple(a.controllers), tuple(conds)),
            replace(st, seeds=None, seed_list=tuple(a.seed_values)),
            command=" ".join([prog, *args]),
        ),
    )
    if rc:
        return rc
    print(summary_table(res["results"]))
    for k, v in res["paths"].items():
        print(f"{k}: {v}")
    return 0
