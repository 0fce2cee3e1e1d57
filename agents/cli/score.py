"""``hyperloop score CONTROLLER``: fly one controller on the published benchmark's seeds,
conditions and families and pair its capacities and its ride comfort with every published
entrant's (:func:`agents.evaluation.score.score`); writes ``score.md``, ``score.json`` and
``score.png`` to ``--out``."""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path

from agents.cli.common import argv_of, import_from_cwd, new_parser, run
from agents.cli.options import PARALLEL, add_settings, settings_from_args

SETTINGS = ("out", "overwrite", "progress", "figures", *PARALLEL)
OWNED = ("score.md", "score.json", "score.png")


def build_parser(prog: str = "hyperloop score") -> argparse.ArgumentParser:
    from agents.evaluation.published import BENCHMARK_VERSION
    from agents.evaluation.score import GUARD_ENTRANT, QUICK_FAMILIES, QUICK_SEEDS

    ap = new_parser(
        prog,
        f"Score one controller against the published {BENCHMARK_VERSION} benchmark: its "
        "per-seed capacities on the published seeds, conditions and families, and its ride "
        "comfort (a_wz) on the same seeds and conditions, paired with every published "
        "entrant's.",
        epilog="CONTROLLER: a registry name (hyperloop evaluate --help lists them), "
        "'package.module:factory' (found from the current folder) or the path of a saved "
        "model.zip; shielded:<any of these> behind the safety filter.",
    )
    ap.add_argument("controller", metavar="CONTROLLER", help="the controller to score")
    ap.add_argument(
        "--quick",
        action="store_true",
        help=f"{', '.join(QUICK_FAMILIES)} only, on the first {QUICK_SEEDS} seeds "
        "(default: every published family on every published seed)",
    )
    ap.add_argument(
        "--allow-mismatch",
        action="store_true",
        help="score even if this installation's fingerprint differs from the published one "
        "(stamped into the result)",
    )
    ap.add_argument(
        "--no-guard",
        dest="guard",
        action="store_false",
        help=f"skip re-flying the published {GUARD_ENTRANT!r} (default: re-fly it on a few "
        "seeds and refuse unless its capacities are the published ones)",
    )
    add_settings(ap, SETTINGS, out=Path("reports/score"))
    return ap


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop score") -> int:
    import_from_cwd()
    from agents.evaluation.outputs import atomic_write_text, output_lock, prepare_output_dir
    from agents.evaluation.published import load_published
    from agents.evaluation.score import ScoreSpec, score
    from agents.evaluation.score_report import markdown, plot_score
    from hyperloop_env.json_values import json_value

    ap = build_parser(prog)
    a = ap.parse_args(argv)
    args = argv_of(argv)
    try:
        st = settings_from_args(a, SETTINGS)
        from agents.cli.evaluate import check_controllers

        check_controllers([a.controller])
    except ValueError as exc:
        ap.error(str(exc))
    spec = ScoreSpec(a.controller, a.quick, a.allow_mismatch, a.guard)

    def job() -> dict:
        with output_lock(st.out, "score output directory"):
            out = prepare_output_dir(st.out, overwrite=st.overwrite, owned=OWNED)
            pub = load_published()
            res = score(spec, workers=st.workers, backend=st.backend, address=st.address,
                        progress=st.progress, published=pub)  # fmt: skip
            res["command"] = " ".join([prog, *args])
            if st.figures:
                plot_score(res, pub, out / "score.png")
            atomic_write_text(out / "score.md", markdown(res))
            atomic_write_text(out / "score.json", json.dumps(json_value(res), indent=1) + "\n")
            return res

    rc, res = run(prog, args, job)
    if not rc:
        e, ride = res["leaderboard"], res["comfort"]["summary"]
        print(
            f"{e['controller']}: above {e['above']}, below {e['below']}, equivalent "
            f"{e['equivalent']}, undecided {e['undecided']}; ride smoother than "
            f"{ride['smoother']}, equivalent {ride['equivalent']}, rougher than "
            f"{ride['rougher']}, undecided {ride['undecided']}; report in {st.out / 'score.md'}"
        )
    return rc
