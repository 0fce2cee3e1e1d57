"""The sensor model between the simulator's record and the observation the agent sees.

Stages, in order, on the *measured* blocks of the observation (the first
``ObservationSpec.n_measured`` entries; speed and curvature are map data and stay exact):

1. **noise** — Gaussian, standard deviation ``SensorConfig.noise_std`` on the scaled
   entries, drawn counter-based from a per-episode key (:func:`kernels.add_noise`), so a
   batch reproduces single environments bit for bit;
2. **dropout** — a hook: ``SensorModel.dropout`` (None by default) is called as
   ``dropout(i, step, obs_row, last_row)`` for every environment row and may overwrite
   entries of ``obs_row`` in place (e.g. hold the last value of a failed sensor). The
   environments install a disturbance's per-episode hook for row ``i`` with
   :meth:`SensorModel.set_episode_hook` (``sensor_hook`` of
   :class:`~hyperloop_env.disturbances.Realisation`); the rows' hooks are then dispatched
   through ``dropout``;
3. **delay** — ``SensorConfig.delay_steps = 1`` returns the previous control step's
   observation (at reset: the reset observation).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from hyperloop_env.config import SensorConfig
from hyperloop_env.kernels import add_noise

DropoutHook = Callable[[int, int, np.ndarray, np.ndarray], None]


class SensorModel:
    """Noise, dropout and delay for ``n`` environments with observations of ``size``."""

    def __init__(self, config: SensorConfig, n: int, size: int, n_measured: int) -> None:
        self.config = config
        self.noise_std = config.noise_std
        self.delay = config.delay_steps
        self.n_measured = n_measured
        self.keys = np.zeros(n, dtype=np.uint64)
        self.counters = np.zeros(n, dtype=np.uint64)
        self.steps = np.zeros(n, dtype=np.int64)
        self.prev = np.zeros((n, size), dtype=np.float32)  # delay line
        self.last = np.zeros((n, size), dtype=np.float32)  # last delivered (dropout hold)
        self.dropout: DropoutHook | None = None
        self._hooks: list[Callable[[int, np.ndarray, np.ndarray], None] | None] | None = None

    def start_episode(self, i: int, key: np.uint64) -> None:
        """New episode of environment ``i`` with noise key ``key``."""
        self.keys[i] = key
        self.counters[i] = 0
        self.steps[i] = 0

    def set_episode_hook(
        self, i: int, hook: Callable[[int, np.ndarray, np.ndarray], None] | None
    ) -> None:
        """Install (or, with None, remove) environment ``i``'s per-episode sensor hook
        ``hook(step, obs_row, last_row)``. While any row has one, ``dropout`` dispatches to
        the rows' hooks (replacing a hook set by hand); with none it stays as it was."""
        if hook is None and self._hooks is None:
            return
        if self._hooks is None:
            self._hooks = [None] * len(self.keys)
        self._hooks[i] = hook
        self.dropout = self._dispatch if any(h is not None for h in self._hooks) else None

    def _dispatch(self, i: int, step: int, obs_row: np.ndarray, last_row: np.ndarray) -> None:
        h = self._hooks[i] if self._hooks is not None else None
        if h is not None:
            h(step, obs_row, last_row)

    def snapshot(self) -> tuple[np.ndarray, ...]:
        return self.prev.copy(), self.counters.copy(), self.steps.copy(), self.last.copy()

    def restore(self, saved: tuple[np.ndarray, ...], rows: np.ndarray) -> None:
        """Put back rows ``rows`` of a :meth:`snapshot` (partial resets)."""
        prev, ctr, steps, last = saved
        self.prev[rows] = prev[rows]
        self.counters[rows] = ctr[rows]
        self.steps[rows] = steps[rows]
        self.last[rows] = last[rows]

    def apply(self, obs: np.ndarray, stepped: np.ndarray | None) -> np.ndarray:
        """The observations delivered to the agent from the true ones (``obs`` (n, size),
        modified in place by noise and dropout); ``stepped`` marks the rows that advanced
        one control step (None: every row was reset)."""
        if self.noise_std > 0.0:
            add_noise(obs, self.keys, self.counters, self.noise_std, self.n_measured)
            self.counters += np.uint64(1)
        if self.dropout is not None:
            for i in range(obs.shape[0]):
                self.dropout(i, int(self.steps[i]), obs[i], self.last[i])
            self.last[:] = obs
        if stepped is not None:
            self.steps += stepped
        if not self.delay:
            return obs.copy()
        out = obs.copy() if stepped is None else np.where(stepped[:, None], self.prev, obs)
        self.prev[:] = obs
        return out
