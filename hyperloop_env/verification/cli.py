"""``python -m hyperloop_env.verification [--json | --markdown] [--case NAME]``: an alias of
``hyperloop verify`` that needs nothing but this package.

The flags are declared here once (:func:`add_arguments`) and used by both commands; the
work is :func:`~hyperloop_env.verification.registry.run_all`,
:func:`~hyperloop_env.verification.report.render` and
:func:`~hyperloop_env.verification.registry.all_verified`.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from hyperloop_env.verification.registry import CASE_NAMES, all_verified, run_all
from hyperloop_env.verification.report import render

DESCRIPTION = (
    "Verification of the simulator against analytical and independent numerical references."
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The verification flags: ``--json``, ``--markdown``, ``--case NAME`` (repeatable)."""
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--markdown", action="store_true", help="print the README's Markdown table")
    parser.add_argument(
        "--case",
        action="append",
        choices=CASE_NAMES,
        metavar="NAME",
        help="run only this case (repeatable; an unknown name lists the cases)",
    )


def output_format(args: argparse.Namespace) -> str:
    """The format the parsed flags ask for (``--json`` before ``--markdown``)."""
    return "json" if args.json else "markdown" if args.markdown else "table"


def main(
    argv: Sequence[str] | None = None, prog: str = "python -m hyperloop_env.verification"
) -> int:
    """Exit code 0 if every case passes except the known failures (which must still
    fail), else 1."""
    ap = argparse.ArgumentParser(prog=prog, description=DESCRIPTION, allow_abbrev=False)
    add_arguments(ap)
    args = ap.parse_args(argv)
    results = run_all(args.case)
    print(render(results, output_format(args)))
    return 0 if all_verified(results) else 1
