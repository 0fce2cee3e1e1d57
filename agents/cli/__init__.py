"""``hyperloop``: one command, one subcommand per study.

Each subcommand is a thin module of this package (parse → settings and spec → the study's
library function → the report); the studies themselves live in :mod:`agents.evaluation`,
:mod:`agents.training` and :mod:`hyperloop_env.verification` and never import this package.
``hyperloop-<name>`` console scripts and ``python -m agents.<name>`` remain as aliases of
the subcommands.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Sequence

SUBCOMMANDS: dict[str, tuple[str, str]] = {
    "train": ("agents.cli.train", "train an agent (PPO / SAC) on the env"),
    "tune": ("agents.cli.tune", "PID design, preview weight, a preset from an agent search"),
    "checkpoints": ("agents.cli.checkpoints", "a training run's checkpoints on validation seeds"),
    "evaluate": ("agents.cli.evaluate", "STS, RMS, contacts and comfort of controllers"),
    "fragility": ("agents.cli.fragility", "contact probability vs one family's severity"),
    "benchmark": ("agents.cli.benchmark", "the suite's fragility grid for every entrant"),
    "capacity": ("agents.cli.capacity", "per-seed capacities and paired verdicts (headline)"),
    "headline": ("agents.cli.headline", "publish a capacity run as the project's headline"),
    "score": ("agents.cli.score", "score one controller against the published benchmark"),
    "leaderboard": ("agents.cli.leaderboard", "admit a score to the leaderboard, or show it"),
    "paper": ("agents.cli.paper", "reproduce the paper's STS results and sweeps"),
    "calibrate": ("agents.cli.calibrate", "calibrate the benchmark suite's levels (baselines)"),
    "compare": ("agents.cli.compare", "learned vs classical target, ride comfort, run cost"),
    "verify": ("agents.cli.verify", "the model's verification cases"),
}
"""name -> (module, one-line description)."""


def usage() -> str:
    width = max(map(len, SUBCOMMANDS))
    lines = [f"  {name:<{width}}  {desc}" for name, (_, desc) in SUBCOMMANDS.items()]
    return (
        "usage: hyperloop <subcommand> [options]   (hyperloop <subcommand> --help)\n\n"
        "Hyperloop magnetic suspension: simulator, controllers and benchmark.\n\n"
        "subcommands:\n" + "\n".join(lines) + "\n"
    )


def main(argv: Sequence[str] | None = None) -> int:
    """The ``hyperloop`` command (module docstring)."""
    from agents.cli.common import import_from_cwd

    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ("-h", "--help"):
        print(usage(), end="")
        return 0
    name, rest = args[0], args[1:]
    if name not in SUBCOMMANDS:
        print(usage(), end="", file=sys.stderr)
        print(f"hyperloop: error: unknown subcommand {name!r}", file=sys.stderr)
        return 2
    import_from_cwd()
    module = importlib.import_module(SUBCOMMANDS[name][0])
    return int(module.main(rest, prog=f"hyperloop {name}") or 0)
