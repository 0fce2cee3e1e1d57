"""``python -m agents.reproduce_paper``: an alias of ``hyperloop paper``
(:mod:`agents.cli.paper`)."""

from agents.cli.common import import_from_cwd
from agents.cli.paper import main

if __name__ == "__main__":
    from agents.invocation import invoked_prog

    import_from_cwd()
    raise SystemExit(main(prog=invoked_prog("hyperloop paper")))
