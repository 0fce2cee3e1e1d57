"""Training a residual controller: environments whose action is the learned correction.

A residual agent's action is the correction ``c ∈ [-1, 1]^n`` added, scaled, to a classical
base law's (:mod:`agents.controllers.residual`); the environment flies
``clip(a_base(obs) + scale·c, −1, 1)`` (:func:`~agents.controllers.residual.apply_correction`,
the function the deployed :class:`~agents.controllers.residual.ResidualController` runs).
The wrappers here are ordinary Gymnasium environments to Stable-Baselines3's PPO and SAC:
same observation, the action space ``Box(-1, 1, (n,))`` of the plant, reward, termination and
infos the plant's (the info of a step also holds ``residual_base_action``, only in the single
env). The base law keeps its state (filter, integrator, delay line): it is reset with its
environment and fed every observation, the one before each step.

* :class:`ResidualEnv` wraps one environment (``gymnasium.make``; the ``dummy`` and
  ``subproc`` vector kinds of ``train.py``): the base's ``reset`` / ``act``.
* :class:`ResidualVectorEnv` wraps the native vector env (``vec="native"``): the base's
  ``reset_batch(mask)`` / ``act_batch``, with the env's autoreset mode followed (NEXT_STEP:
  a row that ended is reset by the next step and its base state with it; SAME_STEP: at
  once; a masked ``reset`` resets the masked rows' state).

:func:`residual_vec_env` / :func:`residual_env` build them from a residual record (the
preset option ``residual``: ``{"base": "lqr-preview", "scale": 0.1}``).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import VectorWrapper

from agents.controllers.residual import apply_correction, check_record, check_scale, make_base


class ResidualEnv(gym.Wrapper):
    """One environment whose action is the correction to ``base``'s action (module
    docstring); ``scale``: the correction's scale."""

    def __init__(self, env: gym.Env, base: Any, scale: float) -> None:
        super().__init__(env)
        self.base = base
        self.scale = check_scale(scale)
        self._obs: np.ndarray | None = None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        obs, info = self.env.reset(seed=seed, options=options)
        self.base.reset(seed=seed)
        self._obs = np.array(obs)
        return obs, info

    def step(self, action: Any) -> Any:
        if self._obs is None:
            raise RuntimeError("ResidualEnv: call reset() before step()")
        a_base = np.asarray(self.base.act(self._obs), dtype=np.float32)
        a = apply_correction(a_base, action, self.scale)
        obs, reward, terminated, truncated, info = self.env.step(a)
        self._obs = np.array(obs)
        info = dict(info)
        info["residual_base_action"] = a_base
        return obs, reward, terminated, truncated, info


class ResidualVectorEnv(VectorWrapper):
    """The native vector env (or any Gymnasium ``VectorEnv``) whose actions are the
    corrections to ``base``'s batched actions (module docstring); ``scale``: the
    correction's scale. ``reset(options={"reset_mask": m})`` is passed through (for
    :class:`~agents.training.sb3_adapter.GymnasiumVectorToSB3`)."""

    def __init__(self, env: Any, base: Any, scale: float) -> None:
        super().__init__(env)
        if not callable(getattr(base, "act_batch", None)):
            raise ValueError(f"the base law {base!r} has no act_batch (needed for a vector env)")
        self.base = base
        self.scale = check_scale(scale)
        self._obs: np.ndarray | None = None
        self._ended = np.zeros(self.num_envs, dtype=np.bool_)  # NEXT_STEP: reset next step
        mode = getattr(env, "metadata", {}).get("autoreset_mode", "next_step")
        self._mode = str(getattr(mode, "value", mode)).lower().replace("_", "")

    @property
    def supports_reset_mask(self) -> bool:
        return bool(getattr(self.env, "supports_reset_mask", False))

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_") or name == "env":
            raise AttributeError(name)
        return getattr(self.env, name)

    def _reset_base(self, mask: np.ndarray) -> None:
        fn = getattr(self.base, "reset_batch", None)
        if callable(fn):
            fn(mask)
        elif mask.all():
            self.base.reset()
        else:
            raise ValueError(f"the base law {self.base!r} has no reset_batch")

    def reset(self, *, seed: Any = None, options: dict[str, Any] | None = None) -> Any:
        obs, info = self.env.reset(seed=seed, options=options)
        n = self.num_envs
        mask = (options or {}).get("reset_mask")
        m = np.ones(n, dtype=np.bool_) if mask is None else np.asarray(mask, dtype=np.bool_)
        if self._obs is None or m.all():
            self._obs = np.array(obs)
            m = np.ones(n, dtype=np.bool_)
        else:
            self._obs[m] = np.asarray(obs)[m]
        self._reset_base(m)
        self._ended[m] = False
        return obs, info

    def step(self, actions: Any) -> Any:
        if self._obs is None:
            raise RuntimeError("ResidualVectorEnv: call reset() before step()")
        a_base = self.base.act_batch(self._obs)
        a = apply_correction(a_base, actions, self.scale)
        obs, reward, terminated, truncated, info = self.env.step(a)
        self._obs = np.array(obs)
        done = np.asarray(terminated, dtype=np.bool_) | np.asarray(truncated, dtype=np.bool_)
        if self._mode == "nextstep":
            restarted = self._ended  # these rows were reset by this step: a new episode
            if restarted.any():
                self._reset_base(restarted.copy())
            self._ended = done & ~restarted
        elif self._mode == "samestep" and done.any():
            self._reset_base(done)  # the observation is already the new episode's
        return obs, reward, terminated, truncated, info


def residual_vec_env(venv: Any, record: dict[str, Any]) -> ResidualVectorEnv:
    """``venv`` (the native vector env) as a residual env of ``record`` (the preset option
    ``residual``: base law, its options, scale), the base law built for its plant."""
    rec = check_record(record)
    return ResidualVectorEnv(venv, make_base(rec, venv), rec["scale"])


def residual_env(env: gym.Env, record: dict[str, Any]) -> ResidualEnv:
    """``env`` (one environment) as a residual env of ``record`` (:func:`residual_vec_env`)."""
    rec = check_record(record)
    return ResidualEnv(env, make_base(rec, env), rec["scale"])
