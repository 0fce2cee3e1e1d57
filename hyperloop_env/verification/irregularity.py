"""Variance of the generated guideway irregularity profiles against the band integral of the
spectrum written out again (:func:`hyperloop_env.verification.reference.german_track_psd`).
"""

from __future__ import annotations

import math

import numpy as np

from hyperloop_env.physics import irregularity as irr_mod
from hyperloop_env.physics.params import IRREGULARITY_CLASSES, IrregularityParams, ModelParams
from hyperloop_env.verification.common import CaseResult, compare
from hyperloop_env.verification.reference import german_track_psd


def psd_band_integral(params: IrregularityParams, lateral: bool) -> float:
    """∫ S(Ω) dΩ over the band by adaptive quadrature (in log Ω) of the spectrum written
    out again (:func:`reference.german_track_psd`, class amplitude and
    scale from :data:`IRREGULARITY_CLASSES`), independent of ``irregularity.psd`` and
    ``band_variance``."""
    from scipy.integrate import quad

    a_v, a_a, scale = IRREGULARITY_CLASSES[params.spectrum]
    amp = (a_a if lateral else a_v) * scale
    lo = math.log(2 * math.pi / params.max_wavelength_m)
    hi = math.log(2 * math.pi / params.min_wavelength_m)

    def integrand(u: float) -> float:
        om = math.exp(u)
        return german_track_psd(om, amp, params.omega_c, params.omega_r) * om

    val, _ = quad(integrand, lo, hi, epsabs=0.0, epsrel=1e-10, limit=200)
    return float(val)


def irregularity_variance(
    lateral: bool, params: IrregularityParams | None = None, seeds: tuple[int, ...] = (0, 1, 2)
) -> CaseResult:
    ip = params if params is not None else IrregularityParams()
    length = ModelParams().simulation.track_length_m
    rows = (irr_mod.ROW_LATERAL,) if lateral else (irr_mod.ROW_LEFT, irr_mod.ROW_RIGHT)
    var = []
    for s in seeds:
        tab = irr_mod.generate(ip, length, np.random.default_rng(s))
        var.extend(float(np.var(tab[r])) for r in rows)
    computed = float(np.mean(var))
    ref = psd_band_integral(ip, lateral)
    plane = "lateral" if lateral else "vertical"
    n = irr_mod.grid_size(ip, length)
    return compare(
        f"irregularity_variance_{plane}",
        f"{plane} irregularity ('{ip.spectrum}'): sample variance over the full period "
        f"({n} x {ip.grid_step_m:g} m), mean of {len(var)} profiles, vs quad of the PSD over "
        f"[{ip.min_wavelength_m:g}, {ip.max_wavelength_m:g}] m wavelengths [m^2]",
        computed,
        ref,
        2e-2,
        info={
            "band_variance_closed_form": irr_mod.band_variance(ip, lateral),
            "rms_m": math.sqrt(computed),
            "seed_spread_rel": float((max(var) - min(var)) / computed),
        },
    )
