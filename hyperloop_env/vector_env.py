"""Native batched environment over :class:`~hyperloop_env.physics.BatchSimulator`.

``gymnasium.make_vec("HyperloopSuspension-v0", num_envs=N,
vectorization_mode="vector_entry_point", ...)`` returns :class:`HyperloopSuspensionVectorEnv`:
the N vehicles are advanced in one compiled, multi-threaded call and the observations and
rewards are computed in one compiled call for the whole batch.

Semantics (identical to N single :class:`~hyperloop_env.env.HyperloopSuspensionEnv`):

* Autoreset: Gymnasium 1.x ``AutoresetMode.NEXT_STEP``. The step after environment i
  terminated or truncated resets it (its action is ignored) and returns the reset
  observation, reward 0, ``terminated = truncated = False`` and the reset info.
* Seeding: ``reset(seed=s)`` seeds environment i with ``s + i`` (a list gives one seed per
  environment; ``None`` keeps each environment's generator). Environment i then matches a
  single environment reset with ``seed=s + i`` step for step, across autoresets (each
  environment draws its episodes from its own generator, as the single one does).
* Info: Gymnasium's vector convention, a dict of arrays of length N (``gap_excursion_m``
  (N, 4), ``state`` (N, n_state), …), each with an all-True ``_key`` mask;
  ``reward_terms`` is a nested dict of (N,) arrays with its own masks.
* Actions: shape (N, 4); NaN/inf anywhere (also in a row being reset) or another shape
  raise ``ValueError``; values outside [-1, 1] are clipped.
* ``render_mode="rgb_array"``: ``render()`` returns a tuple of N frames.
"""

from __future__ import annotations

from typing import Any

import numba as nb
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from hyperloop_env.env import (
    _PREVIEW,
    N_NOISY,
    OBS_BOUND,
    REWARD_TERMS,
    _add_noise,
    _check_action,
    _commanded_currents,
    _configure,
    _episode_steps,
    _observe,
    _reject_unknown,
)
from hyperloop_env.observation import OBS_SIZE, action_to_current
from hyperloop_env.physics.layout import (
    M_ACC_HEAVE,
    M_ACC_LAT,
    M_CONTACT,
    M_GAP,
    M_I,
    M_LAT,
    M_T,
    M_X,
    P_I0,
)
from hyperloop_env.physics.model import BatchSimulator, control_step
from hyperloop_env.physics.params import ModelParams
from hyperloop_env.scenarios import DEFAULT_SCENARIO, ScenarioConfig

PARALLEL_MIN_ENVS = 32
"""Below this many environments the batch is stepped by one thread (a serial loop over
the same compiled ``control_step``, bit-identical): waking the worker threads costs more
than they save for small batches, badly so on a loaded machine."""


@nb.njit(cache=True)
def _step_serial(P, Y, AUX, IRR, ICMD, MEAS, WORK, WTS, UO, SPANS):  # pragma: no cover
    for i in range(Y.shape[0]):
        control_step(P[i], Y[i], AUX[i], IRR[i], ICMD[i], MEAS[i], WORK[i], WTS[i], UO[i], SPANS[i])


