"""Controllers for hyperloop-suspension-gym and their evaluation.

>>> from agents import make_controller
>>> ctrl = make_controller("pid")          # default ModelParams; or pass the env
>>> ctrl.reset(seed=0)

See :mod:`agents.base` (protocol), :mod:`agents.registry`, :mod:`agents.evaluate`.
"""

from agents.base import ControlContext, Controller, PassiveController, control_context
from agents.registry import available_controllers, make_controller, register_controller

__all__ = [
    "ControlContext",
    "Controller",
    "PassiveController",
    "available_controllers",
    "control_context",
    "make_controller",
    "register_controller",
]
