"""``python -m agents.benchmark``: an alias of ``hyperloop benchmark``
(:mod:`agents.cli.benchmark`)."""

from agents.cli.benchmark import main
from agents.cli.common import import_from_cwd

if __name__ == "__main__":
    from agents.invocation import invoked_prog

    import_from_cwd()
    raise SystemExit(main(prog=invoked_prog("hyperloop benchmark")))
