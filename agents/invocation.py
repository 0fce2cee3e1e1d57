"""The name a command-line tool was started by, for its usage line and messages.

The tools run as console scripts (``hyperloop-train``, ``hyperloop-evaluate``, … in
``pyproject.toml``), as ``python -m agents.<module>`` or, for training, as
``python train.py`` in a checkout; each prints the name it was invoked by, so that a
command it suggests (``--resume``, ``--eval-only``) can be pasted back.
"""

from __future__ import annotations

import os
import shlex
import sys
from collections.abc import Sequence

CONSOLE_SCRIPTS: tuple[str, ...] = (
    "hyperloop",
    "hyperloop-train",
    "hyperloop-evaluate",
    "hyperloop-fragility",
    "hyperloop-benchmark",
    "hyperloop-capacity",
)
"""The ``[project.scripts]`` of ``pyproject.toml`` (tests check the two agree)."""

_PACKAGES = ("agents", "hyperloop_env")


DISPATCHERS = ("hyperloop", "python -m agents.cli")
"""The names of the ``hyperloop`` command, whose first argument is a subcommand."""


def invoked_prog(default: str) -> str:
    """The name this process was started by: the console script (``hyperloop-train``),
    ``hyperloop <subcommand>`` (``hyperloop train``), ``python -m <module>`` for one of
    this project's modules, or the script's file name (``train.py``); ``default`` when none
    of these started it (``main()`` called from other code: tests, notebooks, a user's
    runner)."""
    return _invocation(default)[0]


def invoked_args() -> list[str]:
    """The arguments given to :func:`invoked_prog`'s command (after the subcommand of
    ``hyperloop <subcommand>``), so that ``command_line(invoked_prog(…), invoked_args())``
    is the command that was typed."""
    return _invocation("")[1]


def _invocation(default: str) -> tuple[str, list[str]]:
    prog = _started_by(default)
    args = list(sys.argv[1:])
    if prog in DISPATCHERS and args and not args[0].startswith("-"):
        return f"{prog} {args[0]}", args[1:]
    return prog, args


def _started_by(default: str) -> str:
    main = sys.modules.get("__main__")
    spec = getattr(main, "__spec__", None)
    name = getattr(spec, "name", None) or ""
    if name.split(".")[0] in _PACKAGES:
        return f"python -m {name.removesuffix('.__main__')}"
    argv0 = sys.argv[0] if sys.argv and sys.argv[0] else ""
    base = os.path.basename(argv0)
    for suffix in (".exe", "-script.py", "-script.pyw"):  # Windows launchers
        base = base.removesuffix(suffix)
    if base in CONSOLE_SCRIPTS:
        return base
    main_file = getattr(main, "__file__", None)
    if spec is None and main_file and base.endswith(".py") and _same_file(argv0, main_file):
        return base
    return default


def command_line(prog: str, args: Sequence[str]) -> str:
    """The command to type: ``prog`` (``python train.py`` for a script) and the arguments,
    quoted for a POSIX shell."""
    head = f"python {prog}" if prog.endswith(".py") else prog
    return " ".join([head, *(shlex.quote(a) for a in args)])


def _same_file(a: str, b: str) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def interrupted(prog: str, args: Sequence[str], resume_flag: str | None = None) -> int:
    """After Ctrl-C: one line on stderr (no traceback) — what was kept and, for a tool that
    can continue (``resume_flag``), the command that does; returns 130 (128 + SIGINT), the
    shell's exit status for a run stopped by Ctrl-C."""
    msg = f"{prog}: interrupted"
    if resume_flag is not None:
        again = [a for a in args if a not in ("--overwrite", resume_flag)] + [resume_flag]
        msg += f"; finished work is kept: continue with\n  {command_line(prog, again)}"
    print(msg, file=sys.stderr)
    return 130
