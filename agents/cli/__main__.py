"""``python -m agents.cli``: the ``hyperloop`` command."""

from agents.cli import main

raise SystemExit(main())
