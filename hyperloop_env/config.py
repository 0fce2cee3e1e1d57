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
    merge,
    parse_disturbances,
)
from hyperloop_env.observation import ObservationSpec, observation_spec
from hyperloop_env.physics.actuators import ActuatorSet
from hyperloop_env.physics.model import episode_steps, pack
from hyperloop_env.physics.params import (
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
    RANDOM_IRREGULARITY_CLASSES,
    RANDOM_MASS_FACTOR_RANGE,
    RANDOM_RADIUS_RANGE_M,
    RANDOM_SPEED_RANGE_KMH,
    RANDOM_STRAIGHT_PROBABILITY,
    Scenario,
    get_scenario,
)

MAX_SENSOR_NOISE_STD = 10.0
"""Largest accepted ``sensor_noise_std`` (noise on observation entries scaled to O(1))."""


def _real(name: str, value: Any, lo: float | None = None, hi: float | None = None,
          lo_open: bool = False) -> float:  # fmt: skip
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
        p = self.base
        cond = p.condition
        if self.draw_speed:
            lo, hi = RANDOM_SPEED_RANGE_KMH
            cond = replace(cond, speed_kmh=float(rng.uniform(lo, hi)))
        if self.draw_curve:
            straight = rng.random() < RANDOM_STRAIGHT_PROBABILITY
            lo, hi = RANDOM_RADIUS_RANGE_M
            radius = float(np.exp(rng.uniform(math.log(lo), math.log(hi))))
            cond = replace(cond, curve_radius_m=math.inf if straight else radius)
        irr = p.irregularity
        if self.draw_irregularity:
            k = int(rng.integers(len(RANDOM_IRREGULARITY_CLASSES)))
            irr = replace(irr, spectrum=RANDOM_IRREGULARITY_CLASSES[k])
        veh = p.vehicle
        if self.draw_mass:
            lo, hi = RANDOM_MASS_FACTOR_RANGE
            veh = replace(veh, capsule_mass_kg=veh.capsule_mass_kg * float(rng.uniform(lo, hi)))
        return p.with_(condition=cond, irregularity=irr, vehicle=veh)


def _resolve(cfg: EnvConfig) -> ResolvedConfig:
    sc = get_scenario(cfg.scenario)
    extra = cfg.disturbances
    if cfg.irregularity is not None:
        if any(d.name == Roughness.name for d in extra):
            raise ValueError(
                "give either irregularity= or a 'roughness' disturbance, not both"
            )
        extra = merge(extra, (Roughness.from_class(cfg.irregularity),))
    disturbances = merge(sc.disturbances, extra)
    cond = OperatingCondition(
        speed_kmh=cfg.speed_kmh if cfg.speed_kmh is not None else sc.speed_kmh,
        curve_radius_m=cfg.curve_radius_m if cfg.curve_radius_m is not None
        else sc.curve_radius_m,
        cant_deg=cfg.cant_deg if cfg.cant_deg is not None else sc.cant_deg,
    )  # fmt: skip
    magnet = MagnetParams(
        orientation=cfg.magnet if cfg.magnet is not None else "repelling",
        clearance_m=cfg.clearance_m if cfg.clearance_m is not None else MagnetParams.clearance_m,
        coil_time_constant_s=cfg.coil_time_constant_s
        if cfg.coil_time_constant_s is not None
        else DEFAULT_COIL_TIME_CONSTANT_S,
    )
    sim = SimulationParams(
        control_dt_s=cfg.control_dt_s if cfg.control_dt_s is not None
        else SimulationParams.control_dt_s,
        track_length_m=cfg.track_length_m if cfg.track_length_m is not None
        else SimulationParams.track_length_m,
    )  # fmt: skip
    base = ModelParams(
        vehicle=VehicleParams(), magnet=magnet, condition=cond, simulation=sim,
        actuators=cfg.actuators,
    )  # fmt: skip
    base = configure_all(disturbances, base)
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
        base.with_(condition=replace(cond, speed_kmh=RANDOM_SPEED_RANGE_KMH[1]))
    pack(base)  # raises if the magnet cannot carry the vehicle with these parameters
    return res


def build_config(scenario: str = DEFAULT_SCENARIO, **kwargs: Any) -> ResolvedConfig:
    """``EnvConfig.from_kwargs(scenario=scenario, **kwargs).resolve()`` (a shortcut)."""
    return EnvConfig.from_kwargs(scenario=scenario, **kwargs).resolve()


__all__ = [
    "PHYSICAL_OVERRIDES",
    "EnvConfig",
    "ResolvedConfig",
    "RewardWeights",
    "SensorConfig",
    "build_config",
]
