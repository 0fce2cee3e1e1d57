"""The controller protocol and the context a controller is built from.

Every controller (built-in or a user's) is a small object with::

    name: str
    reset(seed: int | None = None) -> None         # start of an episode
    act(obs: np.ndarray) -> np.ndarray             # obs (obs_size,) -> action [-1, 1]^n float32
    act_batch(obs: np.ndarray) -> np.ndarray       # optional: (N, obs_size) -> (N, n)

Observations and actions follow :mod:`hyperloop_env.observation` (the contract): the
action maps to the coil currents ``I = I0·(1 + action_scale·a)``. A controller that needs
the physics (gains designed from the model) receives a :class:`ControlContext`, built by
:func:`control_context` from a Gymnasium environment, a ``Simulator`` or ``ModelParams``:
the model parameters, the actuator set, and the observation layout with a typed view in
physical units (``ctx.view(obs)``). Controllers never read the simulator's internal arrays.

A controller that cannot be built, or that acts wrongly, raises :class:`ControllerError`
(a ``ValueError``) naming it and, where there is one, its file: the command-line tools print
it in one line (``error: …``, exit status 2). :func:`checked_controller` wraps a controller
so that an action of the wrong shape, NaN or infinite, is such an error naming the control
step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numba as nb
import numpy as np
from numba.core import types
from numba.extending import overload

from hyperloop_env.observation import (
    NO_MEMORY,
    MemorySpec,
    ObservationScales,
    ObservationSpec,
    ObservationView,
    observation_spec,
)
from hyperloop_env.physics.actuators import ActuatorSet
from hyperloop_env.physics.arrays import FLOAT32
from hyperloop_env.physics.model import equilibrium_current_A, guidance_bias_A
from hyperloop_env.physics.params import ModelParams
from hyperloop_env.physics.simulator import Simulator


@runtime_checkable
class Controller(Protocol):
    """What the evaluation runner needs from a controller."""

    name: str

    def reset(self, seed: int | None = None) -> None: ...

    def act(self, obs: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class ControlContext:
    """Everything a model-based controller may know about the plant (no hidden state).

    ``params`` are the episode's model parameters (speed, magnet orientation, coil lag …);
    ``nominal_current_A`` is I0 and ``action_scale`` the action map's scale; ``memory``
    the observation's memory options (the env's ``observation_history`` and
    ``observation_front_preview``: blocks appended after the plain observation)."""

    params: ModelParams
    nominal_current_A: float
    action_scale: float = 1.0
    memory: MemorySpec = NO_MEMORY

    @property
    def actuators(self) -> ActuatorSet:
        return self.params.actuators

    @property
    def n_actions(self) -> int:
        return self.params.actuators.size

    @property
    def observation(self) -> ObservationSpec:
        """Layout of the observation (named slices)."""
        return observation_spec(self.params.actuators, self.memory)

    @property
    def scales(self) -> ObservationScales:
        m = self.params.magnet
        return ObservationScales(
            clearance_m=m.clearance_m,
            lateral_clearance_m=self.params.guidance.clearance_m,
            gravity_m_s2=self.params.simulation.gravity_m_s2,
            nominal_current_A=self.nominal_current_A,
        )

    def view(self, obs: Any) -> ObservationView:
        """One observation in physical units (gaps [m], rates [m/s], currents [A], …)."""
        return self.observation.view(obs, self.scales)

    @property
    def guidance_bias_A(self) -> float:
        """I_g0: the guidance magnets' bias current [A] (design rule of GuidanceParams)."""
        return guidance_bias_A(self.params)

    @property
    def dt_s(self) -> float:
        return self.params.simulation.control_dt_s

    @property
    def clearance_m(self) -> float:
        return self.params.magnet.clearance_m

    @property
    def coil_time_constant_s(self) -> float:
        return self.params.magnet.coil_time_constant_s

    @property
    def max_current_A(self) -> float:
        return self.params.magnet.max_current_A

    @property
    def gravity_m_s2(self) -> float:
        return self.params.simulation.gravity_m_s2

    def action_limits(self) -> tuple[float, float]:
        """Action range that keeps the commanded current inside [0, I_max] and [-1, 1]."""
        i0, k = self.nominal_current_A, self.action_scale
        lo = max(-1.0, -1.0 / k)
        hi = min(1.0, (self.max_current_A / i0 - 1.0) / k)
        return lo, hi


