"""``hyperloop verify``: the simulator's verification cases against analytical and
independent numerical references (:mod:`hyperloop_env.verification`; the flags are that
package's, declared once for this command and its alias
``python -m hyperloop_env.verification``). Exit status 0 if every case passes, apart from
the known failures, which must still fail; 1 otherwise."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from agents.cli.common import argv_of, new_parser, run
from hyperloop_env.verification.cli import DESCRIPTION, add_arguments, output_format


def build_parser(prog: str = "hyperloop verify") -> argparse.ArgumentParser:
    ap = new_parser(prog, DESCRIPTION)
    add_arguments(ap)
    return ap


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop verify") -> int:
    from hyperloop_env.verification import all_verified, render, run_all

    a = build_parser(prog).parse_args(argv)
    rc, results = run(prog, argv_of(argv), lambda: run_all(a.case))
    if rc:
        return rc
    print(render(results, output_format(a)))
    return 0 if all_verified(results) else 1
