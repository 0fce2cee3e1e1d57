"""Speed profile: the vehicle accelerates or brakes through the section.

A hyperloop accelerates out of and brakes into stations (linear motors, ≈ 0.1–0.3 g for
passenger comfort) and changes speed between track segments. The section is flown with a
constant longitudinal acceleration a: x_c(t) = x_0 + v_0·t + a·t²/2 (the span-passing
frequency and the curve loads v²/R change with the speed, and so does the observation's
speed entry); :class:`~hyperloop_env.physics.params.OperatingCondition`.

* ``severity`` [m/s²]: |a| (typical 1–3 m/s²; a passenger limit is ≈ 0.3 g = 2.9 m/s²).
* ``mode``: ``"brake"`` (default, a = −severity), ``"accelerate"`` (+severity) or
  ``"random"`` (the sign drawn per episode, probability 1/2 each).

The section must not brake the vehicle below a quarter of its entry speed
(:data:`~hyperloop_env.physics.params.MIN_EXIT_SPEED_FRACTION` = 1/4). With entry speed
v0 [m/s], braking deceleration b = −a > 0 [m/s²] and section length L = ``track_length_m``
[m], the speed at the end of the section is

    v_end = √(v0² − 2·b·L)  >=  v0/4   ⇔   b <= b_max = (1 − 1/16)·v0² / (2·L)

(:func:`max_braking_m_s2`; e.g. 0.72 m/s² at 1000 km/h over 50 km, 0.36 m/s² over
100 km; 18 m/s² over the default 2 km, so the limit only matters for long sections).

* A **configured** profile (``disturbances={"speed_profile": ...}``, any mode) whose braking
  exceeds b_max at the slowest entry speed an episode can have is refused when the
  environment is configured (``ValueError`` naming ``speed_profile severity``, the section
  length and b_max); with ``mode="random"`` the braking half of the episodes must fit.
* A profile **drawn** by a randomising scenario (``random``, ``benchmark-train``: severity
  uniform in 0–2 m/s², ``mode="random"``) is fitted to the episode instead: a braking draw
  above the episode's b_max (its drawn entry speed, the configured ``track_length_m``) is
  reduced to b_max, so the vehicle leaves the section at exactly v0/4. The draws (sign and
  severity, from the same generator) are unchanged, and so is every episode whose draw fits
  its section — all of them on sections up to ≈ 18 km, since b_max >= 2 m/s² there at the
  slowest drawn speed of 1000 km/h. Such an episode therefore never fails at reset.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from hyperloop_env.disturbances.base import Disturbance, ProfileGrid, Realisation, check_real
from hyperloop_env.physics.params import MIN_EXIT_SPEED_FRACTION, ModelParams

MODES = ("brake", "accelerate", "random")


def max_braking_m_s2(speed_m_s: float, track_length_m: float) -> float:
    """The largest braking deceleration b_max [m/s²] (> 0) that flies a section of
    ``track_length_m`` L [m] entered at ``speed_m_s`` v0 [m/s] without falling below
    ``MIN_EXIT_SPEED_FRACTION``·v0: b_max = (v0² − (v0/4)²) / (2·L). Rounded down to the
    last ulp that :class:`~hyperloop_env.physics.params.ModelParams`' own check (the same
    floating-point expression) accepts."""
    v0 = float(speed_m_s)
    length = float(track_length_m)
    v_min2 = (MIN_EXIT_SPEED_FRACTION * v0) ** 2
    b = (v0 * v0 - v_min2) / (2.0 * length)
    while b > 0.0 and v0 * v0 + 2.0 * -b * length < v_min2:
        b = math.nextafter(b, 0.0)
    return b


@dataclass(frozen=True)
class SpeedProfile(Disturbance):
    """Uniform acceleration (or braking) of ``severity`` m/s² through the section."""

    name: ClassVar[str] = "speed_profile"
    severity_unit: ClassVar[str] = "|longitudinal acceleration| [m/s²]"
    description: ClassVar[str] = "uniform braking or acceleration through the section"
    scales_with_severity: ClassVar[bool] = False
    scaling_note: ClassVar[str] = "the sign is drawn; the acceleration changes the kinematics"

    severity: float = 2.0
    mode: str = "brake"

    def __post_init__(self) -> None:
        check_real(self, "severity", lower=0.0, upper=20.0)
        if self.mode not in MODES:
            raise ValueError(f"SpeedProfile.mode must be one of {MODES}, got {self.mode!r}")

    def _acceleration(self, rng: np.random.Generator | None) -> float:
        if self.mode == "brake":
            return -self.severity
        if self.mode == "accelerate":
            return self.severity
        assert rng is not None
        return self.severity if rng.random() < 0.5 else -self.severity

    def validate(self, params: ModelParams) -> None:
        """ValueError if this profile brakes (``brake``, or the braking draws of
        ``random``) harder than the section of ``params`` allows at its entry speed
        (module docstring: b <= b_max = (1 − 1/16)·v0²/(2·L))."""
        if self.mode == "accelerate" or self.severity == 0.0:
            return
        v0 = params.condition.speed_m_s
        length = params.simulation.track_length_m
        b_max = max_braking_m_s2(v0, length)
        if self.severity <= b_max:
            return
        which = "" if self.mode == "brake" else ", whose episodes brake with probability 1/2"
        raise ValueError(
            f"speed_profile severity={self.severity!r} m/s² (SpeedProfile.severity, mode "
            f"{self.mode!r}{which}) brakes the vehicle below a quarter of its entry speed "
            f"({v0:.1f} m/s = {v0 * 3.6:g} km/h) within track_length_m={length!r}: "
            f"v_end² = v0² − 2·b·L must stay >= (v0/4)², so b <= {b_max:.3g} m/s² over this "
            f"section; brake less or shorten the section"
        )

    def configure(self, params: ModelParams) -> ModelParams:
        if self.mode == "random" or self.severity == 0.0:
            return params
        self.validate(params)  # name this field before ModelParams refuses the condition
        cond = replace(params.condition, acceleration_m_s2=self._acceleration(None))
        return params.with_(condition=cond)

    def realise(
        self, params: ModelParams, grid: ProfileGrid, rng: np.random.Generator
    ) -> Realisation:
        if self.mode != "random" or self.severity == 0.0:
            return Realisation()
        acc = self._acceleration(rng)
        if acc < 0.0:  # fit a drawn braking to the section (module docstring)
            b_max = max_braking_m_s2(params.condition.speed_m_s, params.simulation.track_length_m)
            acc = -min(-acc, b_max)
        cond = replace(params.condition, acceleration_m_s2=acc)
        return Realisation(params=params.with_(condition=cond))