def control_context(env_or_params: Any = None, action_scale: float | None = None) -> ControlContext:
    """A :class:`ControlContext` from a Gymnasium env (wrapped or not; its current episode's
    parameters), the native vector env (its configuration's nominal parameters), a
    ``Simulator``, ``ModelParams``, a ``ControlContext`` or None (defaults)."""
    if isinstance(env_or_params, ControlContext):
        ctx = env_or_params
        if action_scale is None:
            return ctx
        return ControlContext(ctx.params, ctx.nominal_current_A, float(action_scale), ctx.memory)
    scale = 1.0
    memory = NO_MEMORY
    if env_or_params is None:
        params = ModelParams()
    elif isinstance(env_or_params, ModelParams):
        params = env_or_params
    elif isinstance(env_or_params, Simulator):
        params = env_or_params.params
    elif hasattr(env_or_params, "num_envs") and hasattr(
        getattr(env_or_params, "unwrapped", env_or_params), "env_config"
    ):  # the native vector env: its rows' nominal model (each row's episode may differ)
        res = getattr(env_or_params, "unwrapped", env_or_params).env_config.resolve()
        params = res.base
        scale = float(res.action_scale)
        memory = res.config.memory
    elif hasattr(env_or_params, "unwrapped") and hasattr(env_or_params.unwrapped, "sim"):
        u = env_or_params.unwrapped
        params = u.sim.params
        scale = float(getattr(u, "action_scale", 1.0))
        memory = _env_memory(u)
    elif hasattr(env_or_params, "sim") and isinstance(env_or_params.sim, Simulator):
        params = env_or_params.sim.params
        scale = float(getattr(env_or_params, "action_scale", 1.0))
        memory = _env_memory(env_or_params)
    else:
        raise ValueError(
            "env_or_params must be a gymnasium env of HyperloopSuspension, a Simulator, "
            f"ModelParams, a ControlContext or None, got {type(env_or_params).__name__}"
        )
    if action_scale is not None:
        scale = float(action_scale)
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"action_scale must be a finite number > 0, got {scale!r}")
    return ControlContext(params, equilibrium_current_A(params), scale, memory)


def _env_memory(env: Any) -> MemorySpec:
    """The memory options of an environment's observation (none for a foreign env)."""
    spec = getattr(env, "observation_spec", None)
    return getattr(spec, "memory", NO_MEMORY)


def check_obs(obs: np.ndarray, size: int) -> np.ndarray:
    """Validate one observation (shape (size,)) and return it as float64."""
    arr = np.asarray(obs, dtype=np.float64)
    if arr.shape != (size,):
        raise ValueError(f"obs must have shape ({size},), got {arr.shape}")
    return arr


class ControllerError(ValueError):
    """A controller cannot be built (its model file is unreadable, its factory failed or
    returned no controller, it does not fit the plant) or returned an invalid action; the
    message names the controller and, where there is one, the file."""


class ControllerOptionError(ControllerError, TypeError):
    """A controller's factory refused its keyword options (a ``TypeError`` too, as an
    unexpected keyword argument is in Python)."""


class ControllerFileError(ControllerError, FileNotFoundError):
    """A file the controller needs does not exist (a ``FileNotFoundError`` too)."""


