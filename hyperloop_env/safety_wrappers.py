"""Wrappers for safe reinforcement learning on the environment's safety cost
(``info["cost"]``, :mod:`hyperloop_env.safety`).

* :class:`SafetyGymnasiumStep`: Safety-Gymnasium's step signature,
  ``(obs, reward, cost, terminated, truncated, info)``, for CMDP code written against it
  (the reset is Gymnasium's ``(obs, info)``, as in Safety-Gymnasium).
* :class:`LagrangianReward`: the reward ``r − λ·c`` with a multiplier λ ≥ 0 the training
  loop sets (``wrapper.multiplier = λ``), so that any RL library (Stable-Baselines3's PPO,
  for one) optimises the Lagrangian of the constrained problem; the step's own reward and
  cost stay in ``info["reward"]`` and ``info["cost"]``.

Both work on one environment (``gymnasium.make``); the cost must be in the info, as the
environments of this package put it there on every step.
"""

from __future__ import annotations

import math
from typing import Any, SupportsFloat

import gymnasium as gym


def _cost(info: dict[str, Any]) -> float:
    try:
        return float(info["cost"])
    except KeyError:
        raise KeyError(
            "the wrapped environment's info has no 'cost' (HyperloopSuspension-v0 puts the "
            "safety cost there on every step)"
        ) from None


class SafetyGymnasiumStep(gym.Wrapper):
    """``step`` returns ``(obs, reward, cost, terminated, truncated, info)`` with the
    step's safety cost (module docstring)."""

    def step(self, action: Any) -> tuple[Any, SupportsFloat, float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, _cost(info), terminated, truncated, info


class LagrangianReward(gym.Wrapper):
    """The reward ``r − λ·c`` (module docstring); ``multiplier`` λ is a finite number ≥ 0."""

    def __init__(self, env: gym.Env, multiplier: float = 0.0) -> None:
        super().__init__(env)
        self.multiplier = multiplier

    @property
    def multiplier(self) -> float:
        return self._multiplier

    @multiplier.setter
    def multiplier(self, value: float) -> None:
        try:
            lam = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"multiplier must be a number >= 0, got {value!r}") from None
        if not (math.isfinite(lam) and lam >= 0.0):
            raise ValueError(f"multiplier must be a finite number >= 0, got {value!r}")
        self._multiplier = lam

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        cost = _cost(info)
        info = {**info, "reward": float(reward)}
        return obs, float(reward) - self._multiplier * cost, terminated, truncated, info
