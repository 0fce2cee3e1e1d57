"""Training: the SB3 adapter (:mod:`.sb3_adapter`), the experiment (:mod:`.experiment`),
presets as data files (:mod:`.presets`, ``presets/*.json``), shipping (:mod:`.shipping`)
and the command line of ``train.py`` (:mod:`.cli`). SB3 and torch are the ``train`` extra.

Importing the package pins torch's CPU numerics for cross-machine reproducibility
(:mod:`.numerics`); import it before torch.
"""

from agents.training.numerics import pin_cpu_numerics

pin_cpu_numerics()
