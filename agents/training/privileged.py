"""The privileged critic's observation: the simulator's state appended to what the agent sees.

An asymmetric actor-critic (the preset option ``privileged_critic``, PPO only) trains a
critic that also sees the simulator's true state while the actor sees only the
observation; the actor is what a controller runs, so the deployed agent needs nothing the
vehicle does not measure (Pinto et al., "Asymmetric Actor Critic for Image-Based Robot
Learning", RSS 2018). The environment side is here; the policy that splits the two parts is
:class:`agents.training.privileged_policy.PrivilegedCriticPolicy`.

:class:`PrivilegedObservationVecEnv` wraps the native vector env (``vec="native"``, also
under the residual wrapper of :mod:`agents.training.residual`) and appends to every
observation row the :data:`PRIVILEGED_SIZE` = 42 entries of :func:`privileged_features`,
float32, in this order:

===========  ======  ================================================================
entries      unit    what (:mod:`hyperloop_env.physics.layout`)
===========  ======  ================================================================
0 – 12       m, rad  the vehicle's generalised coordinates q: capsule heave, lateral,
                     pitch, roll, yaw; the units' vertical y_a, then lateral z_a
                     (FL, FR, RL, RR)
13 – 25      /s      their rates q̇ [m/s, rad/s]
26 – 29      m       the true gap excursion s_a of each unit (the clearance is ± 8 mm)
30 – 33      m       the true lateral offset of each unit from its rail
34 – 37      m       the vertical guideway deflection under each unit
38 – 41      m       the lateral guideway deflection under each unit
===========  ======  ================================================================

No sensor noise, delay or dropout touches them (the observation's own entries keep
theirs). The entries belong to the same instant as the observation row they are appended
to: after a step, the state the step ended in (an episode's final state on the step that
ends it); after a reset, the new episode's first state.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import VectorWrapper
from gymnasium.vector.utils import batch_space

from hyperloop_env.physics.layout import M_GAP, M_LAT, M_W, M_WZ, N_UNITS, NQ

_MEAS_BLOCKS = (M_GAP, M_LAT, M_W, M_WZ)
PRIVILEGED_SIZE = 2 * NQ + len(_MEAS_BLOCKS) * N_UNITS
"""Entries appended to each observation row (module docstring's table)."""


def privileged_features(sim: Any, out: np.ndarray | None = None) -> np.ndarray:
    """The privileged entries of every row of ``sim`` (a
    :class:`~hyperloop_env.physics.simulator.BatchSimulator`), ``(N, PRIVILEGED_SIZE)``
    float32: its state's first ``2·NQ`` entries (q, q̇) and the measurement record's true
    gaps, lateral offsets and guideway deflections (module docstring)."""
    n = sim.Y.shape[0]
    if out is None:
        out = np.empty((n, PRIVILEGED_SIZE), dtype=np.float32)
    out[:, : 2 * NQ] = sim.Y[:, : 2 * NQ]
    col = 2 * NQ
    for m in _MEAS_BLOCKS:
        out[:, col : col + N_UNITS] = sim.MEAS[:, m : m + N_UNITS]
        col += N_UNITS
    return out


def native_env(env: Any) -> Any:
    """The native :class:`~hyperloop_env.vector_env.HyperloopSuspensionVectorEnv` under
    ``env``'s wrappers; ``ValueError`` if there is none (the privileged entries are read
    from its simulator)."""
    from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

    base = getattr(env, "unwrapped", env)
    if not isinstance(base, HyperloopSuspensionVectorEnv):
        raise ValueError(
            "privileged_critic needs the native vector env (vec='native'): it reads the "
            f"simulator's state, and {type(base).__name__} has none to read"
        )
    return base


class PrivilegedObservationVecEnv(VectorWrapper):
    """``env``'s observations with the privileged entries appended (module docstring).
    Actions, rewards, terminations and infos are ``env``'s; ``reset(options={"reset_mask":
    m})`` is passed through (the rows outside ``m`` keep their last observation, privileged
    entries included)."""

    def __init__(self, env: Any) -> None:
        super().__init__(env)
        self._native = native_env(env)
        inner = env.single_observation_space
        if not isinstance(inner, spaces.Box) or len(inner.shape) != 1:
            raise ValueError(f"privileged_critic needs a flat Box observation, got {inner!r}")
        n = inner.shape[0]
        low = np.concatenate([inner.low, np.full(PRIVILEGED_SIZE, -np.inf, np.float32)])
        high = np.concatenate([inner.high, np.full(PRIVILEGED_SIZE, np.inf, np.float32)])
        self.single_observation_space = spaces.Box(low, high, dtype=np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.actor_inputs = int(n)
        self._obs = np.zeros((self.num_envs, n + PRIVILEGED_SIZE), dtype=np.float32)

    @property
    def supports_reset_mask(self) -> bool:
        return bool(getattr(self.env, "supports_reset_mask", False))

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_") or name == "env":
            raise AttributeError(name)
        return getattr(self.env, name)

    def _append(self, obs: Any, rows: np.ndarray | None = None) -> np.ndarray:
        n = self.actor_inputs
        feats = privileged_features(self._native.sim)
        if rows is None:
            self._obs[:, :n] = obs
            self._obs[:, n:] = feats
        else:
            self._obs[rows, :n] = np.asarray(obs)[rows]
            self._obs[rows, n:] = feats[rows]
        return self._obs.copy()

    def reset(self, *, seed: Any = None, options: dict[str, Any] | None = None) -> Any:
        obs, info = self.env.reset(seed=seed, options=options)
        mask = (options or {}).get("reset_mask")
        return self._append(obs, None if mask is None else np.asarray(mask, bool)), info

    def step(self, actions: Any) -> Any:
        obs, reward, terminated, truncated, info = self.env.step(actions)
        return self._append(obs), reward, terminated, truncated, info
