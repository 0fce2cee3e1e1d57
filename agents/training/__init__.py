"""Training: the SB3 adapter (:mod:`.sb3_adapter`), the experiment (:mod:`.experiment`),
presets as data files (:mod:`.presets`, ``presets/*.json``), shipping (:mod:`.shipping`)
and the command line of ``train.py`` (:mod:`.cli`). SB3 and torch are the ``train`` extra.
"""
