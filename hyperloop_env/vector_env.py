"""Native batched environment over :class:`~hyperloop_env.physics.BatchSimulator`.

``gymnasium.make_vec("HyperloopSuspension-v0", num_envs=N,
vectorization_mode="vector_entry_point", ...)`` returns :class:`HyperloopSuspensionVectorEnv`:
the N vehicles are advanced in one compiled, multi-threaded call and the observations and
rewards are computed by the same compiled kernels as the single environment
(:mod:`hyperloop_env.kernels`) for the whole batch. It takes the same configuration
(:class:`~hyperloop_env.config.EnvConfig`, or the same keyword arguments) plus ``num_envs``.

Semantics (identical to N single :class:`~hyperloop_env.env.HyperloopSuspensionEnv`):

* Autoreset: the ``autoreset_mode`` keyword (Gymnasium 1.x :class:`AutoresetMode` or its
  value string; ``metadata["autoreset_mode"]`` and the ``autoreset_mode`` attribute say
  which). ``NEXT_STEP`` (default): the step after environment i terminated or truncated
  resets it (its action is ignored) and returns the reset observation, reward 0,
  ``terminated = truncated = False`` and the reset info. ``SAME_STEP``: the step that ends
  an episode resets the environment at once and returns the reset observation; the last
  observation of the episode is in ``info["final_obs"]`` (an (N,) object array: the
  observation of every ended environment, None for the others; masked by
  ``info["_final_obs"]``) and its info in ``info["final_info"]`` (the ended environments'
  values, zeros elsewhere, masks True for the ended ones), as Gymnasium's
  ``SyncVectorEnv`` gives them, bit for bit.
  ``DISABLED``: no automatic reset; the caller resets the ended environments with
  ``reset(options={"reset_mask": m})`` before the next step (stepping an ended
  environment raises ``RuntimeError``, as Gymnasium's ``SyncVectorEnv`` asserts).
* Per-environment disturbances: ``reset(options={"disturbances": [d_0, …, d_{N-1}]})``
  gives environment i the disturbances ``d_i`` (a mapping name → severity, or None for
  the configured ones) on top of the configuration's, for the episodes this reset starts
  and its autoresets, until a reset gives that environment others. Environment i then
  matches a single environment made with those disturbances. The fragility and capacity
  searches use this to fly one seed at a different severity in every row.
* Seeding: ``reset(seed=s)`` seeds environment i with ``s + i`` (a list gives one seed per
  environment; ``None`` keeps each environment's generator). Environment i then matches a
  single environment reset with ``seed=s + i`` step for step, across autoresets (each
  environment draws its episodes from its own generator, as the single one does).
* Info: Gymnasium's vector convention, a dict of arrays of length N (``gap_excursion_m``
  (N, 4), ``state`` (N, n_state), …), each with an all-True ``_key`` mask;
  ``reward_terms`` is a nested dict of (N,) arrays with its own masks; ``info="flat"``
  gives every reward term its own entry ``reward_<term>`` instead (no nested dict: what
  TorchRL's vector paths and other clients that stack info arrays need).
* TorchRL: ``GymWrapper(gym.make_vec(..., vectorization_mode="vector_entry_point",
  autoreset_mode="Disabled"))`` (TorchRL takes ``DISABLED`` or ``SAME_STEP`` only and
  resets the ended environments itself through ``reset_mask``; with ``"SameStep"`` it
  reads the info too and needs ``info="flat"``); ``GymEnv(id, num_envs=N)`` builds
  single environments and needs ``info="flat"``.
* Actions: shape (N, n_channels); NaN/inf anywhere (also in a row being reset) or another
  shape raise ``ValueError``; values outside [-1, 1] are clipped.
* ``render_mode="rgb_array"``: ``render()`` returns a tuple of N frames;
  ``metadata["render_fps"]`` is the control rate 1/``control_dt_s``, as the single env's.
* Speed: ``parallel`` chooses whether the physics of the batch runs on numba's threads
  (bit-identical either way): True/False always/never; None (the default) one thread below
  ``PARALLEL_MIN_ENVS`` environments, and from there on whichever of the two is faster
  now, measured as the batch steps (:class:`hyperloop_env.kernel_choice.KernelChoice`:
  threads help on an idle machine and stall on a loaded one); ``info=False`` returns empty
  info dicts (but ``final_obs``/``final_info`` of ``SAME_STEP`` autoresets), for loops that read
  the simulator's records themselves. After the physics a step is one compiled call
  (:func:`hyperloop_env.kernels.step_outcome`).
"""

