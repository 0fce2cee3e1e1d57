"""The factories of the built-in controllers, named by the registry's entry points
(``"agents.controllers.factories:pid"`` …; :mod:`agents.controllers.registry`).

A factory takes the plant (a Gymnasium env of this package, ``ModelParams``,
``Simulator``, ``ControlContext`` or None for the default parameters) and keyword options
and returns a controller; each imports its controller module only when called (the
learned ones import torch only then, and need the ``train`` extra).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from agents.controllers.base import Controller
from agents.installation import require_data_file, require_extra

Factory = Callable[..., Controller]


def passive(env_or_params: Any = None, **kw: Any) -> Controller:
    """Constant bias currents (:class:`~agents.controllers.passive.PassiveController`)."""
    from agents.controllers.passive import PassiveController

    return PassiveController(env_or_params, **kw)


def pid(env_or_params: Any = None, **kw: Any) -> Controller:
    """Per-unit gap PID with the tuned design of ``pid_gains.json`` unless ``design=`` or
    ``gains=`` is given (:class:`~agents.controllers.pid.PIDController`)."""
    from agents.controllers.pid import GAINS_FILE, PIDController, load_design

    if kw.get("design") is None and kw.get("gains") is None:
        # the tuned design is package data: a missing file is an error, not other gains
        kw["design"] = load_design(require_data_file(GAINS_FILE, "the tuned PID design"))
    return PIDController(env_or_params, **kw)


def lqr(env_or_params: Any = None, **kw: Any) -> Controller:
    """LQR + steady-state Kalman filter (:class:`~agents.controllers.lqr.LQRController`)."""
    from agents.controllers.lqr import LQRController

    return LQRController(env_or_params, **kw)


def lqr_preview(env_or_params: Any = None, **kw: Any) -> Controller:
    """LQG with a preview of the guideway the front units measured, for the rear units
    (:class:`~agents.controllers.lqr_preview.LQRPreviewController`)."""
    from agents.controllers.lqr_preview import LQRPreviewController

    return LQRPreviewController(env_or_params, **kw)


def mpc(env_or_params: Any = None, **kw: Any) -> Controller:
    """Constrained linear MPC on the LQG's model and filter, solved with DAQP
    (:class:`~agents.controllers.mpc.MPCController`)."""
    from agents.controllers.mpc import MPCController

    return MPCController(env_or_params, **kw)


def mpc_preview(env_or_params: Any = None, **kw: Any) -> Controller:
    """``mpc`` with the rear units' preview of ``lqr-preview`` (weight
    :data:`~agents.controllers.lqr_preview.PREVIEW_WEIGHT` unless ``preview_weight=``)."""
    from agents.controllers.lqr_preview import PREVIEW_WEIGHT
    from agents.controllers.mpc import MPCController

    kw.setdefault("preview_weight", PREVIEW_WEIGHT)
    return MPCController(env_or_params, **kw)


def learned(name: str) -> Factory:
    """The factory of the learned registry entry ``name``: its shipped agent
    (``agents/shipped/<shipped>/``, the entry's metadata), or ``path=`` a train.py run
    directory."""

    def make(env_or_params: Any = None, **kw: Any) -> Controller:
        from agents.controllers.learned import make_learned
        from agents.controllers.registry import check_shipped, learned_spec

        require_extra("train", f"controller {name!r} (a trained Stable-Baselines3 agent)")
        if kw.get("path") is None:
            check_shipped(name)
        algo, folder = learned_spec(name) or (None, None)
        return make_learned(name, env_or_params, algo=algo, folder=folder, **kw)

    make.__doc__ = f"The trained {name!r} agent (shipped, or ``path=`` a run directory)."
    return make


ppo = learned("ppo")
ppo_memory = learned("ppo-memory")
sac = learned("sac")
ppo_guidance = learned("ppo-guidance")


def ppo_residual_guidance(env_or_params: Any = None, **kw: Any) -> Controller:
    """``lqr-preview+g`` plus the shipped PPO correction of ``agents/shipped/
    ppo-residual-guidance/`` (trained with a privileged critic; ``path=`` a run directory
    instead): :func:`agents.controllers.residual.make_residual`."""
    from agents.controllers.registry import check_shipped
    from agents.controllers.residual import ppo_residual_guidance as make

    require_extra("train", "controller 'ppo-residual-guidance' (a trained Stable-Baselines3 agent)")
    if kw.get("path") is None:
        check_shipped("ppo-residual-guidance")
    return make(env_or_params, **kw)
