"""``python -m agents.capacity``: an alias of ``hyperloop capacity``
(:mod:`agents.cli.capacity`)."""

from agents.cli.capacity import main
from agents.cli.common import import_from_cwd

if __name__ == "__main__":
    from agents.invocation import invoked_prog

    import_from_cwd()
    raise SystemExit(main(prog=invoked_prog("hyperloop capacity")))