from __future__ import annotations

from dataclasses import replace
from time import perf_counter
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from hyperloop_env import kernels
from hyperloop_env.config import EnvConfig, ResolvedConfig
from hyperloop_env.disturbances import merge, parse_disturbances
from hyperloop_env.env import (
    DEFAULT_RENDER_FPS,
    OBS_BOUND,
    PREVIEW,
    action_arrays,
    check_action,
    check_render_mode,
    control_rate_hz,
    current_speed_kmh,
    info_fields,
    make_config,
    make_memory,
)
from hyperloop_env.episode import start_episode
from hyperloop_env.kernel_choice import KernelChoice
from hyperloop_env.observation import command_current
from hyperloop_env.physics.arrays import FLOAT32, aligned_zeros, is_float
from hyperloop_env.physics.entry import compiled_entry, strided
from hyperloop_env.physics.layout import P_SPEED, RECORD_FIELDS
from hyperloop_env.physics.model import episode_steps
from hyperloop_env.physics.params import ModelParams
from hyperloop_env.physics.simulator import BatchSimulator
from hyperloop_env.reward import REWARD_TERMS
from hyperloop_env.safety import costs_into
from hyperloop_env.sensors import SensorModel

PARALLEL_MIN_ENVS = 32
"""Below this many environments the batch is stepped by one thread (a serial loop over
the same compiled ``control_step``, bit-identical): waking the worker threads costs more
than they save for small batches, badly so on a loaded machine. From there on (with
``parallel=None``) the faster of the two is measured as the batch steps."""

_CONTACT = RECORD_FIELDS["contact"].start
_SAME_STEP = AutoresetMode.SAME_STEP  # (an identity test in the step: no class lookup)
_SPEED = RECORD_FIELDS["speed_m_s"].start
_GAP = RECORD_FIELDS["gap_excursion_m"]
_LAT = RECORD_FIELDS["lateral_offset_m"]
_TERM_KEYS = tuple((name, "_" + name) for name in REWARD_TERMS)


def _seed_list(seed: Any, n: int) -> list[int | None]:
    """One seed (or None) per environment from ``reset(seed=...)``: None, a non-negative
    int ``s`` (environment i gets ``s + i``; a NumPy integer or 0-d integer array is an
    int) or a sequence of ``n`` non-negative ints / None. Anything else raises
    ``ValueError`` saying what is accepted."""
    what = f"seed must be None, an int >= 0 or a list of num_envs={n} ints >= 0 (or None)"
    if seed is None:
        return [None] * n
    if isinstance(seed, np.ndarray) and seed.ndim == 0:
        seed = seed[()]  # a NumPy scalar, checked as one
    if isinstance(seed, int | np.integer) and not isinstance(seed, bool):
        if seed < 0:
            raise ValueError(f"{what}; got the negative int {seed!r}")
        return [int(seed) + i for i in range(n)]
    if isinstance(seed, str | bytes) or not hasattr(seed, "__len__"):
        raise ValueError(f"{what}; got {type(seed).__name__} {seed!r}")
    seeds = list(seed)
    if len(seeds) != n:
        raise ValueError(f"{what}; got a sequence of length {len(seeds)}")
    for s in seeds:
        if s is not None and (isinstance(s, bool) or not isinstance(s, int | np.integer)):
            raise ValueError(f"{what}; got the entry {type(s).__name__} {s!r}")
        if s is not None and s < 0:
            raise ValueError(f"{what}; got the negative entry {s!r}")
    return [None if s is None else int(s) for s in seeds]


