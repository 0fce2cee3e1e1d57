"""Controller registry: ``make_controller(name, env_or_params)``.

Built-ins: ``passive`` (constant bias currents), ``pid`` (per-unit gap PID, pole
placement), ``lqr`` (LQR + steady-state Kalman filter), ``ppo`` / ``sac`` (trained
Stable-Baselines3 agents: the one shipped in ``agents/shipped/``, or ``path=`` a
``train.py`` run; :mod:`agents.controllers.learned`, torch imported only when asked for;
they need the ``train`` extra, and without it ``make_controller("ppo")`` raises one
:class:`~agents.installation.MissingExtraError` naming ``pip install
"hyperloop-suspension-gym[train]"``). No SAC agent is shipped: ``sac`` needs ``path=``, and
the command-line tools offer only :func:`offered_controllers`.
A user's controller plugs in the same way::

    from agents import register_controller
    register_controller("mine", lambda env_or_params, **kw: MyController(env_or_params, **kw))

A factory receives the environment (or ``ModelParams``/``Simulator``/``ControlContext``)
and keyword options, and returns an object satisfying :class:`agents.controllers.base.Controller`.
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

from agents.controllers.base import Controller
from agents.installation import (
    missing_extra_message,
    missing_modules,
    require_data_file,
    require_extra,
)

Factory = Callable[..., Controller]


def _passive(env_or_params: Any = None, **kw: Any) -> Controller:
    from agents.controllers.passive import PassiveController

    return PassiveController(env_or_params, **kw)


def _pid(env_or_params: Any = None, **kw: Any) -> Controller:
    from agents.controllers.pid import GAINS_FILE, PIDController, load_design

    if kw.get("design") is None and kw.get("gains") is None:
        # the tuned design is package data: a missing file is an error, not other gains
        kw["design"] = load_design(require_data_file(GAINS_FILE, "the tuned PID design"))
    return PIDController(env_or_params, **kw)


def _lqr(env_or_params: Any = None, **kw: Any) -> Controller:
    from agents.controllers.lqr import LQRController

    return LQRController(env_or_params, **kw)


def _learned(algo: str) -> Factory:
    def make(env_or_params: Any = None, **kw: Any) -> Controller:
        """A trained Stable-Baselines3 agent: the shipped one, or ``path=`` a train.py run
        directory (imports torch only when asked for)."""
        from agents.controllers.learned import make_learned

        require_extra("train", f"controller {algo!r} (a trained Stable-Baselines3 agent)")
        if kw.get("path") is None:
            _check_shipped(algo)
        return make_learned(algo, env_or_params, **kw)

    make.learned_name = algo  # type: ignore[attr-defined]
    return make


SHIPPED_FILES = ("model.zip", "vecnormalize.pkl", "training_log.json")
"""The files of a shipped agent (``agents/shipped/<name>/``) that loading it reads."""


def _check_shipped(name: str) -> None:
    """A shipped agent is package data: a missing file of it is an error naming the file
    (not an agent with unnormalised observations or another action set)."""
    from agents.controllers.learned import MODEL_FILE, learned_spec, shipped_path

    spec = learned_spec(name)
    folder = shipped_path(spec[1] if spec else name)
    if not (folder / MODEL_FILE).is_file():
        return  # not shipped at all: make_learned says so (and how to train one)
    for f in SHIPPED_FILES:
        require_data_file(folder / f, f"the shipped {name!r} agent")


_REGISTRY: dict[str, Factory] = {
    "passive": _passive,
    "pid": _pid,
    "lqr": _lqr,
    "ppo": _learned("ppo"),
    "sac": _learned("sac"),
    "ppo-guidance": _learned("ppo-guidance"),
}


def register_controller(name: str, factory: Factory, *, overwrite: bool = False) -> None:
    """Register ``factory(env_or_params, **kwargs) -> Controller`` under ``name``."""
    if not isinstance(name, str) or not name:
        raise ValueError(f"controller name must be a non-empty string, got {name!r}")
    if not callable(factory):
        raise ValueError(f"factory must be callable, got {factory!r}")
    if name in _REGISTRY and not overwrite:
        raise ValueError(f"controller {name!r} is already registered (pass overwrite=True)")
    _REGISTRY[name] = factory


_ENTRY_POINT = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_][\w.]*$")


def is_entry_point(name: str) -> bool:
    """``name`` is a user's controller given as ``"package.module:factory"`` or as the path
    of a saved Stable-Baselines3 model (``.../model.zip``, or a run directory holding one)."""
    if not isinstance(name, str) or name in _REGISTRY:
        return False
    if _ENTRY_POINT.match(name):
        return True
    p = Path(name)
    return p.suffix == ".zip" or (p.is_dir() and (p / "model.zip").is_file())


def _resolve(name: str) -> Factory:
    """The factory of a registry name or of an entry point (:func:`is_entry_point`); a
    name that cannot be built raises ``ValueError`` in one line. Entry points are resolved
    by import in the process that builds the controller, so they reach spawned and Ray
    workers (which import the module themselves) with no registration."""
    if name in _REGISTRY:
        return _REGISTRY[name]
    if not isinstance(name, str):
        raise ValueError(f"controller must be a name, got {name!r}")
    if _ENTRY_POINT.match(name):
        mod_name, _, attr = name.partition(":")
        try:
            obj: Any = importlib.import_module(mod_name)
        except ImportError as exc:
            raise ValueError(f"controller {name!r}: cannot import {mod_name!r} ({exc})") from None
        for part in attr.split("."):
            obj = getattr(obj, part, None)
            if obj is None:
                raise ValueError(f"controller {name!r}: {mod_name!r} has no {attr!r}")
        if not callable(obj):
            raise ValueError(f"controller {name!r}: {attr!r} is not callable")
        return obj
    p = Path(name)
    if p.suffix == ".zip" or p.is_dir():
        model = p if p.suffix == ".zip" else p / "model.zip"
        if not model.is_file():
            raise ValueError(f"controller {name!r}: no Stable-Baselines3 model at {model}")

        def make(env_or_params: Any = None, **kw: Any) -> Controller:
            require_extra("train", f"controller {name!r} (a saved Stable-Baselines3 model)")
            from agents.controllers.learned import SB3Controller, _check_plant

            ctrl = SB3Controller(model, name=kw.pop("name", name), **kw)
            _check_plant(ctrl, env_or_params)
            return ctrl

        return make
    raise ValueError(
        f"unknown controller {name!r}; available: {offered_controllers()}, or "
        "'package.module:factory', or the path of a saved model.zip"
    )


def available_controllers() -> list[str]:
    """Names accepted by :func:`make_controller`."""
    return sorted(_REGISTRY)


def _is_learned(name: str) -> bool:
    """A registry name built by the trained-agent factory (not a user's override)."""
    return getattr(_REGISTRY.get(name), "learned_name", None) is not None


def _is_shipped(name: str) -> bool:
    from agents.controllers.learned import MODEL_FILE, learned_spec, shipped_path

    spec = learned_spec(name)
    return spec is not None and (shipped_path(spec[1]) / MODEL_FILE).is_file()


def controller_problem(name: str, kwargs: dict[str, Any] | None = None) -> str | None:
    """Why ``make_controller(name, **kwargs)`` cannot build ``name`` here, in one line (an
    unknown name, a learned agent that is neither shipped nor given a ``path``, the
    ``train`` extra missing for a learned agent), or None; for validating a command line
    before any work starts."""
    if name not in _REGISTRY:
        try:
            _resolve(name)
        except ValueError as exc:
            return str(exc)
        if not _ENTRY_POINT.match(name):
            miss = missing_modules("train")
            if miss:
                return missing_extra_message("train", f"controller {name!r}", miss)
        return None
    if not _is_learned(name):
        return None
    if (kwargs or {}).get("path") is None and not _is_shipped(name):
        from agents.controllers.learned import MODEL_FILE, learned_spec, shipped_path

        where = shipped_path(learned_spec(name)[1]) / MODEL_FILE
        return (
            f"controller {name!r}: no agent of it is shipped ({where} does not exist); "
            f"controllers available here: {offered_controllers()}"
        )
    miss = missing_modules("train")
    if miss:
        return missing_extra_message("train", f"controller {name!r}", miss)
    return None


def offered_controllers() -> list[str]:
    """The names the command-line tools offer: the registry's, less the learned ones that
    are not shipped (``sac``: ``make_controller("sac", path=run_dir)`` takes a run)."""
    return [n for n in available_controllers() if not _is_learned(n) or _is_shipped(n)]


def make_controller(name: str, env_or_params: Any = None, **kwargs: Any) -> Controller:
    """Build the controller registered as ``name`` — or given as an entry point
    ``"package.module:factory"`` or the path of a saved SB3 ``model.zip``
    (:func:`is_entry_point`) — for the plant ``env_or_params`` (a Gymnasium env of this
    package, ``ModelParams``, ``Simulator``, ``ControlContext`` or None for the default
    parameters)."""
    ctrl = _resolve(name)(env_or_params, **kwargs)
    for attr in ("reset", "act"):
        if not callable(getattr(ctrl, attr, None)):
            raise TypeError(f"controller {name!r} has no callable {attr}()")
    return ctrl
