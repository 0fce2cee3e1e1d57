"""``hyperloop calibrate``: calibrate the benchmark suite's severity levels on the passive
and PID baselines (:func:`agents.evaluation.calibration.run`), or rewrite the suite file
from a finished calibration (``--rewrite-suite``, no runs).

Its defaults are the files of a checkout: the report goes to ``docs/benchmark``
(``calibration.md``, ``calibration.json``, each family's sweep in ``calibration/``) and
the suite to ``agents/evaluation/benchmark_suite.json``. Outside a checkout pass ``--out``
and ``--suite-file``: an installed package's suite file is never written by default."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from agents.cli.common import argv_of, new_parser, run
from agents.cli.options import PARALLEL, add_settings, settings_from_args
from agents.evaluation import calibration as cal

SETTINGS = ("seeds", "distance_km", "out", "figures", *PARALLEL)
CHECKOUT_OUT = Path("docs") / "benchmark"
"""The default ``--out`` (in a checkout; identity tells it from a given ``--out``)."""
CHECKOUT_SUITE = Path("agents") / "evaluation" / "benchmark_suite.json"


def build_parser(prog: str = "hyperloop calibrate") -> argparse.ArgumentParser:
    ap = new_parser(
        prog,
        "Calibrate the benchmark suite's severity levels on the passive and PID baselines "
        f"(calibration seeds from {cal.CALIBRATION_SEED0}; never on a learned agent).",
        epilog=__doc__.split("\n\n")[1],
    )
    ap.add_argument(
        "--families",
        nargs="+",
        default=list(cal.GRIDS),
        choices=list(cal.GRIDS),
        metavar="FAMILY",
        help=f"families to calibrate (default: all: {', '.join(cal.GRIDS)}); an earlier "
        "calibration's other families in --out are kept",
    )
    ap.add_argument(
        "--suite-file",
        type=Path,
        default=None,
        help=f"the suite file to write (default in a checkout: {CHECKOUT_SUITE})",
    )
    ap.add_argument(
        "--rewrite-suite",
        type=Path,
        default=None,
        metavar="CALIBRATION_JSON",
        help="no runs: rewrite the suite file from a calibration.json (pass the --seeds and "
        "--distance-km it was calibrated with)",
    )
    add_settings(
        ap, SETTINGS, seeds=cal.DEFAULT_SEEDS, distance_km=cal.DEFAULT_DISTANCE_KM,
        out=CHECKOUT_OUT,
    )  # fmt: skip
    return ap


def _in_checkout() -> bool:
    return CHECKOUT_SUITE.is_file() and Path("pyproject.toml").is_file()


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop calibrate") -> int:
    ap = build_parser(prog)
    a = ap.parse_args(argv)
    args = argv_of(argv)
    given = {"--out": a.out is not CHECKOUT_OUT or a.rewrite_suite, "--suite-file": a.suite_file}
    defaults = [flag for flag, value in given.items() if not value]
    if defaults and not _in_checkout():
        ap.error(f"not in a checkout (no {CHECKOUT_SUITE} here): pass {' and '.join(defaults)}")
    suite_file = a.suite_file or CHECKOUT_SUITE
    try:
        st = settings_from_args(a, SETTINGS)
        spec = cal.CalibrationSpec(
            seeds=st.seeds, distance_km=st.distance_km, families=tuple(a.families)
        )
    except ValueError as exc:
        ap.error(str(exc))
    if a.rewrite_suite is not None:
        src = a.rewrite_suite
        rc, _ = run(
            prog, args, lambda: cal.rewrite_suite(src, suite_file, st.seeds, st.distance_km)
        )
        if not rc:
            print(f"wrote {suite_file}")
        return rc
    rc, _ = run(
        prog,
        args,
        lambda: cal.run(
            spec,
            st.out,
            suite_file,
            workers=st.workers,
            backend=st.backend,
            address=st.address,
            figures=st.figures,
            log=lambda line: print(line, flush=True),
        ),
    )
    if not rc:
        print(f"wrote {suite_file} and {st.out / 'calibration.md'}")
    return rc
