"""Gymnasium environment: active magnetic suspension of a hyperloop capsule.

The pieces it is made of, each in its own module: the configuration
(:mod:`hyperloop_env.config`), the physics (:mod:`hyperloop_env.physics`), the episode
start (:mod:`hyperloop_env.episode`), the observation (:mod:`hyperloop_env.observation`),
the reward terms (:mod:`hyperloop_env.reward`), the sensor model
(:mod:`hyperloop_env.sensors`) and the compiled kernels shared with the native vector
environment (:mod:`hyperloop_env.kernels`).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from hyperloop_env import kernels
from hyperloop_env.config import EnvConfig, ResolvedConfig
from hyperloop_env.episode import start_episode
from hyperloop_env.keywords import keyword_table, with_table
from hyperloop_env.observation import PREVIEW_DISTANCES_M, command_current
from hyperloop_env.observation_memory import ObservationMemory
from hyperloop_env.physics.actuators import ACTUATOR_KINDS
from hyperloop_env.physics.layout import P_SPEED, RECORD_FIELDS
from hyperloop_env.physics.params import ModelParams, SimulationParams
from hyperloop_env.physics.simulator import Simulator
from hyperloop_env.reward import REWARD_TERMS, reward_info
from hyperloop_env.safety import costs_into
from hyperloop_env.sensors import SensorModel

OBS_BOUND = float(np.finfo(np.float32).max)
"""Bound of the observation Box: every finite float32. Semantically ``Box(-inf, inf)``
(observations are unbounded but always finite); the finite bound avoids the
infinite-bound warnings of Gymnasium's and SB3's environment checkers."""

PREVIEW = np.array(PREVIEW_DISTANCES_M, dtype=np.float64)

_CONTACT = RECORD_FIELDS["contact"].start
_SPEED = RECORD_FIELDS["speed_m_s"].start
_GAP = RECORD_FIELDS["gap_excursion_m"]
_LAT = RECORD_FIELDS["lateral_offset_m"]

RENDER_MODES = ["human", "rgb_array"]

DEFAULT_RENDER_FPS = 1.0 / SimulationParams.control_dt_s
"""``metadata["render_fps"]`` of the classes: the control rate at the default interval (an
instance's is that of its own ``control_dt_s``, :func:`control_rate_hz`)."""

HUMAN_FPS = 50
"""Refresh rate of the ``render_mode="human"`` window [frames/s]: it shows every
``round(1/(HUMAN_FPS·control_dt_s))``-th control step (every 20th at 1 ms), in real time."""

CONSTRUCTOR_KEYWORDS: tuple[tuple[str, str, str], ...] = (
    ("config", "None", "an `EnvConfig` (keywords apply on top)"),
    ("render_mode", "None", '`"rgb_array"` or `"human"` (pygame)'),
    ("info", '"nested"', '`"flat"`: one `reward_<term>` entry per term'),
)
"""The environments' own constructor keywords, besides the configuration's."""


def control_rate_hz(cfg: ResolvedConfig) -> float:
    """Control steps per second of simulated time, 1/control_dt_s: ``render_fps`` of the
    environments, so that a video of one frame per step (Gymnasium's ``RecordVideo``)
    plays in real time."""
    return 1.0 / cfg.control_dt_s


def current_speed_kmh(entry_kmh: Any, record_speed_m_s: Any, entry_speed_m_s: Any) -> Any:
    """The speed now [km/h] (``info["speed_kmh"]``), from the record's speed v(t) [m/s]:
    the entry speed scaled by v(t)/v0, exactly the entry speed at constant speed (arrays
    of rows work alike, so the single and the vector environment agree bit for bit)."""
    return entry_kmh * (record_speed_m_s / entry_speed_m_s)


def make_config(config: EnvConfig | None, kwargs: dict[str, Any]) -> EnvConfig:
    """The environment's config from ``config=`` and/or flat keyword arguments (a
    ``scenario`` given positionally is in ``kwargs``)."""
    if config is None and not kwargs:
        return EnvConfig()
    return EnvConfig.from_kwargs(config, **kwargs)


def check_render_mode(render_mode: str | None, modes: list[str]) -> str | None:
    if render_mode is not None and render_mode not in modes:
        raise ValueError(f"render_mode must be None or one of {modes}, got {render_mode!r}")
    return render_mode


def check_action(action: Any, shape: tuple[int, ...], names: tuple[str, ...]) -> np.ndarray:
    """``action`` as a float64 array of ``shape``; ValueError naming ``action`` if it is not
    real numbers of that shape (a complex action is refused: casting would silently drop
    its imaginary part)."""
    try:
        complex_ = np.iscomplexobj(action)
    except (TypeError, ValueError):  # ragged or not array-like: the cast below says so
        complex_ = False
    if complex_:
        raise ValueError(
            f"action must be real numbers with shape {shape}, got a complex action "
            f"{action!r} (its imaginary part would be dropped)"
        )
    try:
        arr = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"action must be numeric with shape {shape}, got {action!r}") from exc
    if arr.shape != shape:
        raise ValueError(
            f"action must have shape {shape} (one entry per channel {', '.join(names)}), "
            f"got shape {arr.shape}"
        )
    return arr


