"""Training: the SB3 adapter (:mod:`.sb3_adapter`), the experiment (:mod:`.experiment`),
presets as data files (:mod:`.presets`, ``presets/*.json``) and shipping
(:mod:`.shipping`); its command line is ``hyperloop train`` (:mod:`agents.cli.train`, alias
``python train.py``). SB3 and torch are the ``train`` extra.

Importing the package pins torch's CPU numerics for cross-machine reproducibility
(:mod:`.numerics`); import it before torch.
"""

from agents.training.numerics import pin_cpu_numerics

pin_cpu_numerics()
