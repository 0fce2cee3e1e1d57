"""Actuator fault: one unit's levitation coil loses part of its current range, or freezes.

A power-electronics fault (a failed chopper leg, a current limit tripping, a stuck
regulator) leaves one coil with less authority than the controller expects. From an onset
time drawn per episode, the coil of one unit (drawn per episode) is limited to
[I0·(1 − f), I0 + f·(I_max − I0)] with f = 1 − severity, or, with ``freeze``, holds the
current it had at the onset (:class:`~hyperloop_env.physics.params.FaultParams`). The
passive vehicle (constant I0) is not affected; the family measures how much an active
controller relies on one coil.

* ``severity`` [-]: the fraction of the coil's current range lost (0: none, 1: the coil
  is held at I0).
* ``freeze``: hold the onset current instead of limiting the range (severity > 0 needed
  to activate).
* ``onset_fraction``: the onset is uniform in this fraction of the episode's duration
  (default the first half, after 10 %).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from hyperloop_env.disturbances.base import Disturbance, ProfileGrid, Realisation, check_real
from hyperloop_env.physics.model import episode_steps
from hyperloop_env.physics.params import FaultParams, ModelParams
from hyperloop_env.physics.units import N_UNITS


@dataclass(frozen=True)
class ActuatorFault(Disturbance):
    """One levitation coil loses ``severity`` of its range (or freezes) at a random time."""

    name: ClassVar[str] = "actuator_fault"
    severity_unit: ClassVar[str] = "fraction of one coil's current range lost [-]"
    description: ClassVar[str] = "one levitation coil loses current range or freezes"
    scales_with_severity: ClassVar[bool] = False
    scaling_note: ClassVar[str] = "the faulty unit and the onset are drawn per seed"

    severity: float = 0.5
    freeze: bool = False
    onset_fraction: tuple[float, float] = (0.1, 0.5)

    def __post_init__(self) -> None:
        check_real(self, "severity", lower=0.0, upper=1.0)
        if not isinstance(self.freeze, bool):
            raise ValueError(f"ActuatorFault.freeze must be a bool, got {self.freeze!r}")
        lo, hi = self.onset_fraction
        if not (0.0 <= lo <= hi <= 1.0):
            raise ValueError(
                f"ActuatorFault.onset_fraction must be (lo, hi) with 0 <= lo <= hi <= 1, "
                f"got {self.onset_fraction!r}"
            )

    def realise(
        self, params: ModelParams, grid: ProfileGrid, rng: np.random.Generator
    ) -> Realisation:
        if self.severity == 0.0:
            return Realisation()
        duration = episode_steps(params) * params.simulation.control_dt_s
        unit = int(rng.integers(N_UNITS))
        lo, hi = self.onset_fraction
        t_on = float(rng.uniform(lo, hi)) * duration
        fault = FaultParams(
            unit=unit, time_s=t_on, range_fraction=1.0 - self.severity, freeze=self.freeze
        )
        return Realisation(params=params.with_(fault=fault))
