"""Named operating scenarios of the Gymnasium environment and the keyword overrides.

A scenario fixes the operating condition (speed, curve, cant) and the guideway
irregularity class; keyword overrides given to the environment replace single values.

====================  ==========  ==============  ====  ============  =========================
name                  speed       curve radius    cant  irregularity  notes
====================  ==========  ==============  ====  ============  =========================
paper-1000-straight   1000 km/h   straight        0°    maglev        paper §5, default
paper-1000-curved     1000 km/h   200 000 m       0°    maglev        paper §5 (no cant stated)
paper-2000-straight   2000 km/h   straight        0°    maglev
paper-2000-curved     2000 km/h   200 000 m       0°    maglev
random                see below   see below       0°    see below     domain randomisation
====================  ==========  ==============  ====  ============  =========================

``random`` draws, at every reset and from the environment's ``np_random`` (so a seed
reproduces it):

* speed uniform in :data:`RANDOM_SPEED_RANGE_KMH` = [1000, 2000] km/h;
* with probability :data:`RANDOM_STRAIGHT_PROBABILITY` = 0.5 a straight track, otherwise a
  curve whose radius is log-uniform in :data:`RANDOM_RADIUS_RANGE_M` = [100 km, 1000 km]
  (it includes radii the passive vehicle cannot hold at the higher speeds);
* the irregularity class uniformly from :data:`RANDOM_IRREGULARITY_CLASSES`
  (``none``, ``maglev``, ``maglev-rough``; the rail spectra ``german-*`` are far too rough
  for an 8 mm clearance and are available only as an explicit override);
* the capsule mass scaled by a factor uniform in [0.9, 1.1] (±10 %; the nominal current
  I0 follows from the new equilibrium).

A keyword override of ``speed_kmh``, ``curve_radius_m`` or ``irregularity`` fixes that
quantity in the ``random`` scenario (it is then no longer drawn).

The curve (if any) starts at ``curve_start_m`` = 100 m with a 500 m clothoid transition
(:class:`~hyperloop_env.physics.params.OperatingCondition` defaults).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from hyperloop_env.physics.params import (
    IRREGULARITY_CLASSES,
    IrregularityParams,
    MagnetParams,
    ModelParams,
    OperatingCondition,
    SimulationParams,
    VehicleParams,
)

RANDOM_SPEED_RANGE_KMH: tuple[float, float] = (1000.0, 2000.0)
RANDOM_RADIUS_RANGE_M: tuple[float, float] = (100_000.0, 1_000_000.0)
RANDOM_STRAIGHT_PROBABILITY = 0.5
RANDOM_IRREGULARITY_CLASSES: tuple[str, ...] = ("none", "maglev", "maglev-rough")
RANDOM_MASS_FACTOR_RANGE: tuple[float, float] = (0.9, 1.1)

DEFAULT_COIL_TIME_CONSTANT_S = 2e-3
"""Default first-order coil current lag τ [s] of the environment (≈ an 80 Hz current loop,
1/(2πτ)). The simulator's own default is 0 (ideal current source); the environment uses a
finite lag so that agents cannot rely on infinitely fast currents unless they ask for 0."""


@dataclass(frozen=True)
class Scenario:
    """One named scenario (see the module docstring)."""

    name: str
    description: str
    speed_kmh: float = 1000.0
    curve_radius_m: float = math.inf
    cant_deg: float = 0.0
    irregularity: str = "maglev"
    randomize: bool = False


SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in (
        Scenario("paper-1000-straight", "1000 km/h, straight track (paper §5)", 1000.0),
        Scenario(
            "paper-1000-curved", "1000 km/h, R = 200 km curve, no cant (paper §5)", 1000.0, 2e5
        ),
        Scenario("paper-2000-straight", "2000 km/h, straight track (paper §5)", 2000.0),
        Scenario(
            "paper-2000-curved", "2000 km/h, R = 200 km curve, no cant (paper §5)", 2000.0, 2e5
        ),
        Scenario(
            "random",
            "speed, curve, irregularity class and capsule mass drawn at every reset",
            randomize=True,
        ),
    )
}
DEFAULT_SCENARIO = "paper-1000-straight"

OVERRIDE_NAMES: tuple[str, ...] = (
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
"""Keyword overrides that change the physical model (the environment adds its own:
``action_scale``, ``sensor_noise_std``, ``sensor_delay``, reward weights, ``render_mode``)."""


def get_scenario(name: str) -> Scenario:
    """The scenario called ``name``; ValueError listing the valid names otherwise."""
    if not isinstance(name, str) or name not in SCENARIOS:
        raise ValueError(f"unknown scenario {name!r}; valid scenarios: {sorted(SCENARIOS)}")
    return SCENARIOS[name]


def _magnet_orientation(value: Any) -> str:
    if value not in ("repelling", "attracting"):
        raise ValueError(
            f"magnet must be 'repelling' or 'attracting' (MagnetParams.orientation), got {value!r}"
        )
    return value


def _irregularity_class(value: Any) -> str:
    if not isinstance(value, str) or value not in IRREGULARITY_CLASSES:
        raise ValueError(
            f"irregularity must be one of {sorted(IRREGULARITY_CLASSES)} "
            f"(IrregularityParams.spectrum), got {value!r}"
        )
    return value


@dataclass(frozen=True)
class ScenarioConfig:
    """A scenario with its overrides applied: the base parameters and what to randomise."""

    scenario: Scenario
    base: ModelParams
    draw_speed: bool
    draw_curve: bool
    draw_irregularity: bool
    draw_mass: bool

    @property
    def randomized(self) -> bool:
        return self.draw_speed or self.draw_curve or self.draw_irregularity or self.draw_mass

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


def build_config(scenario: str = DEFAULT_SCENARIO, **overrides: Any) -> ScenarioConfig:
    """Apply keyword ``overrides`` (names in :data:`OVERRIDE_NAMES`; ``None`` = keep the
    scenario's value) to the named scenario. Invalid names or values raise ValueError."""
    sc = get_scenario(scenario)
    unknown = sorted(set(overrides) - set(OVERRIDE_NAMES))
    if unknown:
        raise ValueError(f"unknown override(s) {unknown}; valid overrides: {list(OVERRIDE_NAMES)}")
    ov = {k: v for k, v in overrides.items() if v is not None}
    cond = OperatingCondition(
        speed_kmh=ov.get("speed_kmh", sc.speed_kmh),
        curve_radius_m=ov.get("curve_radius_m", sc.curve_radius_m),
        cant_deg=ov.get("cant_deg", sc.cant_deg),
    )
    magnet = MagnetParams(
        orientation=_magnet_orientation(ov.get("magnet", "repelling")),
        clearance_m=ov.get("clearance_m", MagnetParams.clearance_m),
        coil_time_constant_s=ov.get("coil_time_constant_s", DEFAULT_COIL_TIME_CONSTANT_S),
    )
    irr = IrregularityParams(spectrum=_irregularity_class(ov.get("irregularity", sc.irregularity)))
    sim = SimulationParams(
        control_dt_s=ov.get("control_dt_s", SimulationParams.control_dt_s),
        track_length_m=ov.get("track_length_m", SimulationParams.track_length_m),
    )
    base = ModelParams(
        vehicle=VehicleParams(), magnet=magnet, condition=cond, irregularity=irr, simulation=sim
    )
    r = sc.randomize
    cfg = ScenarioConfig(
        scenario=sc,
        base=base,
        draw_speed=r and "speed_kmh" not in ov,
        draw_curve=r and "curve_radius_m" not in ov,
        draw_irregularity=r and "irregularity" not in ov,
        draw_mass=r,
    )
    if cfg.draw_speed:  # validate the extreme of the range (ModelParams checks the travel)
        base.with_(condition=replace(cond, speed_kmh=RANDOM_SPEED_RANGE_KMH[1]))
    from hyperloop_env.physics.model import pack

    pack(base)  # raises if the magnet cannot carry the vehicle with these parameters
    return cfg
