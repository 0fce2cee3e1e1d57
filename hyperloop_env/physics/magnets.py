"""Magnet force laws (paper eq. 3–6), compiled.

Levitation magnet, per unit, with ``K = μ0 N²/4``, current ``I`` [A], gap ``δ = δ0 + s`` [m]
and lateral offset ``z`` [m] of the unit from its rail::

    A(z)  = a2 · (b2 − |z|_s)                          overlap area [m²]   (paper, after eq. 3)
    |z|_s = (2/π)·(z·arctan(z/δ0) − (δ0/2)·ln(1 + (z/δ0)²))   fringing-smoothed |z|
    F_y   = K I² A(z) / δ²                             [N]  (eq. 3 with φ = N I/R, eq. 4,
                                                              R = 2δ/(μ0 A), eq. 5 + 6)
    F_z   = σ·K I² a2 (2/π) arctan(z/δ0) / δ           [N]  (edge force, σ = ±1)

Both components are gradients of one energy ``W = K I² A(z)/δ`` at constant current
(docs/model.md, revised lateral bullet). Attracting (σ = −1): the unit moves in the
co-energy, ``F = +∇W`` in (δ-closing, z) — the edge force restores. Repelling (σ = +1):
``F = −∇W`` — the stored energy falls as the overlap shrinks, so the edge force pushes the
unit further off its rail. The work of (F_y, F_z) around any closed loop in (gap, lateral)
is zero in both cases (verification case ``magnet_work_loop_*``).

Guidance pair (:class:`~hyperloop_env.physics.params.GuidanceParams`), per unit, with
``K_g = μ0 N_g²/4``, area ``A_g``, bias ``I_g0``, differential command ``ΔI``::

    F_L = K_g (I_g0 + ΔI)² A_g / (δg0 + z)²,   F_R = K_g (I_g0 − ΔI)² A_g / (δg0 − z)²
    F_z = σ·(F_L − F_R)                         [N] on the unit (−F_z on the guideway)

Repelling: each magnet pushes the unit away from its rail, stiffness 4·F_g0/δg0 at bias
(restoring); attracting: each pulls, −4·F_g0/δg0 (open-loop unstable).

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

from hyperloop_env.physics.params import MU0, GuidanceParams, MagnetParams

TWO_OVER_PI = 2.0 / math.pi


@nb.njit(cache=True, fastmath=False, _nrt=False)
def smoothed_abs(z: float, delta0: float) -> float:
    """|z|_s whose derivative is (2/π)·arctan(z/δ0) [m]."""
    u = z / delta0
    return TWO_OVER_PI * (z * math.atan(u) - 0.5 * delta0 * math.log1p(u * u))


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def magnet_forces(
    current: float,
    s: float,
    z: float,
    kmag: float,
    a2: float,
    b2: float,
    delta0: float,
    sigma: float,
) -> tuple[float, float]:
    """(F_y, F_z) [N] of one levitation magnet for current [A], gap excursion s [m], lateral
    offset z [m]; ``sigma`` +1 repelling (destabilising edge force), −1 attracting."""
    u = z / delta0
    return magnet_forces_from(
        current, s, z, math.atan(u), math.log1p(u * u), kmag, a2, b2, delta0, sigma
    )


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def magnet_forces_from(
    current: float,
    s: float,
    z: float,
    atan_u: float,
    log1p_u2: float,
    kmag: float,
    a2: float,
    b2: float,
    delta0: float,
    sigma: float,
) -> tuple[float, float]:
    """:func:`magnet_forces` given ``atan_u`` = arctan(z/δ0) and ``log1p_u2`` =
    ln(1 + (z/δ0)²) (the integrator evaluates those for all units first)."""
    delta = delta0 + s
    if delta < 0.1 * delta0:
        delta = 0.1 * delta0
    at = atan_u  # once for |z|_s and the edge force (smoothed_abs's arithmetic)
    overlap = b2 - TWO_OVER_PI * (z * at - 0.5 * delta0 * log1p_u2)
    if overlap < 0.05 * b2:
        overlap = 0.05 * b2
    ki = kmag * current * current
    fy = ki * a2 * overlap / (delta * delta)
    fz = sigma * ki * a2 * TWO_OVER_PI * at / delta
    return fy, fz


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def guidance_force(
    bias: float, d_i: float, z: float, kmag: float, area: float, gap0: float, sigma: float
) -> float:
    """Net lateral force F_z [N] of one guidance pair on its unit for the differential
    current ``d_i`` [A] around ``bias`` [A] at lateral offset ``z`` [m] (gaps floored at
    0.1·δg0, which only happens after contact)."""
    dl = gap0 + z
    dr = gap0 - z
    floor = 0.1 * gap0
    if dl < floor:
        dl = floor
    if dr < floor:
        dr = floor
    il = bias + d_i
    ir = bias - d_i
    return sigma * kmag * area * (il * il / (dl * dl) - ir * ir / (dr * dr))


def pair_force_factor(z: float, gap0: float) -> float:
    """[(δg0/(δg0 − z))² − (δg0/(δg0 + z))²]: the repelling pair's restoring force at
    offset z in units of one magnet's bias force F_g0 [-]."""
    return (gap0 / (gap0 - z)) ** 2 - (gap0 / (gap0 + z)) ** 2


def edge_force_N(magnet: MagnetParams, force_N: float, z: float) -> float:
    """|F_z| of a levitation magnet carrying ``force_N`` at the nominal gap, offset z [N]:
    F0·(δ0/b2)·(2/π)·arctan(z/δ0) (the edge-force law at s = 0, I = I0)."""
    return (
        force_N
        * magnet.nominal_gap_m
        / magnet.pole_width_m
        * TWO_OVER_PI
        * math.atan(z / magnet.nominal_gap_m)
    )


def guidance_bias_current_A(
    guidance: GuidanceParams, magnet: MagnetParams, gravity_m_s2: float, n_units: int
) -> float:
    """I_g0 by the design rule of :class:`GuidanceParams` (or its ``bias_current_A``) [A]."""
    if guidance.bias_current_A is not None:
        return float(guidance.bias_current_A)
    z_d = guidance.design_offset_fraction * guidance.clearance_m
    f0 = guidance.design_mass_kg * gravity_m_s2 / n_units
    demand = guidance.design_mass_kg * guidance.design_lateral_acceleration_m_s2 / n_units
    f_g0 = (demand + edge_force_N(magnet, f0, z_d)) / pair_force_factor(z_d, guidance.nominal_gap_m)
    k_g = MU0 * guidance.turns**2 / 4.0
    area = magnet.pole_length_m * guidance.pole_height_m
    return guidance.nominal_gap_m * math.sqrt(f_g0 / (k_g * area))


def nominal_current_A(magnet: MagnetParams, force_N: float) -> float:
    """Current holding ``force_N`` at the nominal gap with no lateral offset:
    I0 = δ0·√(F/(K·A0)), K = μ0N²/4 (inverse of eq. 3–5) [A]."""
    kmag = MU0 * magnet.turns**2 / 4.0
    return magnet.nominal_gap_m * math.sqrt(force_N / (kmag * magnet.pole_area_m2))


def magnetic_stiffness_N_per_m(magnet: MagnetParams, force_N: float) -> float:
    """|∂F_y/∂δ| = 2F/δ0 at constant current [N/m]: restoring for the repelling
    orientation, destabilising for the attracting one."""
    return 2.0 * force_N / magnet.nominal_gap_m
