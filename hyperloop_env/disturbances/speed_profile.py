"""Speed profile: the vehicle accelerates or brakes through the section.

A hyperloop accelerates out of and brakes into stations (linear motors, ≈ 0.1–0.3 g for
passenger comfort) and changes speed between track segments. The section is flown with a
constant longitudinal acceleration a: x_c(t) = x_0 + v_0·t + a·t²/2 (the span-passing
frequency and the curve loads v²/R change with the speed, and so does the observation's
speed entry); :class:`~hyperloop_env.physics.params.OperatingCondition`.

* ``severity`` [m/s²]: |a| (typical 1–3 m/s²; a passenger limit is ≈ 0.3 g = 2.9 m/s²).
* ``mode``: ``"brake"`` (default, a = −severity), ``"accelerate"`` (+severity) or
  ``"random"`` (the sign drawn per episode). The section must not brake the vehicle below a
  quarter of its entry speed (ValueError otherwise).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from hyperloop_env.disturbances.base import Disturbance, ProfileGrid, Realisation, check_real
from hyperloop_env.physics.params import ModelParams

MODES = ("brake", "accelerate", "random")


@dataclass(frozen=True)
class SpeedProfile(Disturbance):
    """Uniform acceleration (or braking) of ``severity`` m/s² through the section."""

    name: ClassVar[str] = "speed_profile"
    severity_unit: ClassVar[str] = "|longitudinal acceleration| [m/s²]"
    description: ClassVar[str] = "uniform braking or acceleration through the section"

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

    def configure(self, params: ModelParams) -> ModelParams:
        if self.mode == "random" or self.severity == 0.0:
            return params
        cond = replace(params.condition, acceleration_m_s2=self._acceleration(None))
        return params.with_(condition=cond)

    def realise(
        self, params: ModelParams, grid: ProfileGrid, rng: np.random.Generator
    ) -> Realisation:
        if self.mode != "random" or self.severity == 0.0:
            return Realisation()
        cond = replace(params.condition, acceleration_m_s2=self._acceleration(rng))
        return Realisation(params=params.with_(condition=cond))
