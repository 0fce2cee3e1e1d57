"""One frozen, validated configuration of the environment.

:class:`EnvConfig` holds everything that defines an environment: the scenario and its
physical overrides, the actuator set, the disturbances, the action scale, the sensor
model and the reward weights. Both the single and the native vector environment take it,
and ``gymnasium.make(ENV_ID, **kwargs)`` builds it from flat keyword arguments::

    cfg = EnvConfig(scenario="paper-2000-curved", sensors=SensorConfig(noise_std=0.01))
    env = gym.make("HyperloopSuspension-v0", config=cfg)
    env = gym.make("HyperloopSuspension-v0", scenario="paper-2000-curved", sensor_noise_std=0.01)

:meth:`EnvConfig.resolve` turns it into a :class:`ResolvedConfig`: the base
:class:`~hyperloop_env.physics.params.ModelParams`, what the scenario randomises per
episode, the observation layout and the number of control steps of an episode. Evaluation,
rollouts and training read these instead of re-deriving them.

Flat keyword names (``gym.make`` and the constructors) and where they go:

=====================  =====================================================================
keyword                field
=====================  =====================================================================
scenario               ``scenario``
speed_kmh …            physical overrides (``None`` keeps the scenario's value):
                       ``speed_kmh, curve_radius_m, cant_deg, track_length_m, irregularity,
                       control_dt_s, clearance_m, magnet, coil_time_constant_s``
actuators              ``actuators`` (``"levitation"``)
disturbances           ``disturbances`` (mapping name → severity, or Disturbance instances)
action_scale           ``action_scale``
sensor_noise_std       ``sensors.noise_std``
sensor_delay           ``sensors.delay_steps``
gap_weight …           ``reward.gap, reward.guidance, reward.current, reward.comfort,
                       reward.survival, reward.contact`` (from ``gap_weight,
                       guidance_weight, current_weight, comfort_weight, survival_bonus,
                       contact_penalty``)
=====================  =====================================================================

An unknown keyword raises ``TypeError`` (Python's convention) listing the valid names; an
invalid value raises ``ValueError`` naming the argument.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from functools import cached_property
from typing import Any

import numpy as np

from hyperloop_env.disturbances import (
    Disturbance,
    Roughness,
    configure_all,
    make_disturbance,
    merge,
    parse_disturbances,
)
from hyperloop_env.disturbances.roughness import REFERENCE_SPECTRUM
from hyperloop_env.observation import ObservationSpec, observation_spec
from hyperloop_env.physics.actuators import ActuatorSet
from hyperloop_env.physics.irregularity import N_ROWS as PROFILE_ROWS
from hyperloop_env.physics.model import (
    episode_steps,
    pack,
    profile_grid,
    track_length_needed_m,
)
from hyperloop_env.physics.params import (
    GuidewayParams,
    MagnetParams,
    ModelParams,
    OperatingCondition,
    SimulationParams,
    VehicleParams,
    is_real,
)
from hyperloop_env.scenarios import (
    DEFAULT_COIL_TIME_CONSTANT_S,
    DEFAULT_SCENARIO,
    Scenario,
    get_scenario,
)

MAX_SENSOR_NOISE_STD = 10.0
"""Largest accepted ``sensor_noise_std`` (noise on observation entries scaled to O(1))."""

MIN_SPEED_KMH = 1.0
"""Smallest accepted ``speed_kmh`` [km/h]. The model is a high-speed maglev (the paper's
conditions are 1000 and 2000 km/h); below walking pace an episode is only a count of
control steps that grows without bound (a subnormal speed would divide by zero)."""

MIN_CURVE_RADIUS_M = 1_000.0
"""Smallest accepted ``curve_radius_m`` [m]: 1 km.

