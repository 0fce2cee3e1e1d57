"""``hyperloop benchmark``: the suite's fragility grid for every entrant, the headline
table and one fragility report per family
(:func:`agents.evaluation.benchmark.run_benchmark`); ``--merge`` joins finished runs of
different entrants (:func:`~agents.evaluation.benchmark.merge_runs`)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from agents.cli.common import argv_of, import_from_cwd, new_parser, run
from agents.cli.options import PARALLEL, add_settings, settings_from_args
from agents.evaluation import benchmark as bm

SETTINGS = (
    "seeds",
    "seed0",
    "seed_list",
    "allow_training_seeds",
    "distance_km",
    "n_boot",
    "n_boot_fit",
    "out",
    "overwrite",
    "resume",
    "progress",
    "figures",
    *PARALLEL,
)


def build_parser(prog: str = "hyperloop benchmark") -> argparse.ArgumentParser:
    ap = new_parser(
        prog,
        "Run the benchmark suite (agents/evaluation/benchmark_suite.json) for the given "
        "entrants and write the headline table (Markdown, JSON, CSV) and one fragility "
        "report per family.",
    )
    ap.add_argument(
        "--entrants",
        nargs="+",
        default=list(bm.default_entrants()),
        help="controller names; name+g = with the guidance currents (levitation+guidance)",
    )
    ap.add_argument(
        "--conditions", nargs="+", default=["paper"], help="scenarios ('paper' = the four)"
    )
    ap.add_argument("--families", nargs="+", default=None, help="suite families (default: all)")
    ap.add_argument("--suite", type=Path, default=None, help="suite JSON (default: the shipped)")
    ap.add_argument("--print-suite", action="store_true", help="print the suite table and exit")
    ap.add_argument(
        "--merge",
        nargs="+",
        type=Path,
        default=None,
        metavar="RUN_DIR",
        help="no runs: merge finished benchmark runs of different entrants into --out",
    )
    add_settings(
        ap, SETTINGS, seeds=bm.DEFAULT_SEEDS, distance_km=bm.DEFAULT_DISTANCE_KM,
        out=Path("reports/benchmark"),
    )  # fmt: skip
    return ap


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop benchmark") -> int:
    import_from_cwd()  # a user\'s module:factory beside them, as python -m finds it

    ap = build_parser(prog)
    a = ap.parse_args(argv)
    args = argv_of(argv)
    try:
        st = settings_from_args(a, SETTINGS)
    except ValueError as exc:
        ap.error(str(exc))
    if a.print_suite:
        rc, text = run(prog, args, lambda: bm.suite_markdown(bm.load_suite(a.suite)))
        if not rc:
            print(text, end="")
        return rc
    cmd = " ".join([prog, *args])
    if a.merge:
        rc, _ = run(
            prog,
            args,
            lambda: bm.merge_runs(
                a.merge,
                st.out,
                overwrite=st.overwrite,
                figures=st.figures,
                n_boot_fragility=st.n_boot_fit,
                command=cmd,
            ),
        )
        if not rc:
            print(f"headline: {st.out / 'headline.md'} (merged from {len(a.merge)} runs)")
        return rc

    def job() -> dict:
        from agents.evaluation.studies import BenchmarkSpec
        from agents.evaluation.studies import run as run_study

        families = None if a.families is None else tuple(a.families)
        spec = BenchmarkSpec(tuple(a.entrants), tuple(a.conditions), families, a.suite)
        return run_study(spec, st, command=cmd)

    rc, res = run(prog, args, job, "--resume")
    if not rc:
        print(f"headline: {st.out / 'headline.md'} ({res['settings']['wall_s']:.0f} s)")
    return rc


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
