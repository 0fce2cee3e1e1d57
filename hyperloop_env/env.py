"""Gymnasium environment: active magnetic suspension of a hyperloop capsule.

The compiled helpers of this module (``_commanded_currents``, ``_observe``, ``_add_noise``)
are shared with :mod:`hyperloop_env.vector_env` so that the single and the batched
environments produce bit-identical observations and rewards.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numba as nb
import numpy as np
from gymnasium import spaces

from hyperloop_env.observation import (
    CURVATURE_SCALE_M,
    GAP_RATE_SCALE_M_S,
    OBS_SIZE,
    PREVIEW_DISTANCES_M,
    SPEED_SCALE_M_S,
    action_to_current,
)
from hyperloop_env.physics.layout import (
    M_ACC_HEAVE,
    M_ACC_LAT,
    M_CONTACT,
    M_GAP,
    M_I,
    M_LAT,
    M_T,
    M_X,
    P_CLEAR,
    P_CURVE0,
    P_DT,
    P_G,
    P_I0,
    P_KAPPA,
    P_LATCLEAR,
    P_SPEED,
    P_TRANS,
)
from hyperloop_env.physics.model import Simulator
from hyperloop_env.physics.params import ModelParams
from hyperloop_env.scenarios import (
    DEFAULT_SCENARIO,
    OVERRIDE_NAMES,
    ScenarioConfig,
    build_config,
)

# ---- reward -----------------------------------------------------------------------------
REWARD_TERMS: tuple[str, ...] = ("gap", "current", "comfort", "survival", "contact")
"""Names of the reward terms, in the order of ``info["reward_terms"]``."""
GAP_TERM_CAP = 4.0  # (s/Ω)² is capped at 4 (|s| = 2Ω): only matters at the contact step
COMFORT_TERM_CAP = 100.0  # (a_heave² + a_lat²)/g² capped at 100 (10 g)
OBS_BOUND = float(np.finfo(np.float32).max)
"""Bound of the observation Box: every finite float32. Semantically ``Box(-inf, inf)``
(observations are unbounded but always finite); the finite bound avoids the
infinite-bound warnings of Gymnasium's and SB3's environment checkers."""
N_NOISY = 18  # sensor noise acts on obs[0:18] (gap … current), not on speed/curvature

_PREVIEW = np.array(PREVIEW_DISTANCES_M, dtype=np.float64)
_N_PREVIEW = len(PREVIEW_DISTANCES_M)
_CURV0 = OBS_SIZE - _N_PREVIEW


# ---------------------------------------------------------------------------------------
# compiled helpers (row i of 2-D arrays = environment i)
# ---------------------------------------------------------------------------------------


@nb.njit(cache=True)
def _commanded_currents(action, i0, scale, out) -> bool:  # pragma: no cover - compiled
    """out = I0·(1 + scale·clip(a, −1, 1)) (as :func:`observation.action_to_current`);
    False if any action is not finite."""
    n = action.shape[0]
    for i in range(n):
        for a in range(4):
            x = action[i, a]
            if not math.isfinite(x):
                return False
            x = -1.0 if x < -1.0 else (1.0 if x > 1.0 else x)
            out[i, a] = i0[i] * (1.0 + scale * x)
    return True


@nb.njit(cache=True)
def _observe(
    rec, P, prev_gap, mode, obs, reward, terms, w_gap, w_cur, w_acc, bonus, penalty, preview
):  # pragma: no cover - compiled
    """Observation (see :mod:`hyperloop_env.observation`) and reward terms from the
    records ``rec``, row by row according to ``mode[i]``: 0 skip the row, 1 a reset (gap
    rate and reward zero), 2 a step.

    Updates ``prev_gap`` to the current gaps. Non-finite values (a diverged state, which
    the simulator flags as contact) are replaced by 0 in the observation and by the caps
    in the reward."""
    n = rec.shape[0]
    npv = preview.shape[0]
    c0 = obs.shape[1] - npv
    for i in range(n):
        if mode[i] == 0:
            continue
        first = mode[i] == 1
        r = rec[i]
        p = P[i]
        clear = p[P_CLEAR]
        latc = p[P_LATCLEAR]
        i0 = p[P_I0]
        g = p[P_G]
        inv_dt = 1.0 / p[P_DT]
        o = obs[i]
        sgap = 0.0
        scur = 0.0
        for a in range(4):
            s = r[M_GAP + a]
            o[a] = s / clear
            if first:
                o[4 + a] = 0.0
            else:
                o[4 + a] = (s - prev_gap[i, a]) * inv_dt / GAP_RATE_SCALE_M_S
            prev_gap[i, a] = s
            o[8 + a] = r[M_LAT + a] / latc
            e = r[M_I + a] / i0 - 1.0
            o[14 + a] = e
            q = (s / clear) ** 2
            sgap += q if q < GAP_TERM_CAP else GAP_TERM_CAP
            scur += e * e
        ah = r[M_ACC_HEAVE]
        al = r[M_ACC_LAT]
        o[12] = ah / g
        o[13] = al / g
        o[18] = p[P_SPEED] / SPEED_SCALE_M_S
        x = r[M_X]
        for k in range(npv):
            u = (x + preview[k] - p[P_CURVE0]) / p[P_TRANS]
            u = 0.0 if u <= 0.0 else (1.0 if u >= 1.0 else u)
            o[c0 + k] = p[P_KAPPA] * u * CURVATURE_SCALE_M
        for j in range(obs.shape[1]):
            if not math.isfinite(o[j]):
                o[j] = 0.0
        if first:
            for j in range(terms.shape[1]):
                terms[i, j] = 0.0
            reward[i] = 0.0
            continue
        contact = r[M_CONTACT] > 0.5
        if not sgap <= 4.0 * GAP_TERM_CAP:  # NaN
            sgap = 4.0 * GAP_TERM_CAP
        if not scur < 1e12:
            scur = 1e12
        cq = (ah * ah + al * al) / (g * g)
        if not cq < COMFORT_TERM_CAP:
            cq = COMFORT_TERM_CAP
        t0 = -w_gap * 0.25 * sgap
        t1 = -w_cur * 0.25 * scur
        t2 = -w_acc * cq
        t3 = 0.0 if contact else bonus
        t4 = -penalty if contact else 0.0
        terms[i, 0] = t0
        terms[i, 1] = t1
        terms[i, 2] = t2
        terms[i, 3] = t3
        terms[i, 4] = t4
        reward[i] = t0 + t1 + t2 + t3 + t4


@nb.njit(cache=True)
def _splitmix64(x):  # pragma: no cover - compiled
    z = x + np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@nb.njit(cache=True)
def _add_noise(obs, keys, counters, std, n_noisy):  # pragma: no cover - compiled
    """obs[i, :n_noisy] += std·N(0, 1), the normal draws a pure function of (keys[i],
    counters[i], channel) (counter-based, so a batch matches single environments)."""
    two53 = 1.0 / 9007199254740992.0
    for i in range(obs.shape[0]):
        base = _splitmix64(keys[i] ^ (counters[i] * np.uint64(0x100000001B3)))
        for j in range(n_noisy):
            z1 = _splitmix64(base + np.uint64(2 * j))
            z2 = _splitmix64(base + np.uint64(2 * j + 1))
            u1 = ((z1 >> np.uint64(11)) + np.uint64(1)) * two53  # (0, 1]
            u2 = (z2 >> np.uint64(11)) * two53
            obs[i, j] += std * math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


def _check_action(action: Any, shape: tuple[int, ...]) -> np.ndarray:
    try:
        arr = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"action must be numeric with shape {shape}, got {action!r}") from exc
    if arr.shape != shape:
        raise ValueError(
            f"action must have shape {shape} (one entry per unit FL, FR, RL, RR), "
            f"got shape {arr.shape}"
        )
    return arr


def _check_weight(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    if value < 0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return float(value)


def _episode_steps(params: ModelParams) -> int:
    """Control steps to cover the track section: ceil(track_length / (v·dt))."""
    dx = params.condition.speed_m_s * params.simulation.control_dt_s
    return max(1, math.ceil(params.simulation.track_length_m / dx - 1e-9))


def _env_options(
    action_scale: float,
    sensor_noise_std: float,
    sensor_delay: int,
    gap_weight: float,
    current_weight: float,
    comfort_weight: float,
    survival_bonus: float,
    contact_penalty: float,
) -> dict[str, float]:
    """Validated non-physical options (shared with the vector env)."""
    if (
        isinstance(action_scale, bool)
        or not isinstance(action_scale, int | float)
        or not (0 < action_scale <= 10)
    ):
        raise ValueError(f"action_scale must be a number in (0, 10], got {action_scale!r}")
    if sensor_delay not in (0, 1) or isinstance(sensor_delay, bool):
        raise ValueError(f"sensor_delay must be 0 or 1 (control steps), got {sensor_delay!r}")
    return {
        "action_scale": float(action_scale),
        "sensor_noise_std": _check_weight("sensor_noise_std", sensor_noise_std),
        "sensor_delay": int(sensor_delay),
        "gap_weight": _check_weight("gap_weight", gap_weight),
        "current_weight": _check_weight("current_weight", current_weight),
        "comfort_weight": _check_weight("comfort_weight", comfort_weight),
        "survival_bonus": _check_weight("survival_bonus", survival_bonus),
        "contact_penalty": _check_weight("contact_penalty", contact_penalty),
    }


ENV_ARGUMENTS: tuple[str, ...] = (
    "scenario",
    *OVERRIDE_NAMES,
    "action_scale",
    "sensor_noise_std",
    "sensor_delay",
    "gap_weight",
    "current_weight",
    "comfort_weight",
    "survival_bonus",
    "contact_penalty",
    "render_mode",
)
"""Keyword arguments of the environments (the vector env adds ``num_envs``)."""


def _reject_unknown(unknown: dict[str, Any]) -> None:
    if unknown:
        raise ValueError(
            f"unknown argument(s) {sorted(unknown)}; valid arguments: {list(ENV_ARGUMENTS)}"
        )


def _check_render_mode(render_mode: str | None, modes: list[str]) -> str | None:
    if render_mode is not None and render_mode not in modes:
        raise ValueError(f"render_mode must be None or one of {modes}, got {render_mode!r}")
    return render_mode


def _configure(env: Any, scenario: str, render_mode: str | None, args: dict[str, Any]) -> None:
    """Shared constructor work of the single and the vector environment: validate the
    scenario, the physical overrides and the options in ``args`` (the constructor's keyword
    arguments) and set ``config``, ``options``, ``render_mode``, ``action_scale`` and the
    reward weights on ``env``."""
    env.config = build_config(scenario, **{k: args[k] for k in OVERRIDE_NAMES})
    env.options = _env_options(
        args["action_scale"],
        args["sensor_noise_std"],
        args["sensor_delay"],
        args["gap_weight"],
        args["current_weight"],
        args["comfort_weight"],
        args["survival_bonus"],
        args["contact_penalty"],
    )
    env.render_mode = _check_render_mode(render_mode, env.metadata["render_modes"])
    env.action_scale = env.options["action_scale"]
    env._noise = env.options["sensor_noise_std"]
    env._delay = env.options["sensor_delay"]
    env._weights = tuple(
        env.options[k]
        for k in (
            "gap_weight",
            "current_weight",
            "comfort_weight",
            "survival_bonus",
            "contact_penalty",
        )
    )


class HyperloopSuspensionEnv(gym.Env[np.ndarray, np.ndarray]):
    """
    ## Description

    A hyperloop capsule (15 t body on four magnet units, 22 t of levitation frames) flies
    at 1000–2000 km/h over a flexible multi-span guideway (a steel tube on piers every
    30 m) with a stochastic irregularity and, optionally, a horizontal curve. The
    controller sets the four coil currents; the goal is to keep every unit's gap excursion
    inside the clearance Ω = 8 mm (and the lateral offsets inside the lateral clearance)
    with little current effort and a comfortable ride. Physics: :mod:`hyperloop_env.physics`
    (``Simulator``, RK4, 4 substeps per 1 ms control step).

    ## Action Space

    ``Box(-1, 1, (4,), float32)``, one entry per unit (FL, FR, RL, RR), mapped to the
    commanded coil current ``I_a = I0·(1 + action_scale·a_a)`` [A]
    (:func:`hyperloop_env.observation.action_to_current`; ``env.unwrapped.action_to_current``).
    I0 (``env.unwrapped.nominal_current_A``, ≈ 40.5 A) carries the vehicle at the nominal
    gap, so action 0 is the passive suspension. Actions outside [-1, 1] are clipped to it
    (as the Box implies); the simulator then limits the current to [0, I_max]. A coil lag
    ``coil_time_constant_s`` (default 2 ms) filters the applied current. NaN/inf actions
    or a shape other than (4,) raise ``ValueError``.

    ## Observation Space

    ``Box(-F, F, (23,), float32)`` with F the largest float32 (i.e. every finite value:
    semantically ``Box(-inf, inf)``, with finite bounds so that the environment checkers do
    not warn), laid out by :mod:`hyperloop_env.observation`:

    | Num   | Observation                                        | scaling            |
    |-------|----------------------------------------------------|--------------------|
    | 0–3   | gap excursion s_a (FL, FR, RL, RR), + = gap opens   | / clearance Ω      |
    | 4–7   | gap rate, backward difference over one step        | / 1 m/s (0 at reset)|
    | 8–11  | lateral offset of each unit from its rail          | / lateral clearance|
    | 12–13 | capsule heave and lateral acceleration             | / g                |
    | 14–17 | applied coil current                               | I_a/I0 − 1         |
    | 18    | speed                                              | / (2000 km/h)      |
    | 19–22 | curvature at the capsule and 250, 500, 1000 m ahead| × 1e5 m            |

    Optional sensor effects: ``sensor_noise_std`` adds Gaussian noise of that standard
    deviation to the *scaled* entries 0–17 (so it is relative to each entry's scale: 0.01
    is 80 µm on a gap); speed and curvature (map data) stay exact. ``sensor_delay=1``
    returns the previous control step's observation (at reset: the reset observation).
    The full simulator state is privileged: ``env.unwrapped.sim``, ``env.unwrapped.state``
    and ``info["state"]``, never in the observation.

    ## Rewards

    The reward of a step is the sum of the terms reported in ``info["reward_terms"]``:

    - ``gap``      = −gap_weight · mean_a min((s_a/Ω)², 4)            (in [−4, 0]; −1 at Ω)
    - ``current``  = −current_weight · mean_a ((I_a − I0)/I0)²         (applied currents)
    - ``comfort``  = −comfort_weight · min((a_heave² + a_lat²)/g², 100)
    - ``survival`` = +survival_bonus while there is no contact (0 at the contact step)
    - ``contact``  = −contact_penalty at the contact step, else 0

    Defaults: gap_weight 1, current_weight 0.05, comfort_weight 1, survival_bonus 1,
    contact_penalty 100. The survival bonus is needed for PPO: without it every step
    costs (the gap term alone averages ≈ −0.04 for the passive vehicle), so over a
    7200-step episode crashing early (−100 once) would beat flying; with it a step
    without contact is worth ≈ +1 and staying in the air always pays.

    ## Starting State

    Static equilibrium at the start of the track section (capsule centre at x = 10 m), all
    currents at I0, on a guideway irregularity drawn from the episode's seed.

    ## Episode End

    1. Termination: contact, i.e. any |s_a| ≥ Ω or any |lateral offset| ≥ the lateral
       clearance (the simulator's contact flag; also set if the state diverges).
    2. Truncation: the capsule has covered ``track_length_m`` (default 2000 m: 7200 steps,
       7.2 s at 1000 km/h; 3600 steps at 2000 km/h). No ``TimeLimit`` wrapper is used.

    Calling ``step`` after the episode ended without ``reset`` raises ``RuntimeError``.
    ``reset(options=...)`` takes no options (they are ignored).

    ## Rendering

    ``render_mode="rgb_array"``: ``render()`` returns a (360, 640, 3) uint8 frame
    (:mod:`hyperloop_env.rendering`, pygame drawing on an off-screen surface, ~2 ms, no
    display needed). ``"human"``: a pygame window refreshed every
    ``round(1/(render_fps·control_dt_s))`` control steps (every 20 steps at 1 ms, i.e. in
    real time at 50 fps); without a display it raises ``RuntimeError``.

    ## Arguments

    ```python
    >>> import gymnasium as gym, hyperloop_env
    >>> env = gym.make("HyperloopSuspension-v0", scenario="paper-2000-curved",
    ...                irregularity="maglev-rough", sensor_noise_std=0.01)

    ```

    | Parameter              | Default                 | Description                            |
    |------------------------|-------------------------|----------------------------------------|
    | `scenario`             | `"paper-1000-straight"` | named scenario (:mod:`scenarios`)      |
    | `speed_kmh`            | scenario                | speed [km/h]                           |
    | `curve_radius_m`       | scenario                | radius [m], `math.inf` = straight      |
    | `cant_deg`             | 0                       | cant of the curve [deg]                |
    | `track_length_m`       | 2000                    | length of the track section [m]        |
    | `irregularity`         | `"maglev"`              | irregularity class or `"none"`         |
    | `control_dt_s`         | 1e-3                    | control interval [s]                   |
    | `clearance_m`          | 0.008                   | gap clearance Ω [m]                    |
    | `magnet`               | `"repelling"`           | or `"attracting"` (open-loop unstable) |
    | `coil_time_constant_s` | 2e-3                    | coil current lag τ [s] (0 = ideal)     |
    | `action_scale`         | 1.0                     | I = I0·(1 + action_scale·a)            |
    | `sensor_noise_std`     | 0.0                     | noise std on scaled obs[0:18]          |
    | `sensor_delay`         | 0                       | 0 or 1 control step                    |
    | `gap_weight`           | 1.0                     | weight of the gap term                 |
    | `current_weight`       | 0.05                    | weight of the current-effort term      |
    | `comfort_weight`       | 1.0                     | weight of the comfort term             |
    | `survival_bonus`       | 1.0                     | per step without contact               |
    | `contact_penalty`      | 100.0                   | paid once, at contact                  |
    | `render_mode`          | None                    | `"rgb_array"` or `"human"` (pygame)    |

    Physical overrides left at ``None`` keep the scenario's value. Unknown scenarios or
    invalid values raise ``ValueError`` naming the valid choices or the offending field.

    ## Info

    ``position_m``, ``time_s``, ``gap_excursion_m`` (4,), ``lateral_offset_m`` (4,),
    ``current_A`` (4,) applied, ``acceleration_m_s2`` (heave, lateral), ``contact``,
    ``reward_terms`` (dict), ``speed_kmh``, ``curve_radius_m``, ``state`` (full simulator
    state vector, privileged).

    ## Version History

    * v0: Initial version.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 50}

    def __init__(
        self,
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
        self.config: ScenarioConfig
        _configure(self, scenario, render_mode, locals())
        self.action_space = spaces.Box(-1.0, 1.0, (4,), dtype=np.float32)
        self.observation_space = spaces.Box(-OBS_BOUND, OBS_BOUND, (OBS_SIZE,), dtype=np.float32)

        self.sim = Simulator(self.config.base)
        self._set_episode_params(self.config.base)
        self._cmd = np.zeros((1, 4))
        self._prev_gap = np.zeros((1, 4))
        self._obs = np.zeros((1, OBS_SIZE), dtype=np.float32)
        self._obs_prev = np.zeros(OBS_SIZE, dtype=np.float32)
        self._reward = np.zeros(1)
        self._terms = np.zeros((1, len(REWARD_TERMS)))
        self._first = np.ones(1, dtype=np.int8)
        self._later = np.full(1, 2, dtype=np.int8)
        self._noise_key = np.zeros(1, dtype=np.uint64)
        self._noise_ctr = np.zeros(1, dtype=np.uint64)
        self._steps = 0
        self._done = True
        self._has_reset = False
        self._render_every = max(
            1, round(1.0 / (self.metadata["render_fps"] * self.config.base.simulation.control_dt_s))
        )
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
        """Commanded currents [A] for ``action`` (clipped to [-1, 1] as in ``step``)."""
        a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        return action_to_current(a, self.nominal_current_A, self.action_scale)

    # ---- gymnasium API ---------------------------------------------------------------------
    def _set_episode_params(self, params: ModelParams) -> None:
        self._max_steps = _episode_steps(params)
        self._speed_kmh = params.condition.speed_kmh
        self._radius_m = params.condition.curve_radius_m
        self._i0 = np.array([self.sim.nominal_current_A])

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        rng = self.np_random
        params = self.config.sample(rng)
        sim_seed = int(rng.integers(0, 2**63 - 1))
        self._noise_key[0] = np.uint64(rng.integers(0, 2**63 - 1))
        self._noise_ctr[0] = 0
        self.sim.reset(sim_seed, None if params is self.sim.params else params)
        self._set_episode_params(params)
        rec = self.sim.meas
        P = self.sim.P
        _observe(
            rec[None],
            P[None],
            self._prev_gap,
            self._first,
            self._obs,
            self._reward,
            self._terms,
            *self._weights,
            _PREVIEW,
        )
        obs = self._finish_obs()
        if self._delay:
            self._obs_prev[:] = obs
        self._steps = 0
        self._done = False
        self._has_reset = True
        info = self._info(rec, False)
        if self.render_mode == "human":
            self.render()
        return obs, info

    def _finish_obs(self) -> np.ndarray:
        if self._noise > 0.0:
            _add_noise(self._obs, self._noise_key, self._noise_ctr, self._noise, N_NOISY)
            self._noise_ctr += np.uint64(1)
        return self._obs[0].copy()

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if self._done:
            if not self._has_reset:
                raise RuntimeError("HyperloopSuspensionEnv: call reset() before step()")
            raise RuntimeError(
                "HyperloopSuspensionEnv: step() called after the episode ended "
                "(terminated or truncated); call reset() first"
            )
        act = _check_action(action, (4,))
        if not _commanded_currents(act[None], self._i0, self.action_scale, self._cmd):
            raise ValueError(f"action must be finite (no NaN/inf), got {act!r}")
        rec = self.sim.step_record(self._cmd[0])
        _observe(
            rec[None],
            self.sim.P[None],
            self._prev_gap,
            self._later,
            self._obs,
            self._reward,
            self._terms,
            *self._weights,
            _PREVIEW,
        )
        obs = self._finish_obs()
        if self._delay:
            obs, self._obs_prev = self._obs_prev, obs
        self._steps += 1
        terminated = bool(rec[M_CONTACT] > 0.5)
        truncated = (not terminated) and self._steps >= self._max_steps
        self._done = terminated or truncated
        info = self._info(rec, terminated)
        if self.render_mode == "human" and (self._steps % self._render_every == 0 or self._done):
            self.render()
        return obs, float(self._reward[0]), terminated, truncated, info

    def _info(self, rec: np.ndarray, contact: bool) -> dict[str, Any]:
        r = rec.copy()
        t = self._terms[0]
        return {
            "position_m": float(r[M_X]),
            "time_s": float(r[M_T]),
            "gap_excursion_m": r[M_GAP : M_GAP + 4],
            "lateral_offset_m": r[M_LAT : M_LAT + 4],
            "current_A": r[M_I : M_I + 4],
            "acceleration_m_s2": r[M_ACC_HEAVE : M_ACC_LAT + 1],
            "contact": contact,
            "reward_terms": {
                "gap": float(t[0]),
                "current": float(t[1]),
                "comfort": float(t[2]),
                "survival": float(t[3]),
                "contact": float(t[4]),
            },
            "speed_kmh": self._speed_kmh,
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
            self._renderer = Renderer(self.render_mode, self.metadata["render_fps"])
        return self._renderer.draw(self.sim.meas, self.sim.P, self.sim.params)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_renderer"] = None
        return state
