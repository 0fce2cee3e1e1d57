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

Flat keyword names (``gym.make`` and the constructors) and the field each one sets: every
keyword is declared once, as metadata of its field (:func:`hyperloop_env.keywords.kw`:
doc, unit, accepted values), and this table, the environments' argument tables, the
validation, :meth:`EnvConfig.keyword_names` and :meth:`EnvConfig.to_kwargs` are derived
from the declarations. Physical overrides left at ``None`` keep the scenario's value. A
reward weight's keyword is ``<term>_weight``, the term's name (:data:`REWARD_TERMS
<hyperloop_env.reward.REWARD_TERMS>`) being the field's; the former names
``survival_bonus`` and ``contact_penalty`` are deprecated aliases of ``survival_weight`` and
``contact_weight``.

[keyword table]

An unknown keyword raises ``TypeError`` (Python's convention) listing the valid names; an
invalid value raises ``ValueError`` naming the argument.
"""

from __future__ import annotations

import math
import sys
import warnings
from dataclasses import dataclass, field, fields, replace
from functools import cached_property
from math import inf
from pathlib import Path
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
from hyperloop_env.keywords import (
    PHYSICAL,
    REWARD,
    Declared,
    declared,
    field_table,
    kw,
    kw_group,
    validate_fields,
    with_table,
)
from hyperloop_env.observation import MemorySpec, ObservationSpec, observation_spec
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
)
from hyperloop_env.safety import COST_KINDS, DEFAULT_SAFETY_MARGIN_MM, CostLimits, check_margin
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


@dataclass(frozen=True)
class SensorConfig:
    """Sensor model of the observation (:mod:`hyperloop_env.sensors`).

    ``noise_std``: Gaussian noise of that standard deviation on the *scaled* measured
    entries of the observation (so it is relative to each entry's scale: 0.01 is 80 µm on
    a gap), in [0, 10]. ``delay_steps``: 0, or 1 to return the previous control step's
    observation."""

    noise_std: float = field(
        default=0.0,
        metadata=kw(
            "noise std on the scaled measured observation entries",
            bounds=(0.0, MAX_SENSOR_NOISE_STD),
            name="sensor_noise_std",
        ),
    )
    delay_steps: int = field(
        default=0,
        metadata=kw(
            "observation delay (1: the previous step's)",
            unit="control steps",
            choices=(0, 1),
            name="sensor_delay",
        ),
    )

    def __post_init__(self) -> None:
        validate_fields(self)


MAX_REWARD_WEIGHT = 1e12
"""Largest accepted reward weight (every ``<term>_weight``).

Why: each reward term is its weight times a capped quantity (:mod:`hyperloop_env.reward`:
at most 4 for the gap terms, 100 for comfort, 2.5e11 for the current term, 1 for survival
and contact), so with every weight at 1e12 the reward of any step, a diverged one
included, stays within about ±2.5e23: finite in float64 and in float32 (±3.4e38, the
dtype in which many RL libraries store rewards). Larger weights could sum to ±inf (a
weight of 1e308 did); the defaults are 0.05–100, so the bound costs no useful setting."""

_WEIGHT: dict[str, Any] = {
    "bounds": (0.0, MAX_REWARD_WEIGHT),
    "why": "MAX_REWARD_WEIGHT: the reward stays finite",
    "group": REWARD,
}


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the reward terms (:mod:`hyperloop_env.reward`), all >= 0.

    The fields are the terms' names (:data:`hyperloop_env.reward.REWARD_TERMS`, same
    order); the keyword of a weight is ``<term>_weight``."""

    gap: float = field(default=1.0, metadata=kw("weight of the gap term", **_WEIGHT))
    guidance: float = field(default=1.0, metadata=kw("weight of the guidance-gap term", **_WEIGHT))
    current: float = field(
        default=0.05, metadata=kw("weight of the current-effort term", **_WEIGHT)
    )
    comfort: float = field(default=1.0, metadata=kw("weight of the comfort term", **_WEIGHT))
    survival: float = field(
        default=1.0,
        metadata=kw("reward per step without contact", aliases=("survival_bonus",), **_WEIGHT),
    )
    contact: float = field(
        default=100.0,
        metadata=kw("penalty paid once, at contact", aliases=("contact_penalty",), **_WEIGHT),
    )

    def __post_init__(self) -> None:
        validate_fields(self)

    def as_tuple(self) -> tuple[float, ...]:
        """Weights in the order of :data:`hyperloop_env.reward.REWARD_TERMS`."""
        return tuple(getattr(self, f.name) for f in fields(self))


MAGNETS: tuple[str, ...] = ("repelling", "attracting")


def _scenario_name(name: Any) -> str:
    get_scenario(name)  # ValueError listing the scenarios
    return name


def _actuator_set(value: Any) -> ActuatorSet:
    try:
        return ActuatorSet.parse(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(str(exc)) from None


def _disturbance_kwargs(ds: tuple[Disturbance, ...]) -> dict[str, dict[str, Any]]:
    return {d.name: {k: v for k, v in d.to_dict().items() if k != "name"} for d in ds}


_PHYSICAL: dict[str, Any] = {"optional": True, "group": PHYSICAL}
_ANY_NUMBER = (-inf, inf)  # the physics (ModelParams) checks the range


@dataclass(frozen=True)
class EnvConfig:
    """The environment's configuration (see the module docstring). Frozen and validated
    on construction: the physical model it describes is built once (``resolve()``)."""

    scenario: str = field(
        default=DEFAULT_SCENARIO,
        metadata=kw("named scenario (`hyperloop_env.scenarios`)", parse=_scenario_name),
    )
    speed_kmh: float | None = field(
        default=None,
        metadata=kw(
            "speed",
            unit="km/h",
            bounds=(MIN_SPEED_KMH, inf),
            why="MIN_SPEED_KMH",
            shown_default="scenario",
            **_PHYSICAL,
        ),
    )
    curve_radius_m: float | None = field(
        default=None,
        metadata=kw(
            "radius of the horizontal curve, `math.inf` straight",
            unit="m",
            bounds=(MIN_CURVE_RADIUS_M, inf),
            infinite="math.inf for straight",
            why="MIN_CURVE_RADIUS_M: below it the curve's lateral acceleration is far beyond "
            "what the guidance magnets hold and the curvature observation leaves O(1); "
            "math.inf for straight",
            shown_default="scenario",
            **_PHYSICAL,
        ),
    )
    cant_deg: float | None = field(
        default=None,
        metadata=kw(
            "cant of the curve (range: `OperatingCondition`)",
            unit="deg",
            bounds=_ANY_NUMBER,
            shown_default="scenario",
            **_PHYSICAL,
        ),
    )
    track_length_m: float | None = field(
        default=None,
        metadata=kw(
            "length of the track section (longest: `MAX_PROFILE_BYTES`)",
            unit="m",
            bounds=(0.0, inf),
            lo_open=True,
            shown_default=f"{SimulationParams.track_length_m:g}",
            **_PHYSICAL,
        ),
    )
    irregularity: str | None = field(
        default=None,
        metadata=kw(
            'guideway irregularity class (`IRREGULARITY_CLASSES`) or "none"',
            shown_default="scenario",
            **_PHYSICAL,
        ),
    )
    control_dt_s: float | None = field(
        default=None,
        metadata=kw(
            "control interval (longest: the guideway's modes, the speed)",
            unit="s",
            bounds=(MIN_CONTROL_DT_S, inf),
            why="MIN_CONTROL_DT_S",
            shown_default=f"{SimulationParams.control_dt_s:g}",
            **_PHYSICAL,
        ),
    )
    clearance_m: float | None = field(
        default=None,
        metadata=kw(
            "gap clearance Ω (range: `MagnetParams`)",
            unit="m",
            bounds=_ANY_NUMBER,
            shown_default=f"{MagnetParams.clearance_m:g}",
            **_PHYSICAL,
        ),
    )
    magnet: str | None = field(
        default=None,
        metadata=kw(
            "magnet orientation; `attracting` (EMS) is open-loop unstable",
            choices=MAGNETS,
            why="MagnetParams.orientation",
            shown_default='"repelling"',
            **_PHYSICAL,
        ),
    )
    coil_time_constant_s: float | None = field(
        default=None,
        metadata=kw(
            "coil current lag τ, 0 = ideal (range: `MagnetParams`)",
            unit="s",
            bounds=_ANY_NUMBER,
            shown_default=f"{DEFAULT_COIL_TIME_CONSTANT_S:g}",
            **_PHYSICAL,
        ),
    )
    actuators: str | ActuatorSet = field(
        default="levitation",
        metadata=kw(
            "actuator set (the action's channels)",
            parse=_actuator_set,
            dump=lambda a: a.name,
        ),
    )
    disturbances: Any = field(
        default=(),
        metadata=kw(
            "`{name: severity}` (or `Disturbance`s) on top of the scenario's",
            parse=parse_disturbances,
            dump=_disturbance_kwargs,
            omit=lambda d: not d,
        ),
    )
    action_scale: float = field(
        default=1.0,
        metadata=kw("I = I0·(1 + action_scale·a)", bounds=(0.0, 10.0), lo_open=True),
    )
    safety_margin_mm: float = field(
        default=DEFAULT_SAFETY_MARGIN_MM,
        metadata=kw(
            'safety margin m below the clearances: `info["cost"]` counts a step whose gap or '
            "guidance-gap excursion exceeds the clearance − m (`hyperloop_env.safety`; "
            "0 ≤ m < the smaller clearance)",
            unit="mm",
            bounds=(0.0, inf),
            omit=lambda v: v == DEFAULT_SAFETY_MARGIN_MM,
        ),
    )
    safety_cost: str = field(
        default="indicator",
        metadata=kw(
            '`info["cost"]` of a step: `indicator` (0 or 1) or `continuous` (the excursion '
            "beyond the margin over m; `hyperloop_env.safety`)",
            choices=COST_KINDS,
            omit=lambda v: v == "indicator",
        ),
    )
    sensors: SensorConfig = field(default_factory=SensorConfig, metadata=kw_group("sensor model"))
    memory: MemorySpec = field(
        default_factory=MemorySpec, metadata=kw_group("observation memory (off by default)")
    )
    reward: RewardWeights = field(
        default_factory=RewardWeights, metadata=kw_group("reward weights")
    )

    def __post_init__(self) -> None:
        validate_fields(self)
        self.resolved  # noqa: B018 - validate the physical model now

    # ---- keyword interface ------------------------------------------------------------------
    @classmethod
    def keyword_names(cls) -> tuple[str, ...]:
        """Every flat keyword accepted by :meth:`from_kwargs` (and the environments), in
        declaration order (deprecated aliases, also accepted, are not listed)."""
        return tuple(KEYWORDS)

    @classmethod
    def from_kwargs(cls, config: EnvConfig | None = None, **kwargs: Any) -> EnvConfig:
        """``config`` (or the defaults) with the flat keyword arguments applied.

        Unknown keywords raise ``TypeError`` listing the valid ones; a deprecated alias
        warns (``DeprecationWarning``) and sets its keyword; an invalid value raises
        ``ValueError`` naming the keyword as given."""
        valid = cls.keyword_names()
        unknown = sorted(set(kwargs) - set(valid) - set(ALIASES))
        if unknown:
            more = f" (and {', '.join(repr(u) for u in unknown[1:])})" if unknown[1:] else ""
            raise TypeError(
                f"HyperloopSuspension-v0 got an unexpected keyword argument {unknown[0]!r}{more}; "
                f"valid arguments: {list(valid)} (and config=EnvConfig(...), render_mode)"
            )
        if config is not None and not isinstance(config, EnvConfig):
            raise TypeError(f"config must be an EnvConfig, got {type(config).__name__}")
        canonical_keywords(kwargs, warn=True)
        by_path: dict[tuple[str, ...], dict[str, Any]] = {}
        for given, value in kwargs.items():
            d = KEYWORDS[ALIASES.get(given, given)]
            checked = d.keyword.check(given, value)  # the error names the keyword as given
            by_path.setdefault(d.path[:-1], {})[d.path[-1]] = checked
        base = config if config is not None else cls()
        top = by_path.pop((), {})
        for (group,), changes in by_path.items():
            top[group] = replace(getattr(base, group), **changes)
        return replace(base, **top)

    def to_kwargs(self) -> dict[str, Any]:
        """Flat keyword arguments that rebuild this config (JSON-friendly except for
        non-default disturbances, given as ``{name: {field: value}}``); physical
        overrides at ``None`` are left out."""
        out: dict[str, Any] = {}
        for name, d in KEYWORDS.items():
            v: Any = self
            for part in d.path:
                v = getattr(v, part)
            k = d.keyword
            if (k.optional and v is None) or (k.omit is not None and k.omit(v)):
                continue
            out[name] = k.dump(v) if k.dump is not None else v
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


KEYWORDS: dict[str, Declared] = {d.name: d for d in declared(EnvConfig)}
"""Every environment keyword (flat name -> its declaration and field path), in order."""

ALIASES: dict[str, str] = {a: n for n, d in KEYWORDS.items() for a in d.keyword.aliases}
"""Deprecated keyword names -> the keyword they set."""

PHYSICAL_OVERRIDES: tuple[str, ...] = tuple(
    n for n, d in KEYWORDS.items() if d.keyword.group == PHYSICAL
)
"""Keyword overrides of the physical model (``None`` keeps the scenario's value)."""

REWARD_KEYWORDS: dict[str, str] = {
    d.path[-1]: n for n, d in KEYWORDS.items() if d.keyword.group == REWARD
}
"""Reward term (the :class:`RewardWeights` field) -> the keyword of its weight."""

_PACKAGE_DIR = str(Path(__file__).resolve().parent)


def canonical_keywords(kwargs: dict[str, Any], warn: bool = False) -> dict[str, Any]:
    """``kwargs`` with deprecated keyword names (:data:`ALIASES`) replaced by the current
    ones (e.g. a configuration saved before the rename); ``warn``: a
    ``DeprecationWarning`` per alias, attributed to the caller's code. ``TypeError`` if a
    keyword is given under both names."""
    out: dict[str, Any] = {}
    for given, value in kwargs.items():
        name = ALIASES.get(given, given)
        if name != given:
            if name in kwargs:
                raise TypeError(f"got both {given!r} and {name!r} (the same keyword)")
            if warn:
                warnings.warn(
                    f"the keyword {given!r} is deprecated: use {name!r} (the same weight)",
                    DeprecationWarning,
                    stacklevel=_caller_stacklevel(),
                )
        out[name] = value
    return out


def _caller_stacklevel() -> int:
    """``stacklevel`` of the first frame outside hyperloop_env and gymnasium (so that the
    warning points at the user's ``gym.make`` / constructor call)."""
    frame, level = sys._getframe(1), 1
    while frame is not None and (
        frame.f_code.co_filename.startswith(_PACKAGE_DIR)
        or "gymnasium" in Path(frame.f_code.co_filename).parts
    ):
        frame, level = frame.f_back, level + 1  # type: ignore[assignment]
    return level


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
    def cost_limits(self) -> CostLimits:
        """What the safety cost of a step needs (:mod:`hyperloop_env.safety`): this
        configuration's clearances, ``safety_margin_mm`` and ``safety_cost``."""
        return CostLimits.of(
            self.base.magnet.clearance_m,
            self.base.guidance.clearance_m,
            self.config.safety_margin_mm * 1e-3,
            self.config.safety_cost,
        )

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
        return observation_spec(self.base.actuators, self.config.memory)

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
    """The resolved configuration; a number too large (or small) for the model's
    arithmetic raises ``ValueError`` naming the numeric keywords the configuration sets,
    never ``OverflowError`` or ``ZeroDivisionError``."""
    try:
        return _resolve_numbers(cfg)
    except ArithmeticError as exc:
        raise ValueError(_arithmetic_message(cfg, exc)) from exc


def _arithmetic_message(cfg: EnvConfig, exc: ArithmeticError) -> str:
    """Why the model could not be built with ``cfg``'s numbers, naming them."""
    given = [
        f"{name}={value!r}"
        for name, value in cfg.to_kwargs().items()
        if KEYWORDS[name].keyword.bounds is not None and value != KEYWORDS[name].default()
    ]
    which = ", ".join(given) if given else "the scenario's values"
    return (
        f"the model cannot be computed with {which}: a value is out of the range of its "
        f"floating-point arithmetic ({type(exc).__name__}: {exc})"
    )


def _resolve_numbers(cfg: EnvConfig) -> ResolvedConfig:
    sc = get_scenario(cfg.scenario)
    extra = cfg.disturbances
    if cfg.irregularity is not None:
        if any(d.name == Roughness.name for d in extra):
            raise ValueError("give either irregularity= or a 'roughness' disturbance, not both")
        extra = merge(extra, (Roughness.from_class(cfg.irregularity),))
    disturbances = merge(sc.disturbances, extra)
    try:
        base, cond = _base_params(cfg, sc, disturbances)
    except (ValueError, OverflowError) as exc:  # name the argument the user gave
        msg = _explain_timestep(cfg, sc)
        if msg is None:
            raise
        raise ValueError(msg) from exc
    _check_profile_memory(cfg, base)
    check_margin(cfg.safety_margin_mm * 1e-3, base.magnet.clearance_m, base.guidance.clearance_m)
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
    row_bytes = PROFILE_ROWS * np.dtype(np.float64).itemsize
    step = float(base.irregularity.grid_step_m)
    try:
        n, step = profile_grid(base)
    except OverflowError:  # more points than any grid can index: far beyond the budget
        need = "would need more points than a grid can index"
    else:
        nbytes = row_bytes * n
        if nbytes <= MAX_PROFILE_BYTES:
            return
        need = (
            f"({PROFILE_ROWS} rows x {n} points at {step:g} m, float64) would need "
            f"{nbytes / 2**20:.0f} MiB"
        )
    n_max = 2 ** int(math.floor(math.log2(MAX_PROFILE_BYTES / row_bytes)))
    length = base.simulation.track_length_m
    short = base.with_(simulation=replace(base.simulation, track_length_m=1.0))
    margin = track_length_needed_m(short) - 1.0  # beyond the section (exact at any length)
    longest = n_max * step - margin
    arg = (
        f"track_length_m={length!r}"
        if cfg.track_length_m is not None
        else (f"the scenario's track section ({length:g} m)")
    )
    raise ValueError(
        f"{arg} is too long: its guideway profile {need}, over the "
        f"{MAX_PROFILE_BYTES / 2**20:.0f} MiB budget per environment (MAX_PROFILE_BYTES); "
        f"track_length_m must be at most {math.floor(longest):.0f} m"
    )


def build_config(scenario: str = DEFAULT_SCENARIO, **kwargs: Any) -> ResolvedConfig:
    """``EnvConfig.from_kwargs(scenario=scenario, **kwargs).resolve()`` (a shortcut)."""
    return EnvConfig.from_kwargs(scenario=scenario, **kwargs).resolve()


__doc__ = with_table(__doc__, field_table(EnvConfig))

__all__ = [
    "ALIASES",
    "KEYWORDS",
    "MAX_PROFILE_BYTES",
    "MAX_REWARD_WEIGHT",
    "MIN_CONTROL_DT_S",
    "MIN_CURVE_RADIUS_M",
    "MIN_SPEED_KMH",
    "PHYSICAL_OVERRIDES",
    "EnvConfig",
    "ResolvedConfig",
    "RewardWeights",
    "SensorConfig",
    "build_config",
    "canonical_keywords",
]