def controller_error(name: str, exc: BaseException, where: str = "") -> ControllerError:
    """``exc`` (raised while building the controller ``name``) as a :class:`ControllerError`
    of the same kind (an option refused: :class:`ControllerOptionError`; a missing file:
    :class:`ControllerFileError`), its message naming the controller unless it does already,
    and ``where`` (its factory, its file) if given. The caller chains it (``from exc``)."""
    if isinstance(exc, ControllerError):
        return exc
    text = str(exc) if isinstance(exc, ValueError | OSError) else f"{type(exc).__name__}: {exc}"
    at = f" ({where})" if where else ""
    text = f"{text}{at}" if repr(name) in text else f"controller {name!r}{at}: {text}"
    if isinstance(exc, TypeError):
        return ControllerOptionError(text)
    if isinstance(exc, FileNotFoundError):
        return ControllerFileError(text)
    return ControllerError(text)


def controller_shape_problem(ctrl: Any) -> str | None:
    """Why ``ctrl`` is not a controller (no callable ``reset()`` / ``act()``), or None."""
    if ctrl is None:
        return "returned None, not a controller"
    missing = [a for a in ("reset", "act") if not callable(getattr(ctrl, a, None))]
    if missing:
        names = " and ".join(f"{a}()" for a in missing)
        return f"returned a {type(ctrl).__name__}, not a controller (no callable {names})"
    return None


class CheckedController:
    """A controller whose every action is checked: the shape ``(n_actions,)`` (``act``) or
    ``(rows, n_actions)`` (``act_batch``) and finite entries; anything else raises
    :class:`ControllerError` naming the controller (``label``), the control step of the run
    (counted from the last reset) and the expected shape. Everything else is the wrapped
    controller's (attributes are forwarded); it has ``act_batch`` / ``reset_batch`` only if
    the wrapped controller has ``act_batch`` (:func:`checked_controller`)."""

    def __init__(self, controller: Any, label: str, n_actions: int) -> None:
        self.controller = controller
        self.label = label
        self.n_actions = int(n_actions)
        # control steps since each row's reset: _count − _reset_at[row]
        self._count = 0
        self._reset_at = np.zeros(1, dtype=np.int64)
        self._batch_shape = (1, self.n_actions)  # (rows of _reset_at, n_actions)

    def __getattr__(self, attr: str) -> Any:
        if attr == "controller":  # not set yet (copying, unpickling)
            raise AttributeError(attr)
        return getattr(self.controller, attr)

    @property
    def name(self) -> str:
        return getattr(self.controller, "name", type(self.controller).__name__)

    def reset(self, seed: int | None = None) -> None:
        self._count = 0
        self._reset_at = np.zeros(1, dtype=np.int64)
        self._batch_shape = (1, self.n_actions)
        self.controller.reset(seed=seed)

    def act(self, obs: np.ndarray) -> np.ndarray:
        self._count += 1
        return self._checked(self.controller.act(obs), (self.n_actions,))

    def _checked(self, action: Any, shape: tuple[int, ...]) -> np.ndarray:
        a = action
        if (
            type(a) is np.ndarray  # noqa: E721 - the hot path: the usual action passes here
            and a.dtype == FLOAT32
            and a.shape == shape
            and all_finite(a)
        ):
            return a
        try:
            a = np.asarray(action, dtype=np.float32)
        except (TypeError, ValueError) as exc:
            raise self._error(f"returned {type(action).__name__} ({exc})", shape) from None
        if a.shape != shape:
            raise self._error(f"returned an action of shape {a.shape}", shape)
        bad = ~np.isfinite(a)
        if bad.any():
            what = "NaN" if np.isnan(a[bad]).any() else "infinite"
            raise self._error(f"returned a {what} action {_short(action)}", shape, bad)
        return a

    def _error(self, what: str, shape: tuple[int, ...], bad: Any = None) -> ControllerError:
        """The error for an invalid action; ``bad``: its non-finite entries (a batch: the
        first row holding one is named)."""
        row = None
        if bad is not None and len(shape) == 2:
            row = int(np.flatnonzero(bad.any(axis=1))[0])
        step = self._count - int(self._reset_at[row or 0])
        at = f"control step {step} of its run" + (f" (row {row})" if row is not None else "")
        return ControllerError(
            f"controller {self.label!r} {what} at {at}; expected shape {shape} with finite "
            f"values ({self.n_actions} commanded currents{', one row per run' * (len(shape) > 1)})"
        )

    def __repr__(self) -> str:
        return f"checked({self.controller!r})"


