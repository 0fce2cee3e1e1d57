"""Named operating scenarios of the Gymnasium environment.

A scenario fixes the operating condition (speed, curve, cant) and its disturbances (by
default the maglev-grade guideway irregularity); the environment's keyword arguments
(:class:`hyperloop_env.config.EnvConfig`) replace single values.

====================  ==========  ==============  ====  ============  =========================
name                  speed       curve radius    cant  irregularity  notes
====================  ==========  ==============  ====  ============  =========================
paper-1000-straight   1000 km/h   straight        0°    maglev        paper §5, default
paper-1000-curved     1000 km/h   200 000 m       0°    maglev        paper §5 (no cant stated)
paper-2000-straight   2000 km/h   straight        0°    maglev
paper-2000-curved     2000 km/h   200 000 m       0°    maglev
random                see below   see below       0°    see below     domain randomisation
benchmark-train       see below   see below       0°    see below     the benchmark's training
                                                                      distribution
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
  I0 follows from the new equilibrium);
* the disturbance families of :data:`RANDOM_DISTURBANCES`, each active with its
  probability and a severity uniform in its range (thermal camber 0–4 mm, payload 0–25 %
  of the capsule mass, actuator fault 0–50 % of one coil's range, speed profile 0–2 m/s²
  braking or accelerating, pier settlement σ 0–2 mm, joint steps σ 0–0.5 mm, sensor
  dropout 0–5 % of the time). A ``disturbances=`` keyword fixes a family instead.
  A drawn braking that a long section cannot fly (``track_length_m`` beyond ≈ 18 km) is
  capped so that the vehicle leaves the section at a quarter of its entry speed
  (:mod:`hyperloop_env.disturbances.speed_profile`, both randomising scenarios).

``benchmark-train`` (:data:`BENCHMARK_TRAIN`) is the training distribution of the
benchmark's agents (``agents/evaluation/benchmark_suite.json``): speed 1000–2000 km/h;
straight with probability 0.4, else a radius log-uniform in
:data:`BENCHMARK_RADIUS_RANGE_M` = [20 km, 1000 km] (below the critical radius of every
baseline at 2000 km/h); roughness uniform in [0, 0.6] of the German "low" amplitude (the
suite's roughness grid reaches 0.8; beyond ≈ 0.5 even PID touches within kilometres); the
capsule mass ±10 %; and every other family of the suite independently (probability and
severity range in :data:`BENCHMARK_DISTURBANCES`, each range up to about the suite's
highest level).

A keyword override of ``speed_kmh``, ``curve_radius_m`` or ``irregularity`` (or a
``roughness`` disturbance) fixes that quantity in the ``random`` scenario.

The curve (if any) starts at ``curve_start_m`` = 100 m with a 500 m clothoid transition
(:class:`~hyperloop_env.physics.params.OperatingCondition` defaults).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from hyperloop_env.disturbances import Disturbance, Roughness

RANDOM_SPEED_RANGE_KMH: tuple[float, float] = (1000.0, 2000.0)
RANDOM_RADIUS_RANGE_M: tuple[float, float] = (100_000.0, 1_000_000.0)
RANDOM_STRAIGHT_PROBABILITY = 0.5
RANDOM_IRREGULARITY_CLASSES: tuple[str, ...] = ("none", "maglev", "maglev-rough")
RANDOM_MASS_FACTOR_RANGE: tuple[float, float] = (0.9, 1.1)
RANDOM_DISTURBANCES: dict[str, tuple[float, tuple[float, float], dict]] = {
    # family: (probability of being active in an episode, severity range, other fields)
    "thermal_camber": (0.3, (0.0, 0.004), {}),
    "payload": (0.5, (0.0, 0.25), {}),
    "actuator_fault": (0.2, (0.0, 0.5), {}),
    "speed_profile": (0.3, (0.0, 2.0), {"mode": "random"}),
    "pier_settlement": (0.2, (0.0, 0.002), {}),
    "joint_steps": (0.2, (0.0, 0.0005), {}),
    "sensor_dropout": (0.1, (0.0, 0.05), {}),
}
"""Disturbance families the ``random`` scenario draws per episode (each independently
active with its probability, its severity uniform in the range; roughness is the drawn
irregularity class). Drawn from a generator derived from the episode's simulator seed, so
the other draws of the scenario do not change when a family is added."""

BENCHMARK_RADIUS_RANGE_M: tuple[float, float] = (20_000.0, 1_000_000.0)
BENCHMARK_ROUGHNESS_RANGE: tuple[float, float] = (0.0, 0.6)
BENCHMARK_DISTURBANCES: dict[str, tuple[float, tuple[float, float], dict]] = {
    # family: (probability of being active in an episode, severity range, other fields);
    # lengths in mm / 1000 (metres), so a camber range is not read as a clearance
    "thermal_camber": (0.3, (0.0, 8 / 1000), {}),
    "payload": (0.3, (0.0, 0.25), {}),
    "actuator_fault": (0.25, (0.0, 0.9), {}),
    "speed_profile": (0.3, (0.0, 2.0), {"mode": "random"}),
    "pier_settlement": (0.3, (0.0, 4 / 1000), {}),
    "joint_steps": (0.3, (0.0, 1.2 / 1000), {}),
    "sensor_dropout": (0.2, (0.0, 0.4), {}),
}
"""The families ``benchmark-train`` draws per episode besides roughness (module
docstring)."""
DEFAULT_IRREGULARITY = "maglev"
"""The scenarios' irregularity class: the German "low" spectrum at 10 % amplitude."""