def _final_obs(obs: np.ndarray, done: np.ndarray) -> np.ndarray:
    """SAME_STEP's ``info["final_obs"]`` as Gymnasium's vector envs give it: an (N,) object
    array holding the last observation (an array) of every ended environment, None for
    the others (built entry by entry: ``np.array`` of equal rows would make it (N, n_obs))."""
    out = np.full(len(done), None, dtype=object)
    for i in np.flatnonzero(done):
        out[i] = obs[i].copy()
    return out


def _masked_info(info: dict[str, Any], done: np.ndarray) -> dict[str, Any]:
    """SAME_STEP's ``info["final_info"]`` as Gymnasium's vector envs give it: the values of
    the ended environments, zeros elsewhere, every mask ``_key`` (nested dicts too) True
    only for the ended ones."""
    keep = ~done
    out: dict[str, Any] = {}
    for key, value in info.items():
        if isinstance(value, dict):
            out[key] = _masked_info(value, done)
        elif key.startswith("_"):
            out[key] = done.copy()
        else:
            value[keep] = 0
            out[key] = value
    return out


class HyperloopSuspensionVectorEnv(VectorEnv):
    """N independent hyperloop suspension environments, batched (see the module docstring
    and :class:`~hyperloop_env.env.HyperloopSuspensionEnv` for spaces, reward and
    arguments; ``num_envs`` is the only extra argument). ``reset(options={"reset_mask": m})``
    resets only the environments where ``m`` is True, as Gymnasium's own vector envs do."""

    supports_reset_mask = True
    autoreset_mode = AutoresetMode.NEXT_STEP  # the instance's, set by the keyword

    metadata = {
        "render_modes": ["rgb_array"],
        "render_fps": DEFAULT_RENDER_FPS,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        num_envs: int = 1,
        scenario: str | None = None,
        *,
        config: EnvConfig | None = None,
        render_mode: str | None = None,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        parallel: bool | None = None,
        info: bool | str = True,
        **kwargs: Any,
    ) -> None:
        try:
            mode = AutoresetMode(autoreset_mode)
        except ValueError:
            valid = [m.value for m in AutoresetMode]
            raise ValueError(
                f"autoreset_mode must be an AutoresetMode or one of {valid}, got {autoreset_mode!r}"
            ) from None
        self.autoreset_mode = mode
        self.metadata = {**type(self).metadata, "autoreset_mode": mode}
        if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive int, got {num_envs!r}")
        if scenario is not None:
            kwargs["scenario"] = scenario
        self.env_config = make_config(config, kwargs)
        self.config: ResolvedConfig = self.env_config.resolve()
        self.render_mode = check_render_mode(render_mode, self.metadata["render_modes"])
        cfg = self.config
        self.metadata["render_fps"] = control_rate_hz(cfg)
        self.num_envs = n = int(num_envs)
        self.observation_spec = cfg.observation
        self.action_scale = cfg.action_scale
        n_obs = self.observation_spec.base_size  # the memory blocks (if any) follow
        self.single_action_space = spaces.Box(-1.0, 1.0, (cfg.actuators.size,), dtype=np.float32)
        self.single_observation_space = spaces.Box(
            -OBS_BOUND, OBS_BOUND, (self.observation_spec.size,), dtype=np.float32
        )
        self.action_space = batch_space(self.single_action_space, n)
        self._action_shape = tuple(self.action_space.shape)
        self.observation_space = batch_space(self.single_observation_space, n)

        self.sim = BatchSimulator(cfg.base, n)
        self._cost_limits = cfg.cost_limits
        self._params: list[ModelParams] = [cfg.base] * n
        self._rngs: list[np.random.Generator | None] = [None] * n
        self._row_configs: list[ResolvedConfig] = [cfg] * n
        self._config_cache: dict[Any, ResolvedConfig] = {}
        self._weights = np.array(cfg.reward.as_tuple())
        self._neutral, self._index = action_arrays(cfg)
        self._offsets = self.observation_spec.offsets()
        self.sensors = SensorModel(cfg.sensors, n, n_obs, self.observation_spec.n_measured)
        self.memory = make_memory(cfg, n)
        self._base = aligned_zeros((n, cfg.actuators.size))
        self._cmd = aligned_zeros((n, self.sim.n_commands))
        self._info_views = tuple((key, "_" + key, (slice(None), idx)) for key, idx in info_fields())
        self._prev = aligned_zeros((n, 2 * len(self.sim.unit_names)))
        self._obs = aligned_zeros((n, n_obs), np.float32)
        self._reward = aligned_zeros(n)
        self._terms = aligned_zeros((n, len(REWARD_TERMS)))
        self._mode = np.zeros(n, dtype=np.int8)
        self._steps = np.zeros(n, dtype=np.int64)
        self._max_steps = np.zeros(n, dtype=np.int64)
        self._speed_kmh = np.zeros(n)
        self._radius_m = np.zeros(n)
        self._prev_done = np.zeros(n, dtype=np.bool_)
        self._any_done = False  # self._prev_done.any(), kept beside it
        self._spare_done = np.zeros(n, dtype=np.bool_)  # step()'s next done (ping-pong)
        self._no_rows = np.zeros(0, dtype=np.int64)
        self._outcome: Any = None  # kernels.step_outcome bound to these buffers (_bind_outcome)
        self._currents: dict[Any, Any] = {}  # kernels.commanded_currents by the actions' dtype
        self._advance: np.ndarray | None = None  # rows step() advances (None: all; hold())
        if parallel is not None and not isinstance(parallel, bool | np.bool_):
            raise ValueError(f"parallel must be None, True or False, got {parallel!r}")
        self.parallel = parallel if parallel is None else bool(parallel)
        self._choice = KernelChoice() if parallel is None and n >= PARALLEL_MIN_ENVS else None
        if info not in (True, False, "nested", "flat"):
            raise ValueError(f"info must be True, False, 'nested' or 'flat', got {info!r}")
        self.with_info = info is not False
        self.flat_info = info == "flat"
        self._has_reset = False
        self._renderers: list[Any] | None = None

    # ---- helpers -------------------------------------------------------------------------
    @property
    def nominal_current_A(self) -> np.ndarray:
        """I0 of each environment's current episode [A], shape (N,)."""
        return self.sim.nominal_current_A

    def action_to_current(self, actions: Any) -> np.ndarray:
        """Commanded currents [A], shape (N, n), of every action channel for actions (N, n)
        (clipped to [-1, 1] as in ``step``): ``reference·(neutral + action_scale·a)`` per
        channel, as :meth:`HyperloopSuspensionEnv.action_to_current`."""
        a = np.clip(np.asarray(actions, dtype=np.float64), -1.0, 1.0)
        return command_current(self._base, self._neutral[None], self.action_scale, a)

    @property
    def state(self) -> np.ndarray:
        """Privileged full simulator states, shape (N, n_state) (a copy)."""
        return self.sim.Y.copy()

    @property
    def params(self) -> list[ModelParams]:
        """Parameters of each environment's current episode."""
        return list(self._params)

    def _reset_one(self, i: int) -> None:
        rng = self._rngs[i]
        if rng is None:
            rng, _ = seeding.np_random(None)
            self._rngs[i] = rng
        ep = start_episode(self._row_configs[i], rng)
        self.sensors.start_episode(i, ep.noise_key)
        self.sensors.set_episode_hook(i, ep.sensor_hook)
        self.sim.reset_one(
            i,
            ep.sim_seed,
            None if ep.params is self._params[i] else ep.params,
            profile_offset=ep.profile_offset,
        )
        s = self.sim._singles[i]
        self._params[i] = ep.params
        self._base[i] = s.command_reference_A
        self._cmd[i] = s.neutral_command
        self._steps[i] = 0
        self._max_steps[i] = episode_steps(ep.params)
        self._speed_kmh[i] = ep.params.condition.speed_kmh
        self._radius_m[i] = ep.params.condition.curve_radius_m

    def _row_config(self, extra: Any, i: int) -> ResolvedConfig:
        """The resolved configuration of environment i with the extra disturbances
        ``extra`` (validated; cached per distinct set of disturbances)."""
        if extra is None:
            return self.config
        try:
            dist = parse_disturbances(extra)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"options['disturbances'][{i}]: {exc}") from None
        if not dist:
            return self.config
        res = self._config_cache.get(dist)
        if res is None:
            base = self.env_config
            cfg = replace(base, disturbances=merge(base.disturbances, dist))
            res = cfg.resolve()
            if res.observation.size != self.config.observation.size or (
                res.actuators != self.config.actuators
            ):
                raise ValueError(
                    f"options['disturbances'][{i}] changes the spaces of the environment"
                )
            self._config_cache[dist] = res
        return res

    def _observe(self, stepped: np.ndarray | None) -> np.ndarray:
        s = self.sim
        kernels.observe(s.MEAS, s.P, self._prev, self._mode, self._obs, self._offsets, PREVIEW)
        kernels.reward(s.MEAS, s.P, self._mode, self._weights, self._terms, self._reward)
        return self.sensors.apply(self._obs, stepped)

    # ---- gymnasium API -------------------------------------------------------------------
    def reset(
        self,
        *,
        seed: int | list[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every environment, or with ``options={"reset_mask": m}`` (Gymnasium's
        convention, a bool array of shape (num_envs,)) only those where ``m`` is True; the
        others keep their state and their last observation, and the info holds the reset
        environments' values only (zeros elsewhere, every ``_key`` mask equal to ``m``), as
        Gymnasium's own vector envs give it."""
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
        if options and "disturbances" in options:
            extra = options["disturbances"]
            if (
                isinstance(extra, str | bytes | dict)
                or not hasattr(extra, "__len__")
                or (len(extra) != n)
            ):
                raise ValueError(
                    f"options['disturbances'] must be a sequence of num_envs={n} entries "
                    f"(a mapping name -> severity, or None), got {extra!r}"
                )
            rows = [self._row_config(extra[i], i) if mask[i] else None for i in range(n)]
            for i in np.flatnonzero(mask):
                self._row_configs[i] = rows[i]
        elif not partial:
            self._row_configs = [self.config] * n
        seeds = _seed_list(seed, n)
        if seed is not None and not partial:
            self._np_random, self._np_random_seed = seeding.np_random(seeds[0])
        if partial:
            keep = ~mask
            saved_obs = self._obs.copy()
            saved_sensors = self.sensors.snapshot()
        for i in np.flatnonzero(mask):
            sd = seeds[i]
            if sd is not None or self._rngs[i] is None:
                self._rngs[i], _ = seeding.np_random(sd)
            self._reset_one(int(i))
        self._mode[:] = np.where(mask, kernels.MODE_RESET, kernels.MODE_SKIP)
        obs = self._observe(None)
        if partial:
            obs[keep] = saved_obs[keep]
            self._obs[keep] = saved_obs[keep]
            self.sensors.restore(saved_sensors, keep)
        if self.memory is not None:
            obs = self.memory.start(obs, mask)
        self._prev_done[mask] = False
        self._any_done = bool(self._prev_done.any())
        self._has_reset = True
        info = self._info(np.zeros(n, dtype=np.bool_))
        return obs, _masked_info(info, mask) if partial else info

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if not self._has_reset:
            raise RuntimeError("HyperloopSuspensionVectorEnv: call reset() before step()")
        n = self.num_envs
        shape = self._action_shape
        if isinstance(actions, np.ndarray) and actions.shape == shape and is_float(actions.dtype):
            act = actions  # the kernel reads float32 exactly as its float64 conversion
        else:
            act = check_action(actions, shape, self.sim.command_names)
        dt = act.dtype
        currents = self._currents.get(FLOAT32 if dt is FLOAT32 else dt) or self._bind_currents(dt)
        if not currents(act, self._base, self._neutral, self.action_scale, self._index, self._cmd):
            raise ValueError(f"actions must be finite (no NaN/inf), got {act!r}")
        mode = self.autoreset_mode
        prev_done = self._prev_done
        if self._any_done:
            if mode == AutoresetMode.DISABLED:
                raise RuntimeError(
                    "HyperloopSuspensionVectorEnv(autoreset_mode=DISABLED): environments "
                    f"{np.flatnonzero(prev_done).tolist()} ended; reset them with "
                    "reset(options={'reset_mask': mask}) before the next step"
                )
        s = self.sim
        choice = self._choice
        if self._advance is not None:
            meas = s.step_full(self._cmd, rows=self._advance)
        elif choice is None:
            meas = s.step_full(self._cmd, parallel=bool(self.parallel))
        else:
            threaded = choice.parallel()
            t0 = perf_counter()
            meas = s.step_full(self._cmd, parallel=threaded)
            choice.record(threaded, perf_counter() - t0)
        if self._any_done:  # NEXT_STEP: the ended environments reset on this step
            for i in np.flatnonzero(prev_done):
                self._reset_one(int(i))
        sensors = self.sensors
        plain = sensors.dropout is None and not sensors.noise_std and not sensors.delay
        e, b = np.empty, np.bool_
        terminated, truncated = e(n, b), e(n, b)  # returned: new arrays (3 rows of one: slower)
        done = self._spare_done  # internal: this step's done is the next step's prev_done
        any_done = (self._outcome or self._bind_outcome(meas))(
            meas,
            s.P,
            self._prev,
            self._mode,
            self._obs,
            self._offsets,
            PREVIEW,
            self._weights,
            self._terms,
            self._reward,
            prev_done,
            self._steps,
            self._max_steps,
            sensors.steps if plain else self._no_rows,
            _CONTACT,
            terminated,
            truncated,
            done,
        )
        obs = self._obs.copy() if plain else sensors.apply(self._obs, ~prev_done)
        memory = self.memory
        if memory is not None:
            if self._any_done:  # NEXT_STEP: the rows reset on this step start anew
                memory.push(obs, ~prev_done)
                obs = memory.start(obs, prev_done)
            else:
                obs = memory.push(obs)
        reward = self._reward.copy()
        if mode is _SAME_STEP and any_done:
            final_obs = obs.copy()
            final_info = self._info(terminated, force=True)
            for i in np.flatnonzero(done):
                self._reset_one(int(i))
            self._mode[:] = np.where(done, kernels.MODE_RESET, kernels.MODE_SKIP)
            saved = self._obs.copy()
            saved_sensors = self.sensors.snapshot()
            obs = self._observe(None)
            keep = ~done
            obs[keep] = saved[keep]
            self._obs[keep] = saved[keep]
            self.sensors.restore(saved_sensors, keep)
            if memory is not None:
                obs = memory.start(obs, done)
            info = self._info(np.zeros(n, dtype=np.bool_))
            info["final_obs"] = _final_obs(final_obs, done)
            info["_final_obs"] = done.copy()
            info["final_info"] = _masked_info(final_info, done)
            info["_final_info"] = done.copy()
            self._spare_done = prev_done
            self._prev_done = np.zeros(n, dtype=np.bool_)
            self._any_done = False
            return obs, reward, terminated, truncated, info
        self._spare_done = prev_done
        self._prev_done = done
        self._any_done = any_done
        info = self._info(terminated) if self.with_info else {}
        return obs, reward, terminated, truncated, info

    def _bind_currents(self, dt: np.dtype) -> Any:
        """:func:`kernels.commanded_currents` for actions of dtype ``dt`` (float32 or float64,
        two dimensions, any layout), called without numba's type dispatch
        (:mod:`hyperloop_env.physics.entry`)."""
        f = compiled_entry(
            kernels.commanded_currents,
            strided(dt, 2),
            self._base,
            self._neutral,
            float(self.action_scale),
            self._index,
            self._cmd,
        )
        self._currents[dt] = f
        return f

    def _bind_outcome(self, meas: np.ndarray) -> Any:
        """:func:`kernels.step_outcome` for this environment's buffers (all its own, their
        types fixed at construction), called without numba's type dispatch
        (:mod:`hyperloop_env.physics.entry`)."""
        flags = np.empty(self.num_envs, dtype=np.bool_)  # terminated, truncated: a new pair a step
        self._outcome = compiled_entry(
            kernels.step_outcome,
            meas,
            self.sim.P,
            self._prev,
            self._mode,
            self._obs,
            self._offsets,
            PREVIEW,
            self._weights,
            self._terms,
            self._reward,
            self._prev_done,
            self._steps,
            self._max_steps,
            self._no_rows,
            _CONTACT,
            flags,
            flags,
            self._spare_done,
        )
        return self._outcome

    def hold(self, mask: Any) -> None:
        """Rows whose physics :meth:`step` does not advance: a bool array of shape
        ``(num_envs,)`` (True: held), or None (every row advances, the default). A held row
        keeps its state and records; its observation, reward, termination and step count are
        computed from them as for any row, so they are not a trajectory of the model. For a
        rollout engine whose idle rows fly nothing it reads (their actions and values are
        ignored): the advanced rows' values are bit for bit those without the hold (rows
        never interact), on one thread. Resets do not change the hold."""
        if mask is None:
            self._advance = None
            return
        m = np.asarray(mask)
        if m.dtype != np.bool_ or m.shape != (self.num_envs,):
            raise ValueError(
                f"hold: mask must be a bool array of shape ({self.num_envs},) or None, got "
                f"{m.dtype} {m.shape}"
            )
        self._advance = np.flatnonzero(~m).astype(np.int64) if m.any() else None

    def _info(self, contact: np.ndarray, force: bool = False) -> dict[str, Any]:
        """The info dict (module docstring); empty with ``info=False`` unless ``force``."""
        if not (self.with_info or force):
            return {}
        r = self.sim.MEAS.copy()
        t = self._terms.T.copy()  # row k: reward term k of every environment
        m = np.ones(self.num_envs, dtype=np.bool_)
        info: dict[str, Any] = {}
        for key, mask_key, idx in self._info_views:
            info[key] = r[idx]
            info[mask_key] = m
        info["contact"] = contact.copy()
        info["_contact"] = m
        info["cost"] = costs_into(
            r[:, _GAP], r[:, _LAT], self._cost_limits, contact, np.empty(self.num_envs)
        )
        info["_cost"] = m
        if self.flat_info:  # every reward term its own (N,) entry: no nested dict
            for k, (name, _) in enumerate(_TERM_KEYS):
                info["reward_" + name] = t[k]
                info["_reward_" + name] = m
        else:
            terms: dict[str, Any] = {}
            for k, (name, mask_key) in enumerate(_TERM_KEYS):
                terms[name] = t[k]
                terms[mask_key] = m
            info["reward_terms"] = terms
            info["_reward_terms"] = m
        info["speed_kmh"] = current_speed_kmh(self._speed_kmh, r[:, _SPEED], self.sim.P[:, P_SPEED])
        info["_speed_kmh"] = m
        info["curve_radius_m"] = self._radius_m.copy()
        info["_curve_radius_m"] = m
        info["state"] = self.sim.Y.copy()
        info["_state"] = m
        return info

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
        state["_outcome"], state["_currents"] = None, {}  # compiled entries: bound anew
        return state

    def __repr__(self) -> str:
        name = self.config.scenario.name
        return f"HyperloopSuspensionVectorEnv({name}, num_envs={self.num_envs})"
