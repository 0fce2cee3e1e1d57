"""The passive baseline: constant bias currents (action 0), the paper's uncontrolled system."""

from __future__ import annotations

from typing import Any

import numpy as np

from agents.controllers.base import BaseController, control_context


class PassiveController(BaseController):
    """The paper's uncontrolled system: every coil at its bias current (action 0)."""

    name = "passive"

    def __init__(self, env_or_params: Any = None) -> None:
        self.n_actions = control_context(env_or_params).n_actions

    def act(self, obs: np.ndarray) -> np.ndarray:
        return np.zeros(self.n_actions, dtype=np.float32)

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        return np.zeros((np.asarray(obs).shape[0], self.n_actions), dtype=np.float32)
