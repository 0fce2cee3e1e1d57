"""Stochastic guideway irregularity from a one-sided PSD (spectral representation).

German high-speed track spectra (vertical A_v, lateral alignment A_a)::

    S(Ω) = c·A·Ωc² / ((Ω² + Ωr²)(Ω² + Ωc²))    [m²/(rad/m)],  Ωc = 0.8246, Ωr = 0.0206 rad/m

with c the class's PSD scale (:data:`~hyperloop_env.physics.params.IRREGULARITY_CLASSES`).
A profile is r(x) = Σ_k √(2·S(Ω_k)·ΔΩ)·cos(Ω_k·x + φ_k) with φ_k uniform on [0, 2π)
from the run's seed, Ω_k = k·ΔΩ inside [2π/λ_max, 2π/λ_min], evaluated on a grid of step
Δx by one inverse real FFT (so the profile is periodic with period n·Δx ≥ the track
length). Over one period its variance is exactly Σ_k S(Ω_k)·ΔΩ ≈ ∫ S dΩ over the band.

Three profiles are drawn per run: vertical under the left magnets, vertical under the
right magnets, and the lateral alignment shared by both sides. Front and rear units see
the same profile d1/v apart.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from hyperloop_env.physics.params import IRREGULARITY_CLASSES, IrregularityParams

ROW_LEFT = 0
ROW_RIGHT = 1
ROW_LATERAL = 2


def psd(params: IrregularityParams, omega: np.ndarray, lateral: bool = False) -> np.ndarray:
    """One-sided PSD S(Ω) [m²/(rad/m)] of the class at wavenumbers Ω [rad/m]."""
    a_v, a_a, scale = IRREGULARITY_CLASSES[params.spectrum]
    a = a_a if lateral else a_v
    om = np.asarray(omega, dtype=float)
    wc, wr = params.omega_c, params.omega_r
    return scale * a * wc**2 / ((om**2 + wr**2) * (om**2 + wc**2))


def band_variance(params: IrregularityParams, lateral: bool = False) -> float:
    """∫ S(Ω) dΩ over the generated band [m²], in closed form (partial fractions)."""
    a_v, a_a, scale = IRREGULARITY_CLASSES[params.spectrum]
    a = (a_a if lateral else a_v) * scale
    wc, wr = params.omega_c, params.omega_r
    lo = 2 * math.pi / params.max_wavelength_m
    hi = 2 * math.pi / params.min_wavelength_m

    def prim(w: float) -> float:  # ∫ Ωc²/((Ω²+Ωr²)(Ω²+Ωc²)) dΩ
        return wc**2 / (wc**2 - wr**2) * (math.atan(w / wr) / wr - math.atan(w / wc) / wc)

    return a * (prim(hi) - prim(lo))


def grid_size(params: IrregularityParams, length_m: float) -> int:
    """Power of two n with n·Δx ≥ max(length, 2·λ_max)."""
    need = max(length_m, 2.0 * params.max_wavelength_m) / params.grid_step_m
    return int(2 ** math.ceil(math.log2(max(need, 16.0))))


def generate(params: IrregularityParams, length_m: float, rng: np.random.Generator) -> np.ndarray:
    """Profiles on the grid, shape (3, n) [m]: rows left vertical, right vertical, lateral."""
    n = grid_size(params, length_m)
    dx = params.grid_step_m
    out = np.zeros((3, n))
    if IRREGULARITY_CLASSES[params.spectrum][2] == 0.0:
        return out
    d_omega = 2 * math.pi / (n * dx)
    k = np.arange(n // 2 + 1)
    omega = k * d_omega
    band = (omega >= 2 * math.pi / params.max_wavelength_m) & (
        omega <= 2 * math.pi / params.min_wavelength_m
    )
    band[0] = False
    band[-1] = False
    for row, lateral in ((ROW_LEFT, False), (ROW_RIGHT, False), (ROW_LATERAL, True)):
        amp = np.zeros(n // 2 + 1)
        amp[band] = np.sqrt(2.0 * psd(params, omega[band], lateral) * d_omega)
        phase = rng.uniform(0.0, 2 * math.pi, size=n // 2 + 1)
        coeff = amp * np.exp(1j * phase)
        out[row] = np.fft.irfft(coeff, n) * (n / 2.0)
    return out


@nb.njit(cache=True)
def sample(table: np.ndarray, row: int, x: float, dx: float) -> float:
    """Linear interpolation of a periodic profile row at position x [m]."""
    n = table.shape[1]
    u = x / dx
    fi = math.floor(u)
    f = u - fi
    i0 = int(fi) % n
    i1 = (i0 + 1) % n
    return (1.0 - f) * table[row, i0] + f * table[row, i1]
