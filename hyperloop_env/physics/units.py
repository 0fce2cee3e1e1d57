"""The vehicle's magnet units: the one place that defines how many there are.

Four units on two levitation sets: front/rear × left/right. Everything sized per unit
(layout blocks, actuator channels, observation blocks, STS tables) derives from
:data:`UNIT_NAMES`; the unit geometry is in :func:`hyperloop_env.physics.vehicle.unit_offsets`.
"""

from __future__ import annotations

UNIT_NAMES: tuple[str, ...] = ("FL", "FR", "RL", "RR")
"""Front-left, front-right, rear-left, rear-right (front set at +d1/2, left at z = −d2/2)."""

N_UNITS: int = len(UNIT_NAMES)
