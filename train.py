#!/usr/bin/env python
"""Train an RL suspension controller (PPO or SAC, Stable-Baselines3) and evaluate it: an
alias of ``hyperloop train`` (:mod:`agents.cli.train`) in a checkout.

    python train.py                               # PPO on the default scenario
    python train.py --preset shipped-ppo          # reproduces agents/shipped/ppo
    python train.py --help

The work is done by :mod:`agents.training` (experiment :mod:`agents.training.experiment`,
presets ``agents/training/presets/*.json``).
"""

import sys

from agents.cli.train import main

if __name__ == "__main__":
    sys.exit(main())
