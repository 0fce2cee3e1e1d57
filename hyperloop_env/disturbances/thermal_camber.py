"""Thermal camber: each span bowed by a few millimetres (sun on one side of the tube).

A steel tube heated from above expands more on top than below and bows upward between
its piers: a temperature difference ΔT across a tube of depth h gives the curvature
κ = α_T·ΔT/h and, for a simply supported span L, a parabolic camber of midspan height
``c = κ·L²/8`` (beam theory; α_T = 1.2e-5 1/K for steel). For the default 3.3 m tube on
30 m spans, ΔT = 10 K gives c ≈ 4 mm; a few millimetres is typical of a sunny day.

Model: span j (between the piers at ``j·L`` and ``(j+1)·L``) gets the vertical profile
``c_j·4ξ(1 − ξ)``, ξ = (x − jL)/L, added under both magnet rows (the rail rises: the
gap of a repelling magnet closes), with ``c_j = severity·(1 + u_j)``, u_j uniform in
[−spread, +spread] drawn per span from the episode's seed (spans in the sun and in the
shade). The periodic bumps excite the vehicle at the span-passing frequency v/L.

* ``severity`` [m]: mean midspan camber ``c`` (typical 0.002–0.005 m).
* ``spread`` [-]: relative span-to-span variation (default 0.5).
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


@dataclass(frozen=True)
class ThermalCamber(Disturbance):
    """Parabolic upward camber of every span, ``severity`` [m] at midspan on average."""

    name: ClassVar[str] = "thermal_camber"
    severity_unit: ClassVar[str] = "mean midspan camber [m]"
    description: ClassVar[str] = "parabolic upward bow of each span (thermal gradient)"
    scales_with_severity: ClassVar[bool] = True
    scaling_note: ClassVar[str] = "each span's camber is the mean camber × the seed's factor"

    severity: float = 0.003
    spread: float = 0.5

    def __post_init__(self) -> None:
        check_real(self, "severity", lower=0.0, upper=0.05)
        check_real(self, "spread", lower=0.0, upper=1.0)

    def realise(
        self, params: ModelParams, grid: ProfileGrid, rng: np.random.Generator
    ) -> Realisation:
        if self.severity == 0.0:
            return Realisation()
        span = params.guideway.span_m
        x = grid.x_m
        j = np.floor(x / span).astype(np.int64)
        n_spans = int(j.max()) + 1
        camber = self.severity * (1.0 + rng.uniform(-self.spread, self.spread, n_spans))
        xi = x / span - j
        return profile_realisation(grid, camber[j] * 4.0 * xi * (1.0 - xi))