def info_fields() -> tuple[tuple[str, int | slice], ...]:
    """(info key, record index) of the measured ``info`` entries: position, time, gaps,
    lateral offsets, then the applied currents of every actuator kind (its
    ``record_field``), then the accelerations."""
    return (
        ("position_m", RECORD_FIELDS["position_m"].start),
        ("time_s", RECORD_FIELDS["time_s"].start),
        ("gap_excursion_m", RECORD_FIELDS["gap_excursion_m"]),
        ("lateral_offset_m", RECORD_FIELDS["lateral_offset_m"]),
        ("guidance_gap_excursion_m", RECORD_FIELDS["lateral_offset_m"]),
        *((k.record_field, RECORD_FIELDS[k.record_field]) for k in ACTUATOR_KINDS.values()),
        ("acceleration_m_s2", RECORD_FIELDS["acceleration_heave_lateral"]),
    )


def make_memory(cfg: ResolvedConfig, n_rows: int) -> ObservationMemory | None:
    """The observation memory of ``n_rows`` rows, or None without memory options."""
    spec = cfg.observation
    if not spec.memory.active:
        return None
    base = cfg.base
    return ObservationMemory(spec, n_rows, base.vehicle.set_spacing_m, base.simulation.control_dt_s)


def action_arrays(cfg: ResolvedConfig) -> tuple[np.ndarray, np.ndarray]:
    """(neutral per channel, full-command index per channel) of the actuator set."""
    acts = cfg.actuators
    return np.array(acts.neutral()), np.array(acts.command_index(), dtype=np.int64)


