"""``python -m hyperloop_env.verification [--json]``."""

import sys

from hyperloop_env.verification.cli import main

sys.exit(main())