class HyperloopSuspensionVectorEnv(VectorEnv):
    """N independent hyperloop suspension environments, batched (see the module docstring
    and :class:`~hyperloop_env.env.HyperloopSuspensionEnv` for spaces, reward and
    arguments; ``num_envs`` is the only extra argument). ``reset(options={"reset_mask": m})``
    resets only the environments where ``m`` is True, as Gymnasium's own vector envs do."""

    supports_reset_mask = True

    metadata = {
        "render_modes": ["rgb_array"],
        "render_fps": 50,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        num_envs: int = 1,
        scenario: str = DEFAULT_SCENARIO,
        *,
        speed_kmh: float | None = None,
        curve_radius_m: float | None = None,
        cant_deg: float | None = None,
        track_length_m: float | None = None,
        irregularity: str | None = None,
        control_dt_s: float | None = None,
        clearance_m: float | None = None,
        magnet: str | None = None,
        coil_time_constant_s: float | None = None,
        action_scale: float = 1.0,
        sensor_noise_std: float = 0.0,
        sensor_delay: int = 0,
        gap_weight: float = 1.0,
        current_weight: float = 0.05,
        comfort_weight: float = 1.0,
        survival_bonus: float = 1.0,
        contact_penalty: float = 100.0,
        render_mode: str | None = None,
        **unknown: Any,
    ) -> None:
        _reject_unknown(unknown)
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive int, got {num_envs!r}")
        self.config: ScenarioConfig
        _configure(self, scenario, render_mode, locals())
        self.num_envs = n = num_envs
        self.single_action_space = spaces.Box(-1.0, 1.0, (4,), dtype=np.float32)
        self.single_observation_space = spaces.Box(
            -OBS_BOUND, OBS_BOUND, (OBS_SIZE,), dtype=np.float32
        )
        self.action_space = batch_space(self.single_action_space, n)
        self.observation_space = batch_space(self.single_observation_space, n)

        self.sim = BatchSimulator(self.config.base, n)
        self._params: list[ModelParams] = [self.config.base] * n
        self._rngs: list[np.random.Generator | None] = [None] * n
        self._i0 = self.sim.P[:, P_I0].copy()
        self._cmd = np.zeros((n, 4))
        self._prev_gap = np.zeros((n, 4))
        self._obs = np.zeros((n, OBS_SIZE), dtype=np.float32)
        self._obs_prev = np.zeros((n, OBS_SIZE), dtype=np.float32)
        self._reward = np.zeros(n)
        self._terms = np.zeros((n, len(REWARD_TERMS)))
        self._mode = np.zeros(n, dtype=np.int8)
        self._noise_key = np.zeros(n, dtype=np.uint64)
        self._noise_ctr = np.zeros(n, dtype=np.uint64)
        self._steps = np.zeros(n, dtype=np.int64)
        self._max_steps = np.zeros(n, dtype=np.int64)
        self._speed_kmh = np.zeros(n)
        self._radius_m = np.zeros(n)
        self._prev_done = np.zeros(n, dtype=np.bool_)
        self._has_reset = False
        self._renderers: list[Any] | None = None

    # ---- helpers -------------------------------------------------------------------------
    @property
    def nominal_current_A(self) -> np.ndarray:
        """I0 of each environment's current episode [A], shape (N,)."""
        return self._i0.copy()

    def action_to_current(self, actions: Any) -> np.ndarray:
        """Commanded currents [A], shape (N, 4), for actions (N, 4) (clipped to [-1, 1])."""
        a = np.clip(np.asarray(actions, dtype=np.float64), -1.0, 1.0)
        return action_to_current(a, self._i0, self.action_scale)

    @property
    def state(self) -> np.ndarray:
        """Privileged full simulator states, shape (N, n_state) (a copy)."""
        return self.sim.Y.copy()

    def _reset_one(self, i: int) -> None:
        rng = self._rngs[i]
        if rng is None:
            rng, _ = seeding.np_random(None)
            self._rngs[i] = rng
        params = self.config.sample(rng)
        sim_seed = int(rng.integers(0, 2**63 - 1))
        self._noise_key[i] = np.uint64(rng.integers(0, 2**63 - 1))
        self._noise_ctr[i] = 0
        self.sim.reset_one(i, sim_seed, None if params is self._params[i] else params)
        self._params[i] = params
        self._i0[i] = self.sim.P[i, P_I0]
        self._steps[i] = 0
        self._max_steps[i] = _episode_steps(params)
        self._speed_kmh[i] = params.condition.speed_kmh
        self._radius_m[i] = params.condition.curve_radius_m

    def _finish_obs(self, stepped: np.ndarray | None) -> np.ndarray:
        if self._noise > 0.0:
            _add_noise(self._obs, self._noise_key, self._noise_ctr, self._noise, N_NOISY)
            self._noise_ctr += np.uint64(1)
        if not self._delay:
            return self._obs.copy()
        if stepped is None:
            out = self._obs.copy()
        else:
            out = np.where(stepped[:, None], self._obs_prev, self._obs)
        self._obs_prev[:] = self._obs
        return out

    # ---- gymnasium API -------------------------------------------------------------------
    def reset(
        self,
        *,
        seed: int | list[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every environment, or with ``options={"reset_mask": m}`` (Gymnasium's
        convention, a bool array of shape (num_envs,)) only those where ``m`` is True; the
        others keep their state and their last observation."""
        n = self.num_envs
        partial = bool(options) and "reset_mask" in options
        if partial:
            mask = np.asarray(options["reset_mask"])
            if mask.shape != (n,) or mask.dtype != np.bool_:
                raise ValueError(
                    f"options['reset_mask'] must be a bool array of shape ({n},), "
                    f"got {mask.dtype} {mask.shape}"
                )
            if not self._has_reset:
                raise RuntimeError(
                    "HyperloopSuspensionVectorEnv: call reset() without reset_mask first"
                )
        else:
            mask = np.ones(n, dtype=np.bool_)
        if seed is None:
            seeds: list[int | None] = [None] * n
        elif isinstance(seed, int | np.integer) and not isinstance(seed, bool):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)
            if len(seeds) != n:
                raise ValueError(f"seed list must have length num_envs={n}, got {len(seeds)}")
        if seed is not None and not partial:
            self._np_random, self._np_random_seed = seeding.np_random(seeds[0])
        if partial:
            keep = ~mask
            saved = (self._obs.copy(), self._obs_prev.copy(), self._noise_ctr.copy())
        for i in np.flatnonzero(mask):
            sd = seeds[i]
            if sd is not None or self._rngs[i] is None:
                self._rngs[i], _ = seeding.np_random(sd)
            self._reset_one(int(i))
        self._mode[:] = np.where(mask, 1, 0)
        _observe(
            self.sim.MEAS,
            self.sim.P,
            self._prev_gap,
            self._mode,
            self._obs,
            self._reward,
            self._terms,
            *self._weights,
            _PREVIEW,
        )
        obs = self._finish_obs(None)
        if partial:
            obs[keep] = saved[0][keep]
            self._obs[keep] = saved[0][keep]
            self._obs_prev[keep] = saved[1][keep]
            self._noise_ctr[keep] = saved[2][keep]
        self._prev_done[mask] = False
        self._has_reset = True
        return obs, self._info(np.zeros(n, dtype=np.bool_))

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if not self._has_reset:
            raise RuntimeError("HyperloopSuspensionVectorEnv: call reset() before step()")
        n = self.num_envs
        act = _check_action(actions, (n, 4))
        if not _commanded_currents(act, self._i0, self.action_scale, self._cmd):
            raise ValueError(f"actions must be finite (no NaN/inf), got {act!r}")
        if self.num_envs >= PARALLEL_MIN_ENVS:
            meas = self.sim.step(self._cmd)
        else:
            b = self.sim
            _step_serial(b.P, b.Y, b.AUX, b.IRR, self._cmd, b.MEAS, b.WORK, b.WTS, b.UO, b.SPANS)
            meas = b.MEAS
        prev_done = self._prev_done
        stepped = ~prev_done
        if prev_done.any():
            for i in np.flatnonzero(prev_done):
                self._reset_one(int(i))
            self._mode[:] = np.where(prev_done, 1, 2)
        else:
            self._mode[:] = 2
        _observe(
            meas,
            self.sim.P,
            self._prev_gap,
            self._mode,
            self._obs,
            self._reward,
            self._terms,
            *self._weights,
            _PREVIEW,
        )
        obs = self._finish_obs(stepped)
        self._steps += stepped
        terminated = (meas[:, M_CONTACT] > 0.5) & stepped
        truncated = (self._steps >= self._max_steps) & stepped & ~terminated
        self._prev_done = terminated | truncated
        reward = self._reward.copy()
        return obs, reward, terminated, truncated, self._info(terminated)

    def _info(self, contact: np.ndarray) -> dict[str, Any]:
        r = self.sim.MEAS.copy()
        t = self._terms.copy()
        m = np.ones(self.num_envs, dtype=np.bool_)
        terms = {}
        for k, name in enumerate(REWARD_TERMS):
            terms[name] = t[:, k]
            terms["_" + name] = m
        return {
            "position_m": r[:, M_X],
            "_position_m": m,
            "time_s": r[:, M_T],
            "_time_s": m,
            "gap_excursion_m": r[:, M_GAP : M_GAP + 4],
            "_gap_excursion_m": m,
            "lateral_offset_m": r[:, M_LAT : M_LAT + 4],
            "_lateral_offset_m": m,
            "current_A": r[:, M_I : M_I + 4],
            "_current_A": m,
            "acceleration_m_s2": r[:, M_ACC_HEAVE : M_ACC_LAT + 1],
            "_acceleration_m_s2": m,
            "contact": contact.copy(),
            "_contact": m,
            "reward_terms": terms,
            "_reward_terms": m,
            "speed_kmh": self._speed_kmh.copy(),
            "_speed_kmh": m,
            "curve_radius_m": self._radius_m.copy(),
            "_curve_radius_m": m,
            "state": self.sim.Y.copy(),
            "_state": m,
        }

    def render(self) -> tuple[np.ndarray, ...] | None:
        if self.render_mode is None:
            return None
        if not self._has_reset:
            raise RuntimeError("HyperloopSuspensionVectorEnv: call reset() before render()")
        from hyperloop_env.rendering import Renderer

        if self._renderers is None:
            self._renderers = [Renderer("rgb_array", self.metadata["render_fps"])]
        rend = self._renderers[0]
        return tuple(
            rend.draw(self.sim.MEAS[i], self.sim.P[i], self._params[i])
            for i in range(self.num_envs)
        )

    def close_extras(self, **kwargs: Any) -> None:
        if self._renderers is not None:
            for r in self._renderers:
                r.close()
            self._renderers = None

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_renderers"] = None
        return state

    def __repr__(self) -> str:
        name = self.config.scenario.name
        return f"HyperloopSuspensionVectorEnv({name}, num_envs={self.num_envs})"