class HyperloopSuspensionEnv(gym.Env[np.ndarray, np.ndarray]):
    """
    ## Description

    A hyperloop capsule (15 t body on four magnet units, 22 t of levitation frames) flies
    at 1000–2000 km/h over a flexible multi-span guideway (a steel tube on piers every
    30 m) with a stochastic irregularity and, optionally, a horizontal curve; guidance
    magnet pairs hold it laterally. The controller sets the coil currents; the goal is to
    keep every unit's gap excursion inside the clearance Ω = 8 mm (and the guidance gap
    excursions inside Ω_g = 8 mm) with little current effort and a comfortable ride.
    Physics: :mod:`hyperloop_env.physics` (``Simulator``, RK4, 2 substeps per 1 ms control
    step).

    ## Action Space

    ``Box(-1, 1, (n,), float32)``, one entry per channel of ``actuators``:

    | actuators               | n | entries                                                  |
    |-------------------------|---|----------------------------------------------------------|
    | `"levitation"` (default)| 4 | levitation coil currents FL, FR, RL, RR:                 |
    |                         |   | I_a = I0·(1 + action_scale·a_a) [A] (paper eq. 4)        |
    | `"levitation+guidance"` | 8 | the same, then one differential current per guidance     |
    |                         |   | pair gFL … gRR: ΔI_a = I_g0·action_scale·a_a [A]         |
    |                         |   | (left magnet I_g0 + ΔI, right I_g0 − ΔI)                 |

    I0 (``env.unwrapped.nominal_current_A``, ≈ 40.5 A) carries the vehicle at the nominal
    gap and I_g0 ≈ 16.2 A is the guidance bias (GuidanceParams design rule), so action 0 is
    the passive suspension; with ``"levitation"`` the guidance pairs stay at bias.
    Actions outside [-1, 1] are clipped to it (as the Box implies); the simulator then
    limits the currents to their physical range. A coil lag ``coil_time_constant_s``
    (default 2 ms) filters every applied current. NaN/inf actions or another shape raise
    ``ValueError``.

    ## Observation Space

    ``Box(-F, F, (23,), float32)`` for the default actuator set (31 with
    ``"levitation+guidance"``), F the largest float32
    (every finite value: semantically ``Box(-inf, inf)``, with finite bounds so that the
    environment checkers do not warn); layout in :mod:`hyperloop_env.observation`
    (``env.unwrapped.observation_spec``):

    | Num   | Observation                                        | scaling            |
    |-------|----------------------------------------------------|--------------------|
    | 0–3   | gap excursion s_a (FL, FR, RL, RR), + = gap opens   | / clearance Ω      |
    | 4–7   | gap rate, backward difference over one step        | / 1 m/s (0 at reset)|
    | 8–11  | guidance gap excursion z_a (lateral offset from the| / Ω_g (8 mm)       |
    |       | guideway), + = to the right                        |                    |
    | 12–13 | capsule heave and lateral acceleration             | / g                |
    | 14–17 | applied levitation coil current                    | I_a/I0 − 1         |
    | 18    | speed                                              | / (2000 km/h)      |
    | 19–22 | curvature at the capsule and 250, 500, 1000 m ahead| × 1e5 m            |

    With ``"levitation+guidance"`` the guidance gap rate (4, after entry 11, / 1 m/s) and
    the applied differential guidance currents ΔI_a/I_g0 (4, after the levitation currents)
    are inserted: 31 entries (``env.unwrapped.observation_spec.table()`` prints the layout).

    Memory options (off by default; layout in :mod:`hyperloop_env.observation`), appended
    after entry 22 (30 with guidance): ``observation_history=k`` adds the measured entries
    (0–17; 0–25 with guidance) of the previous k − 1 observations, most recent first;
    ``observation_front_preview=True`` adds 16 entries: the front units' (FL, FR) gap and
    guidance gap entries as measured τ − ℓ ago, τ = set spacing / v (16 m: 57.6 ms at
    1000 km/h) the time the rear units take to reach that guideway, ℓ = 0, 5, 10, 20 ms —
    the guideway the rear units meet ℓ ahead. Entries older than the episode are the reset
    observation's.

    Sensor model (:mod:`hyperloop_env.sensors`): ``sensor_noise_std`` adds Gaussian noise
    of that standard deviation to the *scaled* measured entries 0–17 (relative to each
    entry's scale: 0.01 is 80 µm on a gap); speed and curvature (map data) stay exact.
    ``sensor_delay=1`` returns the previous control step's observation (at reset: the reset
    observation). The full simulator state is privileged: ``env.unwrapped.sim``,
    ``env.unwrapped.state`` and ``info["state"]``, never in the observation.

    ## Rewards

    The reward of a step is the sum of the terms reported in ``info["reward_terms"]``
    (:mod:`hyperloop_env.reward`; each term a named function):

    - ``gap``      = −gap_weight · mean_a min((s_a/Ω)², 4)            (in [−4, 0]; −1 at Ω)
    - ``guidance`` = −guidance_weight · mean_a min((z_a/Ω_g)², 4)      (guidance gaps)
    - ``current``  = −current_weight · [mean_a ((I_a − I0)/I0)² + mean_a (ΔI_a/I_g0)²]
    - ``comfort``  = −comfort_weight · min((a_heave² + a_lat²)/g², 100)
    - ``survival`` = +survival_weight while there is no contact (0 at the contact step)
    - ``contact``  = −contact_weight at the contact step, else 0

    The weight of term ``t`` is the keyword ``t_weight`` (defaults in the table of
    arguments below: gap 1, guidance 1, current 0.05, comfort 1, survival 1, contact 100).

    ## Starting State

    Static equilibrium at the start of the track section (capsule centre at x = 10 m), all
    currents at their bias, on a guideway drawn from the episode's seed (irregularity and
    the scenario's other disturbances).

    ## Episode End

    1. Termination: contact, i.e. any |s_a| ≥ Ω or any guidance gap excursion |z_a| ≥ Ω_g
       (the simulator's contact flag; also set if the state diverges).
    2. Truncation: the capsule has covered ``track_length_m`` (default 2000 m: 7200 steps,
       7.2 s at 1000 km/h; 3600 steps at 2000 km/h). No ``TimeLimit`` wrapper is used.

    Calling ``step`` after the episode ended without ``reset`` raises ``RuntimeError``.
    ``reset(options=...)`` takes no options (they are ignored).

    ## Rendering

    ``render_mode="rgb_array"``: ``render()`` returns a (360, 640, 3) uint8 frame
    (:mod:`hyperloop_env.rendering`, pygame drawing on an off-screen surface, ~2 ms, no
    display needed). ``metadata["render_fps"]`` is the control rate 1/``control_dt_s``
    (1000 at 1 ms): a video of one frame per step, as Gymnasium's ``RecordVideo`` writes
    it, plays in real time. ``"human"``: a pygame window refreshed every
    ``round(1/(50·control_dt_s))`` control steps (every 20 steps at 1 ms, i.e. in real time
    at 50 fps); ``render()`` returns None, as Gymnasium's human mode does. Without a
    display it warns once (``UserWarning`` saying to use ``"rgb_array"``), draws
    off-screen and the episode runs on (as CartPole does on a headless machine).

    ## Arguments

    ```python
    >>> import gymnasium as gym, hyperloop_env
    >>> env = gym.make("HyperloopSuspension-v0", scenario="paper-2000-curved",
    ...                irregularity="maglev-rough", sensor_noise_std=0.01)
    >>> from hyperloop_env.config import EnvConfig
    >>> env = gym.make("HyperloopSuspension-v0", config=EnvConfig(scenario="random"))

    ```

    [keyword table]

    Physical overrides left at ``None`` keep the scenario's value. Unknown keywords raise
    ``TypeError`` listing the valid ones; unknown scenarios or invalid values raise
    ``ValueError`` naming the valid choices or the offending argument.

    ## Info

    ``position_m`` [m], ``time_s`` [s], ``gap_excursion_m`` (4,) [m], ``lateral_offset_m``
    (4,) [m] (= ``guidance_gap_excursion_m``), ``current_A`` (4,) applied levitation currents
    [A], ``guidance_current_A`` (4,) applied differential guidance currents [A],
    ``acceleration_m_s2`` (heave, lateral) [m/s²], ``contact``, ``cost`` (the safety cost of
    the step, Safety-Gymnasium's convention: by default 1 if any gap or guidance-gap
    excursion exceeds its clearance less ``safety_margin_mm``, else 0; ``safety_cost=
    "continuous"`` for a graded cost; always ≥ 1 at a contact; it does not enter the reward:
    :mod:`hyperloop_env.safety`), ``reward_terms`` (dict), ``speed_kmh`` (the speed now: it
    changes under the ``speed_profile`` disturbance, as the observation's speed entry does),
    ``curve_radius_m``, ``state`` (full simulator state vector, privileged).
    ``info="flat"`` (constructor keyword) reports each reward term as its own entry
    ``reward_<term>`` instead of the ``reward_terms`` dict, for clients that stack the
    info of a batch and cannot take a nested dict: TorchRL's ``GymEnv(id, num_envs=N)``
    needs it (``GymEnv(id)`` of one environment takes the default).

    ## Version History

    * v0: Initial version.
    """

    __doc__ = with_table(__doc__, keyword_table(EnvConfig, CONSTRUCTOR_KEYWORDS))
    metadata = {"render_modes": RENDER_MODES, "render_fps": DEFAULT_RENDER_FPS}

    def __init__(
        self,
        scenario: str | None = None,
        *,
        config: EnvConfig | None = None,
        render_mode: str | None = None,
        info: str = "nested",
        **kwargs: Any,
    ) -> None:
        if info not in ("nested", "flat"):
            raise ValueError(f"info must be 'nested' or 'flat', got {info!r}")
        self.flat_info = info == "flat"
        if scenario is not None:
            kwargs["scenario"] = scenario
        self.env_config = make_config(config, kwargs)
        self.config: ResolvedConfig = self.env_config.resolve()
        self.render_mode = check_render_mode(render_mode, self.metadata["render_modes"])
        cfg = self.config
        self.metadata = {**type(self).metadata, "render_fps": control_rate_hz(cfg)}
        self.observation_spec = cfg.observation
        self.action_scale = cfg.action_scale
        n_act = cfg.actuators.size
        n_obs = self.observation_spec.base_size  # the memory blocks (if any) follow
        self.action_space = spaces.Box(-1.0, 1.0, (n_act,), dtype=np.float32)
        self.observation_space = spaces.Box(
            -OBS_BOUND, OBS_BOUND, (self.observation_spec.size,), dtype=np.float32
        )

        self.sim = Simulator(cfg.base)
        self._cost_limits = cfg.cost_limits
        self._cost1, self._contact1 = np.zeros(1), np.zeros(1, dtype=np.bool_)
        self._weights = np.array(cfg.reward.as_tuple())
        self._neutral, self._index = action_arrays(cfg)
        self._offsets = self.observation_spec.offsets()
        self.sensors = SensorModel(cfg.sensors, 1, n_obs, self.observation_spec.n_measured)
        self.memory = make_memory(cfg, 1)
        self._cmd = np.zeros((1, self.sim.n_commands))
        self._info_fields = info_fields()
        self._prev = np.zeros((1, 2 * len(self.sim.unit_names)))
        self._obs = np.zeros((1, n_obs), dtype=np.float32)
        self._reward = np.zeros(1)
        self._terms = np.zeros((1, len(REWARD_TERMS)))
        self._first = np.full(1, kernels.MODE_RESET, dtype=np.int8)
        self._later = np.full(1, kernels.MODE_STEP, dtype=np.int8)
        self._stepped = np.ones(1, dtype=np.int64)
        self._set_episode_params(cfg.base)
        self._steps = 0
        self._done = True
        self._has_reset = False
        self._render_every = max(1, round(1.0 / (HUMAN_FPS * cfg.control_dt_s)))
        self._renderer: Any = None

    # ---- public helpers ------------------------------------------------------------------
    @property
    def params(self) -> ModelParams:
        """Parameters of the current episode."""
        return self.sim.params

    @property
    def nominal_current_A(self) -> float:
        """I0 of the current episode [A] (action 0)."""
        return self.sim.nominal_current_A

    @property
    def max_current_A(self) -> float:
        return self.sim.max_current_A

    @property
    def state(self) -> np.ndarray:
        """Privileged full simulator state (a copy; layout in ``physics.layout``)."""
        return self.sim.y.copy()

    @property
    def max_episode_steps(self) -> int:
        """Control steps of the current episode's track section."""
        return self._max_steps

    def action_to_current(self, action: Any) -> np.ndarray:
        """Commanded currents [A] of every action channel for ``action`` (clipped to [-1, 1]
        as in ``step``): ``reference·(neutral + action_scale·a)`` per channel
        (:func:`~hyperloop_env.observation.command_current`; levitation coils
        I0·(1 + s·a), guidance pairs the differential current I_g0·s·a)."""
        a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        return command_current(self._base[0], self._neutral, self.action_scale, a)

    # ---- gymnasium API ---------------------------------------------------------------------
    def _set_episode_params(self, params: ModelParams) -> None:
        self._max_steps = self.sim.episode_steps
        self._speed_kmh = params.condition.speed_kmh
        self._radius_m = params.condition.curve_radius_m
        self._base = self.sim.command_reference_A[None]

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        if isinstance(seed, np.ndarray) and seed.ndim == 0:
            seed = seed[()]  # a NumPy scalar
        if isinstance(seed, np.integer):  # numpy integers are ints
            seed = int(seed)
        super().reset(seed=seed)
        ep = start_episode(self.config, self.np_random)
        self.sensors.start_episode(0, ep.noise_key)
        self.sensors.set_episode_hook(0, ep.sensor_hook)
        self.sim.reset(
            ep.sim_seed,
            None if ep.params is self.sim.params else ep.params,
            profile_offset=ep.profile_offset,
        )
        self._set_episode_params(ep.params)
        self._cmd[0] = self.sim.neutral_command
        obs = self._observe(self._first, None)
        if self.memory is not None:
            obs = self.memory.start(obs[None])[0]
        self._steps = 0
        self._done = False
        self._has_reset = True
        info = self._info(self.sim.meas, False)
        if self.render_mode == "human":
            self.render()
        return obs, info

    def _observe(self, mode: np.ndarray, stepped: np.ndarray | None) -> np.ndarray:
        rec = self.sim.meas[None]
        P = self.sim.P[None]
        kernels.observe(rec, P, self._prev, mode, self._obs, self._offsets, PREVIEW)
        kernels.reward(rec, P, mode, self._weights, self._terms, self._reward)
        return self.sensors.apply(self._obs, stepped)[0]

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if self._done:
            if not self._has_reset:
                raise RuntimeError("HyperloopSuspensionEnv: call reset() before step()")
            raise RuntimeError(
                "HyperloopSuspensionEnv: step() called after the episode ended "
                "(terminated or truncated); call reset() first"
            )
        act = check_action(action, self.action_space.shape, self.sim.command_names)
        if not kernels.commanded_currents(
            act[None], self._base, self._neutral, self.action_scale, self._index, self._cmd
        ):
            raise ValueError(f"action must be finite (no NaN/inf), got {act!r}")
        rec = self.sim.step_full(self._cmd[0])
        obs = self._observe(self._later, self._stepped)
        if self.memory is not None:
            obs = self.memory.push(obs[None])[0]
        self._steps += 1
        terminated = bool(rec[_CONTACT] > 0.5)
        truncated = (not terminated) and self._steps >= self._max_steps
        self._done = terminated or truncated
        info = self._info(rec, terminated)
        if self.render_mode == "human" and (self._steps % self._render_every == 0 or self._done):
            self.render()
        return obs, float(self._reward[0]), terminated, truncated, info

    def _info(self, rec: np.ndarray, contact: bool) -> dict[str, Any]:
        r = rec.copy()
        if self.flat_info:
            info = self._nested_info(r, contact)
            terms = info.pop("reward_terms")
            info.update({f"reward_{k}": v for k, v in terms.items()})
            return info
        return self._nested_info(r, contact)

    def _step_cost(self, r: np.ndarray, contact: bool) -> float:
        """The safety cost of the step whose record is ``r`` (:mod:`hyperloop_env.safety`)."""
        self._contact1[0] = contact
        costs_into(r[None, _GAP], r[None, _LAT], self._cost_limits, self._contact1, self._cost1)
        return float(self._cost1[0])

    def _nested_info(self, r: np.ndarray, contact: bool) -> dict[str, Any]:
        info: dict[str, Any] = {}
        for key, idx in self._info_fields:
            info[key] = float(r[idx]) if isinstance(idx, int) else r[idx]
        return {
            **info,
            "contact": contact,
            "cost": self._step_cost(r, contact),
            "reward_terms": reward_info(self._terms[0]),
            "speed_kmh": current_speed_kmh(
                self._speed_kmh, float(r[_SPEED]), float(self.sim.P[P_SPEED])
            ),
            "curve_radius_m": self._radius_m,
            "state": self.sim.y.copy(),
        }

    # ---- rendering -----------------------------------------------------------------------
    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn(
                "You are calling render method without specifying any render mode. "
                'Pass render_mode="rgb_array" or "human" to gymnasium.make.'
            )
            return None
        if not self._has_reset:
            raise RuntimeError("HyperloopSuspensionEnv: call reset() before render()")
        from hyperloop_env.rendering import Renderer

        if self._renderer is None:
            # human: the window's rate, one frame every _render_every steps in real time
            fps = 1.0 / (self._render_every * self.config.control_dt_s)
            self._renderer = Renderer(self.render_mode, fps)
        return self._renderer.draw(self.sim.meas, self.sim.P, self.sim.params)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_renderer"] = None
        return state
