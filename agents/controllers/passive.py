"""The passive baseline: constant bias currents (action 0), the paper's uncontrolled system."""

from __future__ import annotations

from typing import Any

import numpy as np

from agents.controllers.base import BaseController, control_context


class PassiveController(BaseController):
    """The paper's uncontrolled system: every coil at its bias current (action 0)."""

    name = "passive"

    def __init__(self, env_or_params: Any = None) -> None:
        ctx = control_context(env_or_params)
        self.n_actions = ctx.n_actions
        self.obs_size = ctx.observation.size

    def act(self, obs: np.ndarray) -> np.ndarray:
        if np.shape(obs) != (self.obs_size,):
            raise ValueError(f"obs must have shape ({self.obs_size},), got {np.shape(obs)}")
        return np.zeros(self.n_actions, dtype=np.float32)

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        shape = np.shape(obs)
        if len(shape) != 2 or shape[1] != self.obs_size:
            raise ValueError(f"obs must have shape (N, {self.obs_size}), got {shape}")
        return np.zeros((shape[0], self.n_actions), dtype=np.float32)
