"""Joint steps: small offsets where two spans meet.

Physics and basis. Each span of the guideway rests on its own bearings; bearing heights,
shims and the positioning of the beam ends are set to a tolerance, so the rail of span
``j`` sits at a slightly different height (and lateral position) than its neighbours. The
model shifts every span's rail by a random constant: span ``j`` (between the piers at
``j·L`` and ``(j+1)·L``) is offset by ``c_j ~ N(0, σ²)`` vertically and
``d_j ~ N(0, (lateral_fraction·σ)²)`` laterally, independent between spans, drawn from the
episode's seed. At each joint the rail then steps by ``c_{j+1} − c_j`` (standard deviation
σ·√2).

A magnet does not see a sharp step: its force acts over its pole length ``a2``
(``MagnetParams.pole_length_m``, 1.1 m), and the gap averaged over that length changes
linearly while the magnet passes the joint. The offset is therefore the step function
averaged over a window of the pole length centred at ``x``: a linear ramp of length ``a2``
centred on the joint (exactly the moving average of the step function; ``ramp_m`` overrides
the length, 0 gives the bare step). The same averaging is why the irregularity spectrum is
cut below 2 m wavelengths (:class:`~hyperloop_env.physics.params.IrregularityParams`).

Units and magnitudes.

* ``severity`` = σ [m]: standard deviation of each span's offset. Guideway-beam joints of
  maglev lines are adjusted to a few tenths of a millimetre; 0.1–1 mm covers "as built"
  to "poorly maintained" (a 1 mm step at 1000 km/h passes in 4 ms under a 1.1 m magnet).
* ``lateral_fraction`` [-]: σ_lateral / σ (default 0.5).
* ``ramp_m`` [m]: ramp length; None (default) uses the magnet pole length.

Sign: positive raises the rail (y up) / moves it to +z. Both rails (left and right
vertical rows) get the same vertical offset.
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


def ramped_steps(x: np.ndarray, span_m: float, values: np.ndarray, ramp_m: float) -> np.ndarray:
    """Piecewise constant ``values[j]`` on span j (``j·span ≤ x < (j+1)·span``), averaged
    over a window of ``ramp_m`` centred at each x: linear ramps of length ``ramp_m`` centred
    on the joints (``ramp_m < span_m``). ``values[j]`` for j = −1 is taken as ``values[0]``
    (the track starts at the first span)."""
    j = np.floor(x / span_m).astype(np.int64)
    out = values[j].astype(np.float64)
    if ramp_m <= 0.0:
        return out
    joint = np.rint(x / span_m).astype(np.int64)  # nearest joint index
    d = x - joint * span_m
    near = (np.abs(d) < 0.5 * ramp_m) & (joint >= 1)
    jn = joint[near]
    before, after = values[jn - 1], values[jn]
    out[near] = before + (after - before) * (d[near] + 0.5 * ramp_m) / ramp_m
    return out


@dataclass(frozen=True)
class JointSteps(Disturbance):
    """Every span's rail shifted by a random constant, σ = ``severity`` [m]; steps at the
    joints, ramped over the magnet length."""

    name: ClassVar[str] = "joint_steps"
    severity_unit: ClassVar[str] = "σ of each span's rail offset [m]"
    description: ClassVar[str] = "random offset per span: steps at the span joints"
    scales_with_severity: ClassVar[bool] = True
    scaling_note: ClassVar[str] = "each span's offset is the seed's normal draw × σ"

    severity: float = 0.0005
    lateral_fraction: float = 0.5
    ramp_m: float | None = None

    def __post_init__(self) -> None:
        check_real(self, "severity", lower=0.0, upper=0.02)
        check_real(self, "lateral_fraction", lower=0.0, upper=2.0)
        if self.ramp_m is not None:
            check_real(self, "ramp_m", lower=0.0, upper=10.0)

    def realise(
        self, params: ModelParams, grid: ProfileGrid, rng: np.random.Generator
    ) -> Realisation:
        if self.severity == 0.0:
            return Realisation()
        span = params.guideway.span_m
        ramp = params.magnet.pole_length_m if self.ramp_m is None else self.ramp_m
        if ramp >= span:
            raise ValueError(f"JointSteps.ramp_m must be < the span ({span!r} m), got {ramp!r}")
        x = grid.x_m
        n_spans = int(np.floor(x[-1] / span)) + 2
        vert = rng.normal(0.0, 1.0, n_spans) * self.severity
        lat = rng.normal(0.0, 1.0, n_spans) * (self.lateral_fraction * self.severity)
        return profile_realisation(
            grid, ramped_steps(x, span, vert, ramp), ramped_steps(x, span, lat, ramp)
        )
