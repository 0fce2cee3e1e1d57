"""Stochastic guideway irregularity from a one-sided PSD (spectral representation).

German high-speed track spectra (vertical A_v, lateral alignment A_a)::

    S(Ω) = c·A·Ωc² / ((Ω² + Ωr²)(Ω² + Ωc²))    [m²/(rad/m)],  Ωc = 0.8246, Ωr = 0.0206 rad/m

with c the class's PSD scale (:data:`~hyperloop_env.physics.params.IRREGULARITY_CLASSES`)
times ``IrregularityParams.amplitude²`` (the roughness severity).
A profile is r(x) = Σ_k √(2·S_k)·cos(Ω_k·x + φ_k) with φ_k uniform on [0, 2π) from the
run's seed, Ω_k = k·ΔΩ, and S_k = ∫ S dΩ over bin k (width ΔΩ, clipped to the band
[2π/λ_max, 2π/λ_min]; ≈ S(Ω_k)·ΔΩ), evaluated on a grid of step Δx by one inverse real FFT
(so the profile is periodic with period n·Δx ≥ the track length). Over one period its
variance is exactly Σ_k S_k = ∫ S dΩ over the band.

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
N_ROWS = 3


def psd(params: IrregularityParams, omega: np.ndarray, lateral: bool = False) -> np.ndarray:
    """One-sided PSD S(Ω) [m²/(rad/m)] of the class at wavenumbers Ω [rad/m]."""
    a_v, a_a, scale = IRREGULARITY_CLASSES[params.spectrum]
    a = a_a if lateral else a_v
    om = np.asarray(omega, dtype=float)
    wc, wr = params.omega_c, params.omega_r
    return scale * a * params.amplitude**2 * wc**2 / ((om**2 + wr**2) * (om**2 + wc**2))


def psd_integral(
    params: IrregularityParams, lo: np.ndarray | float, hi: np.ndarray | float, lateral: bool
) -> np.ndarray:
    """∫_lo^hi S(Ω) dΩ [m²] in closed form (partial fractions), elementwise."""
    a_v, a_a, scale = IRREGULARITY_CLASSES[params.spectrum]
    a = (a_a if lateral else a_v) * scale * params.amplitude**2
    wc, wr = params.omega_c, params.omega_r

    def prim(w: np.ndarray | float) -> np.ndarray:  # ∫ Ωc²/((Ω²+Ωr²)(Ω²+Ωc²)) dΩ
        return wc**2 / (wc**2 - wr**2) * (np.arctan(w / wr) / wr - np.arctan(w / wc) / wc)

    return a * (prim(np.asarray(hi, dtype=float)) - prim(np.asarray(lo, dtype=float)))


def band_variance(params: IrregularityParams, lateral: bool = False) -> float:
    """∫ S(Ω) dΩ over the generated band [2π/λ_max, 2π/λ_min] [m²]."""
    lo = 2 * math.pi / params.max_wavelength_m
    hi = 2 * math.pi / params.min_wavelength_m
    return float(psd_integral(params, lo, hi, lateral))


def grid_size(params: IrregularityParams, length_m: float) -> int:
    """Power of two n with n·Δx ≥ max(length, 2·λ_max)."""
    need = max(length_m, 2.0 * params.max_wavelength_m) / params.grid_step_m
    return int(2 ** math.ceil(math.log2(max(need, 16.0))))


def generate(params: IrregularityParams, length_m: float, rng: np.random.Generator) -> np.ndarray:
    """Profiles on the grid, shape (3, n) [m]: rows left vertical, right vertical, lateral."""
    n = grid_size(params, length_m)
    dx = params.grid_step_m
    out = np.zeros((N_ROWS, n))
    if IRREGULARITY_CLASSES[params.spectrum][2] == 0.0 or params.amplitude == 0.0:
        return out
    d_omega = 2 * math.pi / (n * dx)
    k = np.arange(n // 2 + 1)
    # bin k covers [(k − ½)ΔΩ, (k + ½)ΔΩ] ∩ band; its amplitude carries the PSD integral over
    # the bin, so the profile's variance over one period is exactly ∫ S dΩ over the band.
    band_lo = 2 * math.pi / params.max_wavelength_m
    band_hi = 2 * math.pi / params.min_wavelength_m
    lo = np.clip((k - 0.5) * d_omega, band_lo, band_hi)
    hi = np.clip((k + 0.5) * d_omega, band_lo, band_hi)
    lo[0] = hi[0] = 0.0
    lo[-1] = hi[-1] = 0.0  # keep the Nyquist bin empty (band_hi is far below it)
    for row, lateral in ((ROW_LEFT, False), (ROW_RIGHT, False), (ROW_LATERAL, True)):
        amp = np.sqrt(2.0 * np.maximum(psd_integral(params, lo, hi, lateral), 0.0))
        phase = rng.uniform(0.0, 2 * math.pi, size=n // 2 + 1)
        coeff = amp * np.exp(1j * phase)
        out[row] = np.fft.irfft(coeff, n) * (n / 2.0)
    return out


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def sample(table: np.ndarray, row: int, x: float, dx: float) -> float:
    """Linear interpolation of a periodic profile row at position x [m]."""
    n = table.shape[1]
    u = x / dx
    fi = math.floor(u)
    f = u - fi
    i0 = int(fi)
    if i0 < 0 or i0 >= n:  # wrap (an integer division, only off the first period)
        i0 = i0 % n
    i1 = i0 + 1
    if i1 == n:
        i1 = 0
    return (1.0 - f) * table[row, i0] + f * table[row, i1]
