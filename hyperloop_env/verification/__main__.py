"""``python -m hyperloop_env.verification [--json]``: an alias of ``hyperloop verify``."""

import sys

from hyperloop_env.verification.cli import main

sys.exit(main())
