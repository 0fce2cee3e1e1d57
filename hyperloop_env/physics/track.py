"""Horizontal alignment: straight, clothoid transition, circular curve with cant.

Curvature and cant grow linearly over the transition (a clothoid), from ``x0`` to
``x0 + L_t``. In the track frame (banked by the cant θ) every mass m feels

    lateral load  m·a_lat, a_lat = v²κ(x)·cos θ(x) − g·sin θ(x)   [m/s², +z = outward]
    vertical load m·g_eff, g_eff = g·cos θ(x) + v²κ(x)·sin θ(x)   [m/s², along −y]

(quasi-static curve loading; the track frame's rotation rate vκ is slow and its Coriolis
terms on the small relative motions are neglected).
"""

from __future__ import annotations

import math

import numba as nb


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def ramp(x: float, x0: float, length: float) -> float:
    """0 before x0, 1 after x0 + length, linear in between."""
    u = (x - x0) / length
    if u <= 0.0:
        return 0.0
    if u >= 1.0:
        return 1.0
    return u


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def curve_loads(
    x: float, v: float, kappa: float, cant: float, x0: float, length: float, g: float
) -> tuple[float, float, float]:
    """(κ(x) [1/m], a_lat [m/s²], g_eff [m/s²]) at position x."""
    r = ramp(x, x0, length)
    k = kappa * r
    th = cant * r
    if th == 0.0:  # straight and level: cos 0 = 1, sin ±0 = ±0 exactly, without libm
        c = 1.0
        s = th
    else:
        c = math.cos(th)
        s = math.sin(th)
    return k, v * v * k * c - g * s, g * c + v * v * k * s