Why: the model is a high-speed line, and its curve enters the observation as the curvature
κ scaled by 1e5 m (:data:`hyperloop_env.observation.CURVATURE_SCALE_M`: O(1) at the
paper's 200 km radius). At 1 km the curvature entries reach 100, and v²/R is already
77 m/s² (7.9 g) at 1000 km/h and 309 m/s² at 2000 km/h — beyond the most the guidance
magnets can push (about 120 m/s² on the 37 t vehicle: 40 A into the 2 mm gap left at
contact), so contact in the curve's transition is certain well above this radius. A
smaller radius describes no operating condition of the model (``curve_radius_m=1`` gave
observations of 1e5); 1 km is where :func:`agents.evaluation.reproduce_paper.critical_radius`
starts its search, and the randomised scenarios draw 20 km or more."""

MIN_CONTROL_DT_S = 1e-6
"""Smallest accepted ``control_dt_s`` [s]: 1000x finer than the default 1 ms (a subnormal
interval would make the number of control steps of an episode overflow)."""

MAX_PROFILE_BYTES = 256 * 2**20
"""Memory budget of one environment's guideway profile [bytes]: 256 MiB.

The simulator keeps the irregularity of the whole track section as 3 rows (left vertical,
right vertical, lateral) of float64 on a power-of-two grid of 0.1 m steps
(:func:`hyperloop_env.physics.model.profile_grid`), and generating it (FFT) briefly needs
about 2.3x that again. 256 MiB allows a grid of 2**23 points, i.e. a ``track_length_m`` of
up to ~838 km (peak ~450 MB per environment while the profile is drawn; a vector env holds
one profile per environment) — 80x the longest evaluation run of the project (10 km).
Longer sections are refused with a ``ValueError`` instead of running for minutes into a
``MemoryError`` (1e7 m would need 3 GiB of profile and ~9 GB at peak)."""


def _real(
    name: str, value: Any, lo: float | None = None, hi: float | None = None, lo_open: bool = False
) -> float:
    if not is_real(value) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    v = float(value)
    if lo is not None and (v <= lo if lo_open else v < lo):
        raise ValueError(f"{name} must be {'>' if lo_open else '>='} {lo}, got {value!r}")
    if hi is not None and v > hi:
        raise ValueError(f"{name} must be <= {hi}, got {value!r}")
    return v


@dataclass(frozen=True)
class SensorConfig:
    """Sensor model of the observation (:mod:`hyperloop_env.sensors`).

    ``noise_std``: Gaussian noise of that standard deviation on the *scaled* measured
    entries of the observation (so it is relative to each entry's scale: 0.01 is 80 µm on
    a gap), in [0, 10]. ``delay_steps``: 0, or 1 to return the previous control step's
    observation."""

    noise_std: float = 0.0
    delay_steps: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "noise_std", _real("sensor_noise_std", self.noise_std, 0.0, MAX_SENSOR_NOISE_STD)
        )
        d = self.delay_steps
        if isinstance(d, bool) or not isinstance(d, int | np.integer) or int(d) not in (0, 1):
            raise ValueError(f"sensor_delay must be 0 or 1 (control steps), got {d!r}")
        object.__setattr__(self, "delay_steps", int(d))


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the reward terms (:mod:`hyperloop_env.reward`), all >= 0.

    Keyword names: ``gap_weight``, ``guidance_weight``, ``current_weight``,
    ``comfort_weight``, ``survival_bonus``, ``contact_penalty``."""

    gap: float = 1.0
    guidance: float = 1.0
    current: float = 0.05
    comfort: float = 1.0
    survival: float = 1.0
    contact: float = 100.0

    def __post_init__(self) -> None:
        for f in fields(self):
            kw = REWARD_KEYWORDS[f.name]
            object.__setattr__(self, f.name, _real(kw, getattr(self, f.name), 0.0))

    def as_tuple(self) -> tuple[float, ...]:
        """Weights in the order of :data:`hyperloop_env.reward.REWARD_TERMS`."""
        return tuple(getattr(self, f.name) for f in fields(self))


REWARD_KEYWORDS: dict[str, str] = {
    "gap": "gap_weight",
    "guidance": "guidance_weight",
    "current": "current_weight",
    "comfort": "comfort_weight",
    "survival": "survival_bonus",
    "contact": "contact_penalty",
}

PHYSICAL_OVERRIDES: tuple[str, ...] = (
    "speed_kmh",
    "curve_radius_m",
    "cant_deg",
    "track_length_m",
    "irregularity",
    "control_dt_s",
    "clearance_m",
    "magnet",
    "coil_time_constant_s",
)
"""Keyword overrides of the physical model (``None`` keeps the scenario's value)."""

MAGNETS: tuple[str, ...] = ("repelling", "attracting")

_NUMERIC_OVERRIDES: tuple[str, ...] = (
    "speed_kmh",
    "curve_radius_m",
    "cant_deg",
    "track_length_m",
    "control_dt_s",
    "clearance_m",
    "coil_time_constant_s",
)


@dataclass(frozen=True)
class EnvConfig:
    """The environment's configuration (see the module docstring). Frozen and validated
    on construction: the physical model it describes is built once (``resolve()``)."""

    scenario: str = DEFAULT_SCENARIO
    speed_kmh: float | None = None
    curve_radius_m: float | None = None
    cant_deg: float | None = None
    track_length_m: float | None = None
    irregularity: str | None = None
    control_dt_s: float | None = None
    clearance_m: float | None = None
    magnet: str | None = None
    coil_time_constant_s: float | None = None
    actuators: str | ActuatorSet = "levitation"
    disturbances: Any = ()
    action_scale: float = 1.0
    sensors: SensorConfig = field(default_factory=SensorConfig)
    reward: RewardWeights = field(default_factory=RewardWeights)

    def __post_init__(self) -> None:
        get_scenario(self.scenario)
        self._check_numeric_overrides()
        try:
            acts = ActuatorSet.parse(self.actuators)
        except (TypeError, ValueError) as exc:
            raise ValueError(str(exc)) from None
        object.__setattr__(self, "actuators", acts)
        object.__setattr__(self, "disturbances", parse_disturbances(self.disturbances))
        a = self.action_scale
        if not is_real(a) or not (0 < a <= 10):
            raise ValueError(f"action_scale must be a number in (0, 10], got {a!r}")
        object.__setattr__(self, "action_scale", float(a))
        if not isinstance(self.sensors, SensorConfig):
            raise ValueError(f"sensors must be a SensorConfig, got {self.sensors!r}")
        if not isinstance(self.reward, RewardWeights):
            raise ValueError(f"reward must be a RewardWeights, got {self.reward!r}")
        if self.magnet is not None and self.magnet not in MAGNETS:
            raise ValueError(
                f"magnet must be 'repelling' or 'attracting' (MagnetParams.orientation), "
                f"got {self.magnet!r}"
            )
        self.resolved  # noqa: B018 - validate the physical model now

    def _check_numeric_overrides(self) -> None:
        """Numbers of the physical overrides: real (NumPy scalars are stored as Python
        floats), finite (a curve radius may be ``math.inf``: straight) and, for speed,
        control interval and track length, inside the bounds the model can run."""
        for name in _NUMERIC_OVERRIDES:
            v = getattr(self, name)
            if v is None:
                continue
            if not is_real(v) or math.isnan(v):
                raise ValueError(f"{name} must be a number, got {v!r}")
            if math.isinf(v) and name == "curve_radius_m" and v < 0:
                raise ValueError(f"{name} must be > 0 (math.inf for straight), got {v!r}")
            if math.isinf(v) and name != "curve_radius_m":
                raise ValueError(f"{name} must be finite, got {v!r}")
            object.__setattr__(self, name, float(v))
        if self.curve_radius_m is not None and self.curve_radius_m < MIN_CURVE_RADIUS_M:
            raise ValueError(
                f"curve_radius_m must be >= {MIN_CURVE_RADIUS_M:g} m (MIN_CURVE_RADIUS_M: "
                "below it the curve's lateral acceleration is far beyond what the guidance "
                "magnets hold and the curvature observation leaves O(1); math.inf for "
                f"straight), got {self.curve_radius_m!r}"
            )
        if self.speed_kmh is not None and self.speed_kmh < MIN_SPEED_KMH:
            raise ValueError(
                f"speed_kmh must be >= {MIN_SPEED_KMH} km/h (MIN_SPEED_KMH), got {self.speed_kmh!r}"
            )
        if self.control_dt_s is not None and self.control_dt_s < MIN_CONTROL_DT_S:
            raise ValueError(
                f"control_dt_s must be >= {MIN_CONTROL_DT_S} s (MIN_CONTROL_DT_S), "
                f"got {self.control_dt_s!r}"
            )
        if self.track_length_m is not None and self.track_length_m <= 0:
            raise ValueError(f"track_length_m must be > 0, got {self.track_length_m!r}")

    # ---- keyword interface ------------------------------------------------------------------
    @classmethod
    def keyword_names(cls) -> tuple[str, ...]:
        """Every flat keyword accepted by :meth:`from_kwargs` (and the environments)."""
        return (
            "scenario",
            *PHYSICAL_OVERRIDES,
            "actuators",
            "disturbances",
            "action_scale",
            "sensor_noise_std",
            "sensor_delay",
            *REWARD_KEYWORDS.values(),
        )

    @classmethod
    def from_kwargs(cls, config: EnvConfig | None = None, **kwargs: Any) -> EnvConfig:
        """``config`` (or the defaults) with the flat keyword arguments applied.

        Unknown keywords raise ``TypeError`` listing the valid ones."""
        valid = cls.keyword_names()
        unknown = sorted(set(kwargs) - set(valid))
        if unknown:
            more = f" (and {', '.join(repr(u) for u in unknown[1:])})" if unknown[1:] else ""
            raise TypeError(
                f"HyperloopSuspension-v0 got an unexpected keyword argument {unknown[0]!r}{more}; "
                f"valid arguments: {list(valid)} (and config=EnvConfig(...), render_mode)"
            )
        if config is not None and not isinstance(config, EnvConfig):
            raise TypeError(f"config must be an EnvConfig, got {type(config).__name__}")
        base = config if config is not None else cls()
        sensors = base.sensors
        if "sensor_noise_std" in kwargs or "sensor_delay" in kwargs:
            sensors = SensorConfig(
                noise_std=kwargs.pop("sensor_noise_std", sensors.noise_std),
                delay_steps=kwargs.pop("sensor_delay", sensors.delay_steps),
            )
        rw = {f: kwargs.pop(kw) for f, kw in REWARD_KEYWORDS.items() if kw in kwargs}
        reward = replace(base.reward, **rw) if rw else base.reward
        return replace(base, sensors=sensors, reward=reward, **kwargs)

    def to_kwargs(self) -> dict[str, Any]:
        """Flat keyword arguments that rebuild this config (JSON-friendly except for
        non-default disturbances, given as ``{name: {field: value}}``)."""
        out: dict[str, Any] = {"scenario": self.scenario}
        for k in PHYSICAL_OVERRIDES:
            v = getattr(self, k)
            if v is not None:
                out[k] = v
        out["actuators"] = self.actuators.name
        if self.disturbances:
            out["disturbances"] = {
                d.name: {k: v for k, v in d.to_dict().items() if k != "name"}
                for d in self.disturbances
            }
        out["action_scale"] = self.action_scale
        out["sensor_noise_std"] = self.sensors.noise_std
        out["sensor_delay"] = self.sensors.delay_steps
        for f, kw in REWARD_KEYWORDS.items():
            out[kw] = getattr(self.reward, f)
        return out

    def replace(self, **kwargs: Any) -> EnvConfig:
        """Copy with flat keyword arguments applied (as :meth:`from_kwargs`)."""
        return EnvConfig.from_kwargs(self, **kwargs)

    # ---- resolution --------------------------------------------------------------------------
    @cached_property
    def resolved(self) -> ResolvedConfig:
        return _resolve(self)

    def resolve(self) -> ResolvedConfig:
        """The physical model and the episode logic this configuration describes."""
        return self.resolved

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state.pop("resolved", None)
        return state


@dataclass(frozen=True, eq=False)
class ResolvedConfig:
    """A scenario with its overrides applied: the base parameters, the disturbances, what
    to randomise per episode, and the stages' settings."""

    config: EnvConfig
    scenario: Scenario
    base: ModelParams
    disturbances: tuple[Disturbance, ...]
    draw_speed: bool
    draw_curve: bool
    draw_irregularity: bool
    draw_mass: bool

    @property
    def randomized(self) -> bool:
        return self.draw_speed or self.draw_curve or self.draw_irregularity or self.draw_mass

    def episode_disturbances(self, rng: np.random.Generator) -> tuple[Disturbance, ...]:
        """The disturbances of one episode: the configured ones, plus (``random``
        scenario) the families of ``RANDOM_DISTURBANCES`` drawn from ``rng`` that the
        configuration does not fix."""
        spec = self.scenario.random
        if spec is None:
            return self.disturbances
        fixed = {d.name for d in self.config.disturbances}
        drawn = []
        for name, (prob, (lo, hi), fields_) in spec.disturbances.items():
            active = rng.random() < prob
            sev = float(rng.uniform(lo, hi))
            if active and name not in fixed and sev > 0.0:
                drawn.append(make_disturbance(name, sev, **fields_))
        return merge(self.disturbances, tuple(drawn))

    @property
    def actuators(self) -> ActuatorSet:
        return self.base.actuators

    @property
    def action_scale(self) -> float:
        return self.config.action_scale

    @property
    def sensors(self) -> SensorConfig:
        return self.config.sensors

    @property
    def reward(self) -> RewardWeights:
        return self.config.reward

    @cached_property
    def observation(self) -> ObservationSpec:
        return observation_spec(self.base.actuators)

    @property
    def control_dt_s(self) -> float:
        return self.base.simulation.control_dt_s

    @property
    def episode_steps(self) -> int:
        """Control steps of an episode at the base parameters (the speed may be drawn)."""
        return episode_steps(self.base)

    def expected_steps(self, distance_km: float | None = None) -> int:
        """Control steps to cover ``distance_km`` (default: the track section) at the base
        speed and control interval."""
        if distance_km is None:
            return self.episode_steps
        p = self.base
        sim = replace(p.simulation, track_length_m=float(distance_km) * 1000.0)
        return episode_steps(p.with_(simulation=sim))

    def sample(self, rng: np.random.Generator) -> ModelParams:
        """Parameters of one episode (``base`` unless the scenario randomises; the draws
        come from ``rng`` in a fixed order: speed, straight/curve, radius, class, mass)."""
        if not self.randomized:
            return self.base
        spec = self.scenario.random
        assert spec is not None
        p = self.base
        cond = p.condition
        if self.draw_speed:
            lo, hi = spec.speed_range_kmh
            cond = replace(cond, speed_kmh=float(rng.uniform(lo, hi)))
        if self.draw_curve:
            straight = rng.random() < spec.straight_probability
            lo, hi = spec.radius_range_m
            radius = float(np.exp(rng.uniform(math.log(lo), math.log(hi))))
            cond = replace(cond, curve_radius_m=math.inf if straight else radius)
        irr = p.irregularity
        if self.draw_irregularity:
            if spec.roughness_range is None:
                k = int(rng.integers(len(spec.irregularity_classes)))
                irr = replace(irr, spectrum=spec.irregularity_classes[k])
            else:
                lo, hi = spec.roughness_range
                irr = replace(
                    irr, spectrum=REFERENCE_SPECTRUM, amplitude=float(rng.uniform(lo, hi))
                )
        veh = p.vehicle
        if self.draw_mass:
            lo, hi = spec.mass_factor_range
            veh = replace(veh, capsule_mass_kg=veh.capsule_mass_kg * float(rng.uniform(lo, hi)))
        return p.with_(condition=cond, irregularity=irr, vehicle=veh)


def _resolve(cfg: EnvConfig) -> ResolvedConfig:
    sc = get_scenario(cfg.scenario)
    extra = cfg.disturbances
    if cfg.irregularity is not None:
        if any(d.name == Roughness.name for d in extra):
            raise ValueError("give either irregularity= or a 'roughness' disturbance, not both")
        extra = merge(extra, (Roughness.from_class(cfg.irregularity),))
    disturbances = merge(sc.disturbances, extra)
    try:
        base, cond = _base_params(cfg, sc, disturbances)
    except ValueError as exc:  # name the argument the user gave, not the physics field
        msg = _explain_timestep(cfg, sc)
        if msg is None:
            raise
        raise ValueError(msg) from exc
    _check_profile_memory(cfg, base)
    r = sc.randomize
    fixed_rough = cfg.irregularity is not None or any(
        d.name == Roughness.name for d in cfg.disturbances
    )
    res = ResolvedConfig(
        config=cfg,
        scenario=sc,
        base=base,
        disturbances=disturbances,
        draw_speed=r and cfg.speed_kmh is None,
        draw_curve=r and cfg.curve_radius_m is None,
        draw_irregularity=r and not fixed_rough,
        draw_mass=r,
    )
    if res.draw_speed:  # validate the extreme of the range (ModelParams checks the travel)
        try:
            base.with_(condition=replace(cond, speed_kmh=sc.random.speed_range_kmh[1]))
        except ValueError as exc:
            msg = _explain_timestep(cfg, sc)
            if msg is None:
                raise
            raise ValueError(msg) from exc
    # configured disturbances must fit every episode: check them at the slowest entry
    # speed an episode can have (a drawn speed from the range's low end)
    slowest = base
    if res.draw_speed and sc.random.speed_range_kmh[0] < cond.speed_kmh:
        slowest = base.with_(
            condition=replace(
                base.condition, speed_kmh=sc.random.speed_range_kmh[0], acceleration_m_s2=0.0
            )
        )
    for d in disturbances:
        d.validate(slowest)
    pack(base)  # raises if the magnet cannot carry the vehicle with these parameters
    return res


def _base_params(
    cfg: EnvConfig, sc: Scenario, disturbances: tuple[Disturbance, ...]
) -> tuple[ModelParams, OperatingCondition]:
    cond = OperatingCondition(
        speed_kmh=cfg.speed_kmh if cfg.speed_kmh is not None else sc.speed_kmh,
        curve_radius_m=cfg.curve_radius_m if cfg.curve_radius_m is not None else sc.curve_radius_m,
        cant_deg=cfg.cant_deg if cfg.cant_deg is not None else sc.cant_deg,
    )
    magnet = MagnetParams(
        orientation=cfg.magnet if cfg.magnet is not None else "repelling",
        clearance_m=cfg.clearance_m if cfg.clearance_m is not None else MagnetParams.clearance_m,
        coil_time_constant_s=cfg.coil_time_constant_s
        if cfg.coil_time_constant_s is not None
        else DEFAULT_COIL_TIME_CONSTANT_S,
    )
    sim = SimulationParams(
        control_dt_s=cfg.control_dt_s
        if cfg.control_dt_s is not None
        else SimulationParams.control_dt_s,
        track_length_m=cfg.track_length_m
        if cfg.track_length_m is not None
        else SimulationParams.track_length_m,
    )
    base = ModelParams(
        vehicle=VehicleParams(),
        magnet=magnet,
        condition=cond,
        simulation=sim,
        actuators=cfg.actuators,
    )
    return configure_all(disturbances, base), cond


def _explain_timestep(cfg: EnvConfig, sc: Scenario) -> str | None:
    """The user-facing reason a speed / control interval was refused by the physics
    (:class:`~hyperloop_env.physics.params.ModelParams` checks one RK4 substep against the
    guideway's highest mode and its span), naming ``speed_kmh`` / ``control_dt_s``; None
    if neither limit is the cause."""
    dt = cfg.control_dt_s if cfg.control_dt_s is not None else SimulationParams.control_dt_s
    substeps = SimulationParams.substeps
    g = GuidewayParams()
    dt_arg = ("" if cfg.control_dt_s is not None else "the default ") + f"control_dt_s={dt!r}"
    if not g.rigid:
        f_max = max(g.natural_frequency_hz(g.n_modes), g.natural_frequency_hz(g.n_modes, True))
        dt_max = 2.0 * substeps / (2.0 * math.pi * f_max)
        if dt > dt_max:
            return (
                f"control_dt_s={dt!r} is too long for the guideway's highest mode "
                f"({f_max:.0f} Hz, mode {g.n_modes} of a {g.span_m:g} m span) with "
                f"{substeps} RK4 substeps per control interval: RK4 would be unstable; "
                f"at most {dt_max:.4g} s"
            )
    if cfg.speed_kmh is not None:
        speed, speed_arg = cfg.speed_kmh, f"speed_kmh={cfg.speed_kmh!r}"
    elif sc.random is not None:
        speed = sc.random.speed_range_kmh[1]
        speed_arg = f"the scenario {sc.name!r} (speeds up to {speed:g} km/h)"
    else:
        speed, speed_arg = sc.speed_kmh, f"the scenario {sc.name!r} ({sc.speed_kmh:g} km/h)"
    footprint = VehicleParams.set_spacing_m + MagnetParams.pole_length_m
    step = speed / 3.6 * dt / substeps
    if footprint + step >= g.span_m:
        v_max = (g.span_m - footprint) * substeps / dt * 3.6
        return (
            f"{speed_arg} is too fast for {dt_arg}: one RK4 substep travels {step:.4g} m "
            f"and the magnet footprint ({footprint:g} m) plus one substep must stay within "
            f"a guideway span ({g.span_m:g} m); at most {v_max:.4g} km/h at this "
            f"control interval; lower speed_kmh or control_dt_s"
        )
    return None


def _check_profile_memory(cfg: EnvConfig, base: ModelParams) -> None:
    """Refuse a track section whose guideway profile exceeds :data:`MAX_PROFILE_BYTES`."""
    n, step = profile_grid(base)
    row_bytes = PROFILE_ROWS * np.dtype(np.float64).itemsize
    nbytes = row_bytes * n
    if nbytes <= MAX_PROFILE_BYTES:
        return
    n_max = 2 ** int(math.floor(math.log2(MAX_PROFILE_BYTES / row_bytes)))
    margin = track_length_needed_m(base) - base.simulation.track_length_m
    longest = n_max * step - margin
    length = base.simulation.track_length_m
    arg = (
        f"track_length_m={length!r}"
        if cfg.track_length_m is not None
        else (f"the scenario's track section ({length:g} m)")
    )
    raise ValueError(
        f"{arg} is too long: its guideway profile ({PROFILE_ROWS} rows x {n} points at "
        f"{step:g} m, float64) would need {nbytes / 2**20:.0f} MiB, over the "
        f"{MAX_PROFILE_BYTES / 2**20:.0f} MiB budget per environment (MAX_PROFILE_BYTES); "
        f"track_length_m must be at most {math.floor(longest):.0f} m"
    )


def build_config(scenario: str = DEFAULT_SCENARIO, **kwargs: Any) -> ResolvedConfig:
    """``EnvConfig.from_kwargs(scenario=scenario, **kwargs).resolve()`` (a shortcut)."""
    return EnvConfig.from_kwargs(scenario=scenario, **kwargs).resolve()


__all__ = [
    "MAX_PROFILE_BYTES",
    "MIN_CONTROL_DT_S",
    "MIN_CURVE_RADIUS_M",
    "MIN_SPEED_KMH",
    "PHYSICAL_OVERRIDES",
    "EnvConfig",
    "ResolvedConfig",
    "RewardWeights",
    "SensorConfig",
    "build_config",
]
