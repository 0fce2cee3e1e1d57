"""What every subcommand does the same way: its parser, the current directory on the import
path, and how a run ends (an error line and exit 2, Ctrl-C with one line, SIGTERM with a
clean exit)."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Sequence
from typing import Any

from agents.evaluation.outputs import OutputDirError


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """The description as written; the default of every option that takes a value in its
    help (a switch's help says what it switches; a help that names its default keeps it)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        takes_value = action.nargs != 0 and action.option_strings
        if takes_value and "default" not in text and action.default is not argparse.SUPPRESS:
            text += " (default: %(default)s)"
        return text


def new_parser(prog: str, description: str, epilog: str | None = None) -> argparse.ArgumentParser:
    """A subcommand's parser: no abbreviated flags (a flag is given whole or refused), every
    default shown in ``--help``."""
    return argparse.ArgumentParser(
        prog=prog,
        description=description,
        epilog=epilog,
        allow_abbrev=False,
        formatter_class=HelpFormatter,
    )


def import_from_cwd() -> None:
    """Put the current directory first on the import path, as ``python -m`` does, so that
    ``--controllers mypkg.mod:make`` finds a package beside the user (a console script
    starts with its own folder there instead)."""
    cwd = os.getcwd()
    if cwd not in sys.path and "" not in sys.path:
        sys.path.insert(0, cwd)


def argv_of(argv: Sequence[str] | None) -> list[str]:
    return list(sys.argv[1:] if argv is None else argv)


def run(
    prog: str,
    args: Sequence[str],
    job: Callable[[], Any],
    resume_flag: str | None = None,
) -> tuple[int, Any]:
    """``(0, job())``; or, without a traceback: ``SystemExit(2)`` after an error line naming
    the problem (a bad value, a busy or foreign folder, a missing extra: a usage error, as
    argparse's own), ``(130, None)`` after Ctrl-C (one line; for a resumable study the
    command that continues it) and exit 143 on SIGTERM (workers stopped, temporary files
    removed, the folder's lock released)."""
    from agents.evaluation.backends import sigterm_exits
    from agents.invocation import interrupted

    try:
        with sigterm_exits():
            return 0, job()
    except KeyboardInterrupt:
        return interrupted(prog, args, resume_flag), None
    except (OutputDirError, ValueError, FileExistsError, FileNotFoundError, ImportError) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
