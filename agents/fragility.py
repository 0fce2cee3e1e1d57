"""``python -m agents.fragility``: an alias of ``hyperloop fragility``
(:mod:`agents.cli.fragility`)."""

from agents.cli.common import import_from_cwd
from agents.cli.fragility import main

if __name__ == "__main__":
    from agents.invocation import invoked_prog

    import_from_cwd()
    raise SystemExit(main(prog=invoked_prog("hyperloop fragility")))
