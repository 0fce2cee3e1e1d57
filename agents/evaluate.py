"""``python -m agents.evaluate``: an alias of ``hyperloop evaluate``
(:mod:`agents.cli.evaluate`)."""

from agents.cli.common import import_from_cwd
from agents.cli.evaluate import main

if __name__ == "__main__":
    from agents.invocation import invoked_prog

    import_from_cwd()
    raise SystemExit(main(prog=invoked_prog("hyperloop evaluate")))
