"""Pier settlement: every support of the guideway displaced at random (differential
settlement and construction misalignment), the rail following the piers piecewise
linearly.

Physics and basis. The guideway is a chain of *simply supported* spans (piers every
``GuidewayParams.span_m``, 30 m by default). A displaced support moves a simply supported
span as a rigid body (no bending is induced), so the rail between two piers is the straight
line through their displaced positions: the profile is piecewise linear with kinks at the
piers. Uniform settlement of every pier does not matter to the vehicle; what matters is the
*differential* settlement between neighbouring piers, which is what this family draws:
pier ``j`` (at ``x = j·L``, ``j = 0, 1, …``) gets a vertical offset ``v_j ~ N(0, σ²)`` and a
lateral offset ``h_j ~ N(0, (lateral_fraction·σ)²)``, independent between piers, drawn from
the episode's seed. Both rails of the tube follow the same pier (no roll of the
cross-section), so the vertical offset is added under the left and the right magnets alike.

Units and magnitudes.

* ``severity`` = σ [m]: standard deviation of each pier's vertical offset. Design limits for
  ballastless high-speed-rail bridges allow a few millimetres of differential settlement
  between adjacent piers (of order 5 mm), while maglev guideways are built and re-aligned to
  sub-millimetre tolerances; 0.5–5 mm spans "well aligned" to "settled". With σ the
  adjacent-pier difference has standard deviation σ·√2 and the kink angle at a pier
  (v_{j-1} − 2 v_j + v_{j+1})/L has standard deviation σ·√6/L.
* ``lateral_fraction`` [-]: σ_lateral / σ (default 0.5: piers settle more than they shift
  sideways).

Sign: a positive offset raises the rail (y up, :mod:`hyperloop_env.physics.params`); the
lateral offset is along +z (to the right). The offset is added to the simulator's profile
grid (:class:`~hyperloop_env.disturbances.base.ProfileGrid`), rows left vertical, right
vertical, lateral.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from hyperloop_env.disturbances.base import (
    Disturbance,
    ProfileGrid,
    Realisation,
    check_real,
    profile_realisation,
)
from hyperloop_env.physics.params import ModelParams


def pier_offsets(
    n_piers: int, sigma_m: float, lateral_sigma_m: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """(vertical, lateral) offsets [m] of ``n_piers`` piers, in this draw order."""
    vert = rng.normal(0.0, 1.0, n_piers) * sigma_m
    lat = rng.normal(0.0, 1.0, n_piers) * lateral_sigma_m
    return vert, lat


@dataclass(frozen=True)
class PierSettlement(Disturbance):
    """Random vertical (and lateral) offset of every pier, σ = ``severity`` [m]; the rail is
    piecewise linear between the piers."""

    name: ClassVar[str] = "pier_settlement"
    severity_unit: ClassVar[str] = "σ of each pier's vertical offset [m]"
    description: ClassVar[str] = "random pier offsets, rail piecewise linear (kinks at piers)"
    scales_with_severity: ClassVar[bool] = True
    scaling_note: ClassVar[str] = "each pier's offset is the seed's normal draw × σ"

    severity: float = 0.002
    lateral_fraction: float = 0.5

    def __post_init__(self) -> None:
        check_real(self, "severity", lower=0.0, upper=0.05)
        check_real(self, "lateral_fraction", lower=0.0, upper=2.0)

    def realise(
        self, params: ModelParams, grid: ProfileGrid, rng: np.random.Generator
    ) -> Realisation:
        if self.severity == 0.0:
            return Realisation()
        span = params.guideway.span_m
        x = grid.x_m
        n_piers = int(np.floor(x[-1] / span)) + 2  # piers 0 … past the end of the grid
        vert, lat = pier_offsets(n_piers, self.severity, self.lateral_fraction * self.severity, rng)
        xp = np.arange(n_piers) * span
        return profile_realisation(grid, np.interp(x, xp, vert), np.interp(x, xp, lat))
