"""Controllers: the protocol, the registry and the built-in baselines.

``passive`` (:mod:`.passive`), ``pid`` (:mod:`.pid`), ``lqr`` (:mod:`.lqr`; design models in
:mod:`.linear`) and trained agents (:mod:`.learned`). Controllers see the plant only
through :class:`~agents.controllers.base.ControlContext` and the observation. A controller
that cannot be built or acts wrongly raises :class:`~agents.controllers.base.ControllerError`
(a ``ValueError``) naming it.
"""

from agents.controllers.base import (
    BaseController,
    ControlContext,
    Controller,
    ControllerError,
    checked_controller,
    control_context,
)
from agents.controllers.passive import PassiveController
from agents.controllers.registry import (
    available_controllers,
    make_controller,
    register_controller,
)

__all__ = [
    "BaseController",
    "ControlContext",
    "Controller",
    "ControllerError",
    "PassiveController",
    "available_controllers",
    "checked_controller",
    "control_context",
    "make_controller",
    "register_controller",
]
