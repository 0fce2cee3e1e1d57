"""``python -m hyperloop_env.verification [--json]``."""

import sys

from hyperloop_env.verification import main

sys.exit(main())
