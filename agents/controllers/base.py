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
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from hyperloop_env.observation import (
    NO_MEMORY,
    MemorySpec,
    ObservationScales,
    ObservationSpec,
    ObservationView,
    observation_spec,
)
from hyperloop_env.physics.actuators import ActuatorSet
from hyperloop_env.physics.model import Simulator, equilibrium_current_A, guidance_bias_A
from hyperloop_env.physics.params import ModelParams


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


class BaseController:
    """Convenience base for controllers (``reset`` does nothing by default)."""

    name = "base"

    def reset(self, seed: int | None = None) -> None:  # pragma: no cover - trivial
        pass

    def act(self, obs: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r})"