DEFAULT_COIL_TIME_CONSTANT_S = 2e-3
"""Default first-order coil current lag τ [s] of the environment (≈ an 80 Hz current loop,
1/(2πτ)). The simulator's own default is 0 (ideal current source); the environment uses a
finite lag so that agents cannot rely on infinitely fast currents unless they ask for 0."""


def _default_disturbances() -> tuple[Disturbance, ...]:
    return (Roughness.from_class(DEFAULT_IRREGULARITY),)


@dataclass(frozen=True)
class RandomSpec:
    """What a randomising scenario draws at every reset (see the module docstring): speed
    uniform in ``speed_range_kmh``; straight with ``straight_probability``, else a radius
    log-uniform in ``radius_range_m``; the irregularity class uniformly from
    ``irregularity_classes`` — or, if ``roughness_range`` is given, a roughness severity
    uniform in it (amplitude factor of the German "low" spectrum); the capsule mass scaled
    uniformly in ``mass_factor_range``; and each family of ``disturbances`` (name →
    (probability, severity range, other fields)) independently."""

    speed_range_kmh: tuple[float, float] = RANDOM_SPEED_RANGE_KMH
    radius_range_m: tuple[float, float] = RANDOM_RADIUS_RANGE_M
    straight_probability: float = RANDOM_STRAIGHT_PROBABILITY
    irregularity_classes: tuple[str, ...] = RANDOM_IRREGULARITY_CLASSES
    roughness_range: tuple[float, float] | None = None
    mass_factor_range: tuple[float, float] = RANDOM_MASS_FACTOR_RANGE
    disturbances: dict[str, tuple[float, tuple[float, float], dict]] = field(
        default_factory=lambda: dict(RANDOM_DISTURBANCES)
    )

    def __hash__(self) -> int:
        return hash((self.speed_range_kmh, self.radius_range_m, self.roughness_range))


@dataclass(frozen=True)
class Scenario:
    """One named scenario (see the module docstring). ``random`` (a :class:`RandomSpec`)
    makes it draw its conditions at every reset."""

    name: str
    description: str
    speed_kmh: float = 1000.0
    curve_radius_m: float = math.inf
    cant_deg: float = 0.0
    disturbances: tuple[Disturbance, ...] = field(default_factory=_default_disturbances)
    random: RandomSpec | None = None

    @property
    def randomize(self) -> bool:
        return self.random is not None


BENCHMARK_TRAIN = RandomSpec(
    radius_range_m=BENCHMARK_RADIUS_RANGE_M,
    straight_probability=0.4,
    roughness_range=BENCHMARK_ROUGHNESS_RANGE,
    disturbances=BENCHMARK_DISTURBANCES,
)
"""What ``benchmark-train`` draws at every reset (module docstring)."""

PAPER_SCENARIOS: tuple[str, ...] = (
    "paper-1000-straight",
    "paper-1000-curved",
    "paper-2000-straight",
    "paper-2000-curved",
)
"""The paper's four conditions (§5), in the order of its tables."""

SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in (
        Scenario(PAPER_SCENARIOS[0], "1000 km/h, straight track (paper §5)", 1000.0),
        Scenario(
            PAPER_SCENARIOS[1], "1000 km/h, R = 200 km curve, no cant (paper §5)", 1000.0, 2e5
        ),
        Scenario(PAPER_SCENARIOS[2], "2000 km/h, straight track (paper §5)", 2000.0),
        Scenario(
            PAPER_SCENARIOS[3], "2000 km/h, R = 200 km curve, no cant (paper §5)", 2000.0, 2e5
        ),
        Scenario(
            "random",
            "speed, curve, irregularity class, capsule mass and disturbance families drawn "
            "at every reset",
            random=RandomSpec(),
        ),
        Scenario(
            "benchmark-train",
            "the benchmark's training distribution: speed, curve down to 20 km, roughness "
            "0-0.6 and every disturbance family of the suite drawn at every reset",
            random=BENCHMARK_TRAIN,
        ),
    )
}
DEFAULT_SCENARIO = PAPER_SCENARIOS[0]


def get_scenario(name: str) -> Scenario:
    """The scenario called ``name``; ValueError listing the valid names otherwise."""
    if not isinstance(name, str) or name not in SCENARIOS:
        raise ValueError(f"unknown scenario {name!r}; valid scenarios: {sorted(SCENARIOS)}")
    return SCENARIOS[name]


def expand_scenarios(names: str | list[str] | tuple[str, ...]) -> list[str]:
    """``"paper"`` → the four paper scenarios; other names must be known scenarios."""
    if isinstance(names, str):
        names = [names]
    out: list[str] = []
    for n in names:
        items = PAPER_SCENARIOS if n == "paper" else (n,)
        for it in items:
            if it not in SCENARIOS:
                raise ValueError(
                    f"unknown scenario {it!r}; valid: 'paper', {', '.join(sorted(SCENARIOS))}"
                )
            if it not in out:
                out.append(it)
    return out