class CheckedBatchController(CheckedController):
    """:class:`CheckedController` of a controller with ``act_batch``."""

    def reset_batch(self, mask: np.ndarray) -> None:
        m = np.asarray(mask, dtype=np.bool_)
        if self._reset_at.shape != m.shape:
            self._reset_at = np.full(m.shape, self._count, dtype=np.int64)
            self._batch_shape = (m.shape[0] if m.ndim else -1, self.n_actions)
        self._reset_at[m] = self._count
        inner = getattr(self.controller, "reset_batch", None)
        if callable(inner):
            inner(mask)

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        n = obs.shape[0] if type(obs) is np.ndarray else int(np.shape(obs)[0])  # noqa: E721
        shape = self._batch_shape
        if shape[0] != n:
            self._reset_at = np.full(n, self._count, dtype=np.int64)
            self._batch_shape = shape = (n, self.n_actions)
        self._count += 1
        a = self.controller.act_batch(obs)
        if (  # the hot path of _checked, inline
            type(a) is np.ndarray  # noqa: E721
            and a.dtype is FLOAT32
            and a.shape == shape
            and all_finite(a)
        ):
            return a
        return self._checked(a, shape)


def _finite(a: np.ndarray) -> bool:  # pragma: no cover - replaced by its overload
    raise NotImplementedError("_finite runs compiled only (all_finite)")


@overload(_finite, jit_options={"nogil": True, "_nrt": False})
def _finite_impl(a):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    """:func:`_finite` by the array's layout, chosen when it compiles: a C-contiguous array in
    one flat pass that vectorises (no early exit: an and-reduction), any other layout
    element by element."""
    if isinstance(a, types.Array) and a.layout == "C":

        def flat(a):  # type: ignore[no-untyped-def]
            f = a.reshape(a.size)
            ok = True
            for i in range(f.size):
                x = f[i]
                ok &= x - x == 0.0  # NaN and ±inf give NaN
            return ok

        return flat

    def strided(a):  # type: ignore[no-untyped-def]
        for v in np.nditer(a):
            x = v.item()
            if not (x - x == 0.0):  # NaN and ±inf give NaN
                return False
        return True

    return strided


@nb.njit(cache=True, nogil=True, _nrt=False)
def all_finite(a):  # pragma: no cover - compiled
    """True if every entry of the float array ``a`` (any shape and layout) is finite (one
    pass, no temporaries: the action check of every control step)."""
    return _finite(a)


def checked_controller(controller: Any, label: str, n_actions: int) -> CheckedController:
    """``controller`` with its actions checked (:class:`CheckedController`; batched if it
    has ``act_batch``): ``label`` names it in the errors, ``n_actions`` is the plant's
    number of actions (``ctx.n_actions``)."""
    if isinstance(controller, CheckedController):
        return controller
    if callable(getattr(controller, "act_batch", None)):
        return CheckedBatchController(controller, label, n_actions)
    return CheckedController(controller, label, n_actions)


def _short(action: Any) -> str:
    """An action for a message (a few entries)."""
    return np.array2string(np.asarray(action, dtype=np.float64).ravel()[:8], precision=4)


class BaseController:
    """Convenience base for controllers (``reset`` does nothing by default)."""

    name = "base"

    def reset(self, seed: int | None = None) -> None:  # pragma: no cover - trivial
        pass

    def act(self, obs: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r})"
