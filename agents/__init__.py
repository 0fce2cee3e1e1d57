"""Controllers, their evaluation and training for hyperloop-suspension-gym.

>>> from agents import make_controller
>>> ctrl = make_controller("pid")          # default ModelParams; or pass the env
>>> ctrl.reset(seed=0)

Subpackages (imports flow controllers ← evaluation, controllers ← training):

* :mod:`agents.controllers` — protocol, registry, passive / PID / LQR, trained-agent loader;
* :mod:`agents.evaluation` — rollouts, STS evaluation (``python -m agents.evaluate``),
  paper reproduction (``python -m agents.reproduce_paper``), reports and figures;
* :mod:`agents.training` — the SB3 adapter, the experiment (``train.py``) and its presets.
"""

from agents.controllers import (
    ControlContext,
    Controller,
    PassiveController,
    available_controllers,
    control_context,
    make_controller,
    register_controller,
)

__all__ = [
    "ControlContext",
    "Controller",
    "PassiveController",
    "available_controllers",
    "control_context",
    "make_controller",
    "register_controller",
]
