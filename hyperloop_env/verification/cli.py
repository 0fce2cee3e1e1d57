"""Command line: ``python -m hyperloop_env.verification [--json | --markdown] [--case NAME]``."""

from __future__ import annotations

import argparse
import json

from hyperloop_env.verification.registry import CASE_NAMES, outcome, run_all
from hyperloop_env.verification.report import format_table, markdown_table, results_json

DESCRIPTION = (
    "Verification of the simulator against analytical and independent numerical references."
)


def main(argv: list[str] | None = None) -> int:
    """Exit code 0 if every case passes except the known failures (which must still
    fail), else 1."""
    ap = argparse.ArgumentParser(
        prog="python -m hyperloop_env.verification", description=DESCRIPTION
    )
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--markdown", action="store_true", help="print the README's Markdown table")
    ap.add_argument("--case", action="append", choices=CASE_NAMES, help="run only these")
    args = ap.parse_args(argv)
    results = run_all(args.case)
    if args.json:
        print(json.dumps(results_json(results), indent=2))
    elif args.markdown:
        print(markdown_table(results))
    else:
        print(format_table(results))
    ok = all(outcome(k, r) in ("PASS", "XFAIL") for k, r in results.items())
    return 0 if ok else 1
