"""Magnet force law (paper eq. 3–6), compiled.

Per unit, with ``K = μ0 N²/4``, current ``I`` [A], gap ``δ = δ0 + s`` [m] and lateral
offset ``z`` [m] of the unit from its rail::

    A(z)  = a2 · (b2 − |z|_s)                          overlap area [m²]   (paper, after eq. 3)
    |z|_s = (2/π)·(z·arctan(z/δ0) − (δ0/2)·ln(1 + (z/δ0)²))   fringing-smoothed |z|
    F_y   = K I² A(z) / δ²                             [N]  (eq. 3 with φ = N I/R, eq. 4,
                                                              R = 2δ/(μ0 A), eq. 5 + 6)
    F_z   = −K I² a2 (2/π) arctan(z/δ0) / δ            [N]  (= ∂W'/∂z, W' = K I² A/δ)

``F_y`` acts on the magnet unit along +y (up) in both orientations: a repelling magnet
rides above its guide and is pushed up, an attracting one hangs below its rail and is
pulled up; the guideway receives −F_y. What differs is how the gap relates to the unit
position (``s = σ·(y − w − r)``, σ = +1 / −1), hence the sign of the magnetic stiffness.
To keep the state finite after contact the gap in the force law is floored at 0.1·δ0
(the run has already ended in contact by then: the clearance is < δ0).
"""

from __future__ import annotations

import math

import numba as nb

from hyperloop_env.physics.params import MU0, MagnetParams

TWO_OVER_PI = 2.0 / math.pi


@nb.njit(cache=True, fastmath=False)
def smoothed_abs(z: float, delta0: float) -> float:
    """|z|_s whose derivative is (2/π)·arctan(z/δ0) [m]."""
    u = z / delta0
    return TWO_OVER_PI * (z * math.atan(u) - 0.5 * delta0 * math.log1p(u * u))


@nb.njit(cache=True)
def magnet_forces(
    current: float, s: float, z: float, kmag: float, a2: float, b2: float, delta0: float
) -> tuple[float, float]:
    """(F_y, F_z) [N] of one unit for current [A], gap excursion s [m], lateral offset z [m]."""
    delta = delta0 + s
    if delta < 0.1 * delta0:
        delta = 0.1 * delta0
    overlap = b2 - smoothed_abs(z, delta0)
    if overlap < 0.05 * b2:
        overlap = 0.05 * b2
    ki = kmag * current * current
    fy = ki * a2 * overlap / (delta * delta)
    fz = -ki * a2 * TWO_OVER_PI * math.atan(z / delta0) / delta
    return fy, fz


def nominal_current_A(magnet: MagnetParams, force_N: float) -> float:
    """Current holding ``force_N`` at the nominal gap with no lateral offset:
    I0 = δ0·√(F/(K·A0)), K = μ0N²/4 (inverse of eq. 3–5) [A]."""
    kmag = MU0 * magnet.turns**2 / 4.0
    return magnet.nominal_gap_m * math.sqrt(force_N / (kmag * magnet.pole_area_m2))


def magnetic_stiffness_N_per_m(magnet: MagnetParams, force_N: float) -> float:
    """|∂F_y/∂δ| = 2F/δ0 at constant current [N/m]: restoring for the repelling
    orientation, destabilising for the attracting one."""
    return 2.0 * force_N / magnet.nominal_gap_m
