"""Payload: extra capsule mass the nominal design does not know, placed off-centre.

A hyperloop capsule of 15 t carries up to ~28 passengers with luggage (≈ 2.5 t) or
freight; the nominal coil currents I0 (and every model-based controller) are designed for
the empty vehicle, so the passive suspension sags under the load and, with the load off
the centre line, tilts: the corners carry P_a = (W/4)·(1 ± x_g/(d1/2) ± z_g/(d2/2))
(:class:`~hyperloop_env.physics.params.VehicleParams`).

* ``severity`` [-]: payload mass as a fraction of the capsule mass (0.1 = 1.5 t; typical
  0–0.3).
* ``x_range_m``, ``z_range_m``: the payload's own centre of gravity is drawn per episode,
  uniform in ±x_range (along the capsule, default ±L/4 = ±6.25 m) and ±z_range (across,
  default ±b/4 = ±0.675 m); the capsule's centre of gravity moves by
  payload·x_p/(m_v + payload).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from hyperloop_env.disturbances.base import Disturbance, ProfileGrid, Realisation, check_real
from hyperloop_env.physics.params import ModelParams


@dataclass(frozen=True)
class Payload(Disturbance):
    """``severity`` × the capsule mass added, at a random off-centre position."""

    name: ClassVar[str] = "payload"
    severity_unit: ClassVar[str] = "payload mass / capsule mass [-]"
    description: ClassVar[str] = "unknown payload mass with an off-centre centre of gravity"
    scales_with_severity: ClassVar[bool] = False
    scaling_note: ClassVar[str] = (
        "the payload's position is drawn; the mass ratio changes the model"
    )

    severity: float = 0.15
    x_range_m: float = 6.25
    z_range_m: float = 0.675

    def __post_init__(self) -> None:
        check_real(self, "severity", lower=0.0, upper=1.0)
        check_real(self, "x_range_m", lower=0.0, upper=12.5)
        check_real(self, "z_range_m", lower=0.0, upper=1.35)

    def realise(
        self, params: ModelParams, grid: ProfileGrid, rng: np.random.Generator
    ) -> Realisation:
        if self.severity == 0.0:
            return Realisation()
        v = params.vehicle
        m_p = self.severity * v.capsule_mass_kg
        x_p = float(rng.uniform(-self.x_range_m, self.x_range_m))
        z_p = float(rng.uniform(-self.z_range_m, self.z_range_m))
        m_tot = v.capsule_mass_kg + v.payload_kg + m_p
        veh = replace(
            v,
            payload_kg=v.payload_kg + m_p,
            cg_offset_x_m=(v.cg_offset_x_m * (m_tot - m_p) + m_p * x_p) / m_tot,
            cg_offset_z_m=(v.cg_offset_z_m * (m_tot - m_p) + m_p * z_p) / m_tot,
        )
        return Realisation(params=params.with_(vehicle=veh))
