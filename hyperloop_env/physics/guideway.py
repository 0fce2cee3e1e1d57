"""Modal guideway: simply supported Euler–Bernoulli spans (paper eq. 11, 12, 15, 16).

Per span of length L, w(x, t) = Σ_k q_k(t)·φ_k(x), φ_k = √2·sin(kπx/L), and

    ρA·L·(q̈_k + 2ζ ω_k q̇_k + ω_k² q_k) = Q_k,   ω_k = (kπ/L)²·√(EI/ρA)   (eq. 15)

A magnet force F spread uniformly over the magnet length La = a2 (eq. 12) gives the
generalised force Q_k = −F·W_k with the footprint weight

    W_k(x_a) = (1/La)·∫_footprint∩span φ_k dx
             = √2·(cos(kπξ1/L) − cos(kπξ2/L))/(kπ La/L),   ξ1,2 = footprint ends in the span,

and by reciprocity the deflection the magnet sees is the footprint mean Σ_k q_k·W_k.
The cosines cos(kθ) come from the Chebyshev recurrence cos((k+1)θ) = 2cosθ·cos(kθ) −
cos((k−1)θ): two transcendental calls per unit and span whatever the number of modes.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

SQRT2 = math.sqrt(2.0)


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def footprint_angles(
    x_center: float, half_len: float, span_start: float, span_len: float
) -> tuple[bool, float, float]:
    """(touches the span, θ1, θ2): the footprint ends in the span as angles π·ξ/L."""
    xi1 = x_center - half_len - span_start
    xi2 = x_center + half_len - span_start
    if xi1 < 0.0:
        xi1 = 0.0
    if xi2 > span_len:
        xi2 = span_len
    if xi2 <= xi1:
        return False, 0.0, 0.0
    return True, math.pi * xi1 / span_len, math.pi * xi2 / span_len


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def footprint_fill(
    c1: float,
    c2: float,
    half_len: float,
    span_len: float,
    out: np.ndarray,
    row: int,
    offset: int,
    n: int,
) -> None:
    """out[row, offset + k] = W_{k+1}, k < n, from c1 = cos θ1 and c2 = cos θ2 (Chebyshev
    recurrence)."""
    a_prev, a_cur = 1.0, c1  # cos(0·θ1), cos(1·θ1)
    b_prev, b_cur = 1.0, c2
    scale = SQRT2 * span_len / (math.pi * 2.0 * half_len)
    for k in range(n):
        out[row, offset + k] = scale * (a_cur - b_cur) / (k + 1)
        a_next = 2.0 * c1 * a_cur - a_prev
        b_next = 2.0 * c2 * b_cur - b_prev
        a_prev, a_cur = a_cur, a_next
        b_prev, b_cur = b_cur, b_next


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def footprint_weights_into(
    x_center: float,
    half_len: float,
    span_start: float,
    span_len: float,
    out: np.ndarray,
    row: int,
    offset: int,
    n: int,
) -> bool:
    """Fill out[row, offset + k] = W_{k+1}, k < n, for a load centred at x_center; False if
    it misses the span (the weights are then 0): :func:`footprint_angles`, two cosines,
    :func:`footprint_fill`."""
    hit, th1, th2 = footprint_angles(x_center, half_len, span_start, span_len)
    if not hit:
        for k in range(n):
            out[row, offset + k] = 0.0
        return False
    footprint_fill(math.cos(th1), math.cos(th2), half_len, span_len, out, row, offset, n)
    return True


@nb.njit(cache=True, error_model="numpy")
def footprint_weights(
    x_center: float, half_len: float, span_start: float, span_len: float, out: np.ndarray
) -> bool:
    """Fill out[k] = W_{k+1} for a load centred at x_center; False if it misses the span."""
    n = out.shape[0]
    tmp = np.empty((1, n))
    hit = footprint_weights_into(x_center, half_len, span_start, span_len, tmp, 0, 0, n)
    for k in range(n):
        out[k] = tmp[0, k]
    return hit


def mode_shape(x: np.ndarray, k: int, span_len: float) -> np.ndarray:
    """φ_k(x) = √2·sin(kπx/L) (k from 1)."""
    return SQRT2 * np.sin(k * np.pi * np.asarray(x) / span_len)
