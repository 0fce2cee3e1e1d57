"""Vehicle equilibrium and passive (in)stability at constant current: the right-hand side and
the records at rest on a rigid guideway, and the eigenvalues of :func:`linearize.linearize`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hyperloop_env.physics.layout import M_ACC_HEAVE, M_ACC_YAW, M_GAP, NQ, P_F0, P_G
from hyperloop_env.physics.linearize import linearize
from hyperloop_env.physics.model import pack
from hyperloop_env.physics.params import (
    GuidewayParams,
    IrregularityParams,
    MagnetParams,
    ModelParams,
)
from hyperloop_env.physics.simulator import Simulator
from hyperloop_env.verification.common import CaseResult, ConstantCurrentRhs, threshold

# ---------------------------------------------------------------------------------------
# equilibrium on a rigid guideway
# ---------------------------------------------------------------------------------------


def equilibrium_rigid(n_steps: int = 200) -> CaseResult:
    vals: dict[str, float] = {}
    for orientation in ("repelling", "attracting"):
        p = ModelParams(
            magnet=MagnetParams(orientation=orientation),
            guideway=GuidewayParams(rigid=True),
            irregularity=IrregularityParams(spectrum="none"),
        )
        sim = Simulator(p)
        sim.reset(seed=0)
        g = float(sim.P[P_G])
        i0 = sim.nominal_current_A
        f = ConstantCurrentRhs(sim.P, sim.irr, sim.spans.copy(), i0)
        d = f(0.0, sim.y.copy())
        vals[f"{orientation}_rhs_max_over_g"] = float(np.abs(d[: 2 * NQ]).max() / g)
        rec = sim.run([i0] * 4, n_steps)
        vals[f"{orientation}_record_acc_max_over_g"] = float(
            np.abs(rec[:, M_ACC_HEAVE : M_ACC_YAW + 1]).max() / g
        )
        vals[f"{orientation}_max_gap_m"] = float(np.abs(rec[:, M_GAP : M_GAP + 4]).max())
    worst = max(v for k, v in vals.items() if k.endswith("_over_g"))
    thr = 1e-9
    return threshold(
        "equilibrium_rigid",
        f"at rest on a rigid straight smooth guideway with I0: max |dy/dt| of the vehicle "
        f"states on the initial state and max |M_ACC_*| over {n_steps} control steps, "
        "relative to g, for both magnet orientations",
        worst,
        thr,
        worst < thr,
        info=vals,
    )


# ---------------------------------------------------------------------------------------
# passive stability
# ---------------------------------------------------------------------------------------


def passive_stability(orientation: str) -> CaseResult:
    p = ModelParams(magnet=MagnetParams(orientation=orientation))
    lin = linearize(p)
    ev = lin.eigenvalues()
    max_re = float(ev.real.max())
    P = pack(p)
    m_eff = p.vehicle.total_mass_kg / 4.0
    estimate = math.sqrt(2 * P[P_F0] / (p.magnet.nominal_gap_m * m_eff))
    info: dict[str, Any] = {
        "max_real_eigenvalue": max_re,
        "n_eigenvalues": int(ev.size),
        "slowest_decay_rate": float(-max_re),
    }
    if orientation == "repelling":
        # the least damped oscillatory mode: vehicle heave/pitch on the magnet springs
        osc = ev[ev.imag > 1e-6]
        lam0 = osc[np.argmax(osc.real)]
        info["least_damped_mode_hz"] = float(abs(lam0) / (2 * math.pi))
        info["least_damped_mode_damping_ratio"] = float(-lam0.real / abs(lam0))
        return threshold(
            "passive_stability_repelling",
            "repelling magnet, constant current I0: largest real part of the eigenvalues "
            "of the linearised vehicle (must be < 0)",
            max_re,
            0.0,
            max_re < 0.0,
            info=info,
        )
    real_pos = ev[(np.abs(ev.imag) < 1e-9 * np.abs(ev).max()) & (ev.real > 0)]
    lam = float(real_pos.real.max()) if real_pos.size else math.nan
    info.update(
        {
            "largest_positive_real_eigenvalue": lam,
            "rigid_body_estimate_sqrt_2F0_over_delta0_meff": estimate,
            "m_eff_kg": m_eff,
            "ratio_to_estimate": lam / estimate if real_pos.size else math.nan,
        }
    )
    return threshold(
        "passive_instability_attracting",
        "attracting magnet, constant current I0: largest positive real eigenvalue of the "
        "linearised vehicle (must be > 0)",
        lam if real_pos.size else max_re,
        0.0,
        bool(real_pos.size > 0),
        info=info,
    )
