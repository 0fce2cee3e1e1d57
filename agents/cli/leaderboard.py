"""``hyperloop leaderboard``: ``add RESULT.json`` admits a ``hyperloop score`` result to
the board (refused if scored with another fingerprint), ``show`` prints the board
(:mod:`agents.evaluation.leaderboard`)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from agents.cli.common import argv_of, new_parser, run

BOARD = Path("docs") / "leaderboard"


def build_parser(prog: str = "hyperloop leaderboard") -> argparse.ArgumentParser:
    ap = new_parser(prog, (__doc__ or "").split("\n\n")[0].replace("``", ""))
    sub = ap.add_subparsers(dest="mode", required=True)
    add = sub.add_parser("add", help="admit a score result to the board")
    add.add_argument("result", type=Path, help="a score.json written by hyperloop score")
    add.add_argument(
        "--replace", action="store_true", help="replace the controller's entry on the board"
    )
    add.add_argument(
        "--readme",
        type=Path,
        default=Path("README.md"),
        help="the README whose leaderboard block is refreshed (if it has one)",
    )
    show = sub.add_parser("show", help="print the board as Markdown")
    for p in (add, show):
        p.add_argument(
            "--board", type=Path, default=BOARD, help="the board folder (default: %(default)s)"
        )
    return ap


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop leaderboard") -> int:
    from agents.evaluation import leaderboard as lb

    a = build_parser(prog).parse_args(argv)
    args = argv_of(argv)
    if a.mode == "add":
        rc, target = run(prog, args, lambda: lb.add(a.result, a.board, overwrite=a.replace))
        if not rc:
            print(f"added: {target}")
            if lb.update_readme(a.readme, a.board):
                print(f"{a.readme}: leaderboard block refreshed")
        return rc
    rc, text = run(prog, args, lambda: lb.table(a.board))
    if not rc:
        sys.stdout.write(text)
    return rc
