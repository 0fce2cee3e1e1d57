"""Vehicle and magnet verification cases driven through the production code path.

The computed side is always the production simulator: its one-control-step map (RK4,
``Simulator.step`` with the state set in ``sim.y``), its records, or the compiled force
law :func:`~hyperloop_env.physics.magnets.magnet_forces`. The references come from
:mod:`hyperloop_env.verification.reference` (hand-assembled matrices, closed forms,
scipy), never from ``linearize.py`` or the parameter helpers.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np

from hyperloop_env.physics.layout import (
    A_I,
    A_SPAN0,
    A_SPAN1,
    M_ALAT,
    M_FY,
    M_GAP,
    M_LAT,
    NQ,
    P_A2,
    P_AG,
    P_B2,
    P_DELTA0,
    P_DELTAG0,
    P_I0,
    P_IG0,
    P_KMAG,
    P_KMAGG,
    Q_UZ,
)
from hyperloop_env.physics.magnets import guidance_force, magnet_forces
from hyperloop_env.physics.model import pack
from hyperloop_env.physics.params import (
    GuidewayParams,
    IrregularityParams,
    MagnetParams,
    ModelParams,
    OperatingCondition,
    SimulationParams,
)
from hyperloop_env.physics.simulator import Simulator
from hyperloop_env.physics.units import N_UNITS
from hyperloop_env.physics.vehicle import U_FG, rhs
from hyperloop_env.verification.common import CaseResult, compare, threshold
from hyperloop_env.verification.reference import (
    CAPSULE_MASS_PAPER_KG,
    FRAME_MASS_PAPER_KG,
    GRAVITY_PAPER_M_S2,
    guidance_stiffness_reference,
    nominal_current_paper_A,
    quasi_static_lateral_offset,
    vehicle_matrices,
    vehicle_modes,
)

N_VEHICLE = 2 * NQ  # 13 coordinates and their rates
VEHICLE_MODE_NAMES = ("heave", "pitch", "roll", "lateral", "yaw")
MODE_TOL = 1e-6
"""Relative tolerance on modal frequencies, damping ratios and eigenvalues: the RK4 map at
0.25 ms reproduces exp(λ·dt) to ~(|λ|h)⁴/120 < 1e-7 for |λ| < 200/s, and the central
differences (1e-7 perturbations of a state at equilibrium) add ~1e-9."""


def rigid_smooth_params(orientation: str = "repelling", **sections: Any) -> ModelParams:
    """Default vehicle on a rigid, straight, smooth guideway with an ideal current source."""
    base = {
        "magnet": MagnetParams(orientation=orientation, coil_time_constant_s=0.0),
        "guideway": GuidewayParams(rigid=True),
        "irregularity": IrregularityParams(spectrum="none"),
    }
    base.update(sections)
    return ModelParams(**base)  # type: ignore[arg-type]


class StepMap:
    """The Simulator's one-control-step map on the 26 vehicle states, x ↦ Φ(x), at constant
    current I0 (production RK4: ``sim.y`` set, ``sim.step`` called, ``sim.y`` read), always
    from the state, time and span ring of ``reset``."""

    def __init__(self, params: ModelParams) -> None:
        self.sim = Simulator(params)
        self.sim.reset(seed=0)
        self.y0 = self.sim.y.copy()
        self.aux0 = self.sim.aux.copy()
        self.currents = [self.sim.nominal_current_A] * len(self.sim.command_names)
        self.dt = params.simulation.control_dt_s

    def __call__(self, x: np.ndarray) -> np.ndarray:
        sim = self.sim
        sim.y[:] = self.y0
        sim.y[:N_VEHICLE] = x
        sim.aux[:] = self.aux0
        sim.spans[:] = self.aux0[A_SPAN0 : A_SPAN1 + 1].astype(np.int64)
        sim.step(self.currents)
        return sim.y[:N_VEHICLE].copy()

    def jacobian(self, x: np.ndarray, eps: float = 1e-7) -> np.ndarray:
        """Central-difference Jacobian ∂Φ/∂x (26 × 26)."""
        J = np.zeros((N_VEHICLE, N_VEHICLE))
        for j in range(N_VEHICLE):
            e = np.zeros(N_VEHICLE)
            e[j] = eps
            J[:, j] = (self(x + e) - self(x - e)) / (2.0 * eps)
        return J


@lru_cache(maxsize=4)
def step_map_eigenvalues(orientation: str) -> np.ndarray:
    """Continuous-time eigenvalues λ = log(μ)/dt [1/s] of the step map's Jacobian at the
    reset state (the equilibrium), μ its eigenvalues."""
    smap = StepMap(rigid_smooth_params(orientation))
    J = smap.jacobian(smap.y0[:N_VEHICLE].copy())
    mu = np.linalg.eigvals(J).astype(complex)
    return np.log(mu) / smap.dt


@lru_cache(maxsize=4)
def reference_eigen(orientation: str) -> tuple[np.ndarray, dict[str, complex]]:
    """Eigenvalues and named capsule modes of the hand-assembled 13-DOF vehicle."""
    p = rigid_smooth_params(orientation)
    mats = vehicle_matrices(p.vehicle, p.magnet, p.simulation.gravity_m_s2, p.guidance)
    return vehicle_modes(mats)


def _matched(computed: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``computed`` reordered to pair with ``reference`` (min-cost assignment on |Δλ|)."""
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(reference[:, None] - computed[None, :])
    rows, cols = linear_sum_assignment(cost)
    out = np.empty_like(reference)
    out[rows] = computed[cols]
    return out


def _freq_zeta(lam: complex) -> tuple[float, float]:
    """(natural frequency |λ|/2π [Hz], damping ratio −Re λ/|λ|)."""
    return abs(lam) / (2.0 * math.pi), -lam.real / abs(lam)


def vehicle_mode(name: str, quantity: str) -> CaseResult:
    """Natural frequency (``quantity="hz"``) or damping ratio (``"zeta"``) of the named
    capsule mode (repelling magnet, constant I0): eigenvalue of the production step map
    (log μ/dt) nearest the mode of the hand-assembled 13-DOF reference (scipy.linalg.eig
    of the first-order form; see :func:`reference.vehicle_matrices`)."""
    if name not in VEHICLE_MODE_NAMES or quantity not in ("hz", "zeta"):
        raise ValueError(f"unknown vehicle mode case {name!r}/{quantity!r}")
    lam_c = step_map_eigenvalues("repelling")
    _, named = reference_eigen("repelling")
    ref = named[name]
    got = complex(lam_c[np.argmin(np.abs(lam_c - ref))])
    f_c, z_c = _freq_zeta(got)
    f_r, z_r = _freq_zeta(ref)
    computed, reference = (f_c, f_r) if quantity == "hz" else (z_c, z_r)
    what = "natural frequency |lambda|/2pi [Hz]" if quantity == "hz" else "damping ratio"
    return compare(
        f"vehicle_mode_{name}_{quantity}",
        f"{name} mode of the vehicle (repelling, I0, rigid straight smooth guideway): "
        f"{what} from the eigenvalues log(mu)/dt of the Jacobian of the Simulator's "
        "one-step map vs the hand-assembled 13-DOF M, C, K (scipy eig)",
        computed,
        reference,
        MODE_TOL,
        info={
            "computed_eigenvalue": [got.real, got.imag],
            "reference_eigenvalue": [ref.real, ref.imag],
            "damped_frequency_hz": got.imag / (2.0 * math.pi),
        },
    )


def vehicle_eigenvalues(orientation: str) -> CaseResult:
    """All 26 eigenvalues of the step map (log μ/dt) against the 13-DOF reference,
    paired by a min-cost assignment: max |Δλ|/|λ| (covers the unit/frame modes, the
    overdamped pairs and, for ``attracting``, the unstable poles)."""
    lam_c = step_map_eigenvalues(orientation)
    lam_r, _ = reference_eigen(orientation)
    matched = _matched(lam_c, lam_r)
    rel = np.abs(matched - lam_r) / np.abs(lam_r)
    worst = float(rel.max())
    order = np.argsort(np.abs(lam_r))
    table = [
        [float(lam_r[i].real), float(lam_r[i].imag), float(matched[i].real), float(rel[i])]
        for i in order
        if lam_r[i].imag >= 0
    ]
    return threshold(
        f"vehicle_eigenvalues_{orientation}",
        f"{orientation} magnet, I0: all 26 eigenvalues log(mu)/dt of the Simulator's one-step "
        "map Jacobian vs the hand-assembled 13-DOF vehicle (assignment by |d lambda|): "
        "max relative error",
        worst,
        MODE_TOL,
        worst < MODE_TOL,
        info={"reference_re_im__computed_re__rel_error": table},
    )


def vehicle_unstable_pole_attracting() -> CaseResult:
    """Largest real eigenvalue of the attracting (EMS) vehicle at constant current: step
    map vs the 13-DOF reference; the rigid-body estimate √(k_m/m_eff) = √(2F0/(δ0·m_eff)),
    m_eff = (m_v + m_m)/4 (i.e. √(2g/δ0)), is reported beside it."""
    lam_c = step_map_eigenvalues("attracting")
    lam_r, _ = reference_eigen("attracting")
    got = float(lam_c.real[np.abs(lam_c.imag) < 1e-9].max())
    ref = float(lam_r.real[np.abs(lam_r.imag) < 1e-9].max())
    p = rigid_smooth_params("attracting")
    m_eff = (p.vehicle.capsule_mass_kg + p.vehicle.frame_mass_kg) / 4.0
    f0 = m_eff * p.simulation.gravity_m_s2
    estimate = math.sqrt(2.0 * f0 / (p.magnet.nominal_gap_m * m_eff))
    return compare(
        "vehicle_unstable_pole_attracting",
        "attracting magnet, I0: largest real eigenvalue of the Simulator's one-step map "
        "(log(mu)/dt) vs the hand-assembled 13-DOF vehicle [1/s]",
        got,
        ref,
        MODE_TOL,
        info={
            "rigid_body_estimate_sqrt_2F0_over_delta0_meff": estimate,
            "ratio_to_estimate": got / estimate,
            "n_unstable_reference": int((lam_r.real > 0).sum()),
            "n_unstable_computed": int((lam_c.real > 0).sum()),
        },
        extra_ok=bool((lam_c.real > 0).sum() == (lam_r.real > 0).sum()),
    )


# ---------------------------------------------------------------------------------------
# total weight and nominal current
# ---------------------------------------------------------------------------------------


def weight_check(max_newton: int = 5) -> CaseResult:
    """At equilibrium the four magnets carry the published weight.

    The equilibrium is the fixed point of the production step map at I0 (rigid, straight,
    smooth), found by Newton iteration on x = Φ(x) from the reset state (finite-difference
    Jacobian). Computed: Σ M_FY of the record after one step from it. Reference:
    (15 000 + 22 000 kg)·9.81 m/s² (paper Table 1). Also I0 (``Simulator.nominal_current_A``)
    must equal δ0·√(4F0/(μ0 N² A0)), F0 = the published weight / 4 (paper eq. 3–5 at δ0).
    Tolerance 1e-9 on both."""
    p = rigid_smooth_params("repelling")
    smap = StepMap(p)
    x = smap.y0[:N_VEHICLE].copy()
    residuals = []
    for _ in range(max_newton):
        r = smap(x) - x
        residuals.append(float(np.abs(r).max()))
        if residuals[-1] < 1e-15:
            break
        J = smap.jacobian(x)
        x = x - np.linalg.solve(J - np.eye(N_VEHICLE), r)
    smap(x)
    rec = smap.sim.meas
    computed = float(rec[M_FY : M_FY + N_UNITS].sum())
    weight = (CAPSULE_MASS_PAPER_KG + FRAME_MASS_PAPER_KG) * GRAVITY_PAPER_M_S2
    i0_ref = nominal_current_paper_A(p.magnet, weight / 4.0)
    i0 = smap.sim.nominal_current_A
    i0_rel = abs(i0 - i0_ref) / i0_ref
    tol = 1e-9
    return compare(
        "weight_check",
        "equilibrium (fixed point of the Simulator's step map at I0, rigid straight smooth): "
        "sum of the 4 magnet forces (M_FY) vs (15000 + 22000 kg) 9.81 m/s^2 [N]; and I0 vs "
        "delta0 sqrt(4 F0/(mu0 N^2 A0))",
        computed,
        weight,
        tol,
        info={
            "nominal_current_A": i0,
            "nominal_current_reference_A": i0_ref,
            "nominal_current_rel_error": i0_rel,
            "equilibrium_gap_excursion_m": rec[M_GAP : M_GAP + 4],
            "newton_residuals": residuals,
        },
        extra_ok=i0_rel <= tol,
    )


# ---------------------------------------------------------------------------------------
# quasi-static lateral offset in a steady curve
# ---------------------------------------------------------------------------------------

CURVE_CASES = {
    "curve_lateral_offset_R200km": (1000.0, 200e3, 0.0),
    "curve_lateral_offset_R200km_cant1deg": (1000.0, 200e3, 1.0),
    "curve_lateral_offset_2000kmh_R200km": (2000.0, 200e3, 0.0),
}


def curve_lateral_offset(
    name: str, duration_s: float = 12.0, window_s: float = 2.0, transition_m: float = 300.0
) -> CaseResult:
    """Mean lateral offset of the units in a steady curve vs the static equilibrium.

    Simulator: default vehicle, repelling, constant I0, rigid guideway, no irregularity;
    the clothoid (``transition_m``) starts at x = 0, the run lasts ``duration_s`` and the
    four units' lateral offsets (record ``M_LAT``) are averaged over the last ``window_s``
    (the lateral modes, ≈1 Hz at ζ ≈ 0.2, have decayed). Reference:
    :func:`reference.quasi_static_lateral_offset` (edge force and guidance pair
    written from the force laws, gap change from the reduced overlap, brentq). Tolerance
    1e-3; the
    peak-to-peak of the mean offset over the window must be < 1 % of it."""
    speed_kmh, radius, cant = CURVE_CASES[name]
    v = speed_kmh / 3.6
    n = int(round(duration_s / 1e-3))
    p = rigid_smooth_params(
        "repelling",
        condition=OperatingCondition(
            speed_kmh=speed_kmh,
            curve_radius_m=radius,
            cant_deg=cant,
            transition_length_m=transition_m,
            curve_start_m=0.0,
        ),
        simulation=SimulationParams(track_length_m=v * duration_s + 100.0),
    )
    sim = Simulator(p)
    sim.reset(seed=0)
    rec = sim.run([sim.nominal_current_A] * 4, n)
    w = int(round(window_s / p.simulation.control_dt_s))
    lat = rec[-w:, M_LAT : M_LAT + 4]
    computed = float(lat.mean())
    eq = quasi_static_lateral_offset(
        p.vehicle, p.magnet, v, radius, math.radians(cant), p.simulation.gravity_m_s2
    )
    ptp = float(np.ptp(lat.mean(axis=1)))
    settled = ptp < 1e-2 * abs(eq.offset_m)
    return compare(
        name,
        f"steady curve {speed_kmh:g} km/h, R = {radius / 1e3:g} km, cant {cant:g} deg "
        f"(rigid, smooth, I0): mean unit lateral offset M_LAT over the last {window_s:g} s "
        f"of {duration_s:g} s vs the static lateral equilibrium of the units (edge force, "
        "guidance pair, gap change, brentq) [m]",
        computed,
        eq.offset_m,
        1e-3,
        info={
            "lateral_load_reference_m_s2": eq.lateral_load_m_s2,
            "lateral_load_record_m_s2": float(rec[-1, M_ALAT]),
            "unit_lateral_load_N": eq.unit_load_N,
            "gap_excursion_mean_m": float(rec[-w:, M_GAP : M_GAP + 4].mean()),
            "gap_excursion_reference_m": eq.gap_m - p.magnet.nominal_gap_m,
            "window_peak_to_peak_m": ptp,
            "spread_between_units_m": float(np.ptp(lat.mean(axis=0))),
        },
        extra_ok=settled,
    )


# ---------------------------------------------------------------------------------------
# guidance magnets
# ---------------------------------------------------------------------------------------


def guidance_stiffness(orientation: str, dz: float = 1e-6) -> CaseResult:
    """Lateral stiffness of a guidance pair at bias, from the production right-hand side:
    the guidance force of unit FL in the rhs output (``U_FG``) with its lateral offset at
    ±dz (everything else at the reset state of a rigid, smooth, straight track), central
    difference −ΔF/Δz, vs 4·F_g0/δg0 (restoring, repelling) or −4·F_g0/δg0 (attracting)
    with F_g0 and the design-rule bias written out again (:mod:`.reference`). Tolerance
    1e-6."""
    p = rigid_smooth_params(orientation)
    sim = Simulator(p)
    sim.reset(seed=0)
    y0 = sim.y.copy()
    forces = []
    for sgn in (1.0, -1.0):
        y = y0.copy()
        y[Q_UZ] += sgn * dz
        dydt = np.zeros_like(y)
        cur = sim.aux[A_I : A_I + sim.n_commands].copy()
        rhs(0.0, y, sim.P, sim.irr, 0.0, cur, cur, sim.spans, dydt, sim.wts, sim.uo)
        forces.append(float(sim.uo[U_FG, 0]))
    computed = -(forces[0] - forces[1]) / (2.0 * dz)
    ref = guidance_stiffness_reference(p.guidance, p.magnet, p.simulation.gravity_m_s2)
    return compare(
        f"guidance_stiffness_{orientation}",
        f"{orientation} guidance pair at bias: -dF_g/dz of unit FL from the production rhs "
        "(central difference) vs +-4 F_g0/delta_g0 (F_g0 and the design-rule bias written "
        "out again) [N/m]",
        computed,
        ref,
        1e-6,
        info={
            "bias_current_A": float(sim.P[P_IG0]),
            "sign": "restoring" if computed > 0 else "destabilising",
        },
        extra_ok=bool(np.sign(computed) == np.sign(ref)),
    )


def guidance_pole_attracting() -> CaseResult:
    """Open-loop pole of the attracting guidance pairs: the units' lateral "twist" mode
    (FL and RL against FR and RR: no net force or yaw moment on the capsule, so it stands
    still) obeys m_u·z̈ + c_s·ż + (k_s + k_e − k_g)·z = 0 with m_u = m_m/4, k_s = K_z/4,
    c_s = c_z/4, k_e = (2/π)·F0/b2 (the edge force restores an attracting magnet) and
    k_g = 4·F_g0/δg0 (:mod:`.reference`): λ = (−c_s + √(c_s² + 4 m_u (k_g − k_e − k_s)))
    /(2 m_u). Computed: the eigenvalue of the Simulator's one-step map (log(μ)/dt) nearest
    to it. Tolerance 1e-6."""
    p = rigid_smooth_params("attracting")
    vp, mp = p.vehicle, p.magnet
    m_u = vp.frame_mass_kg / 4.0
    k_s = vp.secondary_stiffness_N_per_m / 4.0
    c_s = vp.secondary_damping_Ns_per_m / 4.0
    f0 = (vp.capsule_mass_kg + vp.frame_mass_kg) * p.simulation.gravity_m_s2 / 4.0
    k_e = 2.0 / math.pi * f0 / mp.pole_width_m
    k_g = -guidance_stiffness_reference(p.guidance, mp, p.simulation.gravity_m_s2)
    ref = (-c_s + math.sqrt(c_s**2 + 4.0 * m_u * (k_g - k_e - k_s))) / (2.0 * m_u)
    lam = step_map_eigenvalues("attracting")
    real = lam.real[np.abs(lam.imag) < 1e-9]
    got = float(real[np.argmin(np.abs(real - ref))])
    return compare(
        "guidance_pole_attracting",
        "attracting guidance pairs at bias: unstable pole of the units' lateral twist mode, "
        "Simulator step map (log(mu)/dt) vs the closed form of m_u z'' + c_s z' + "
        "(k_s + k_e - 4F_g0/delta_g0) z = 0 [1/s]",
        got,
        ref,
        MODE_TOL,
        info={"k_guidance_N_per_m": k_g, "k_edge_N_per_m": k_e, "k_secondary_N_per_m": k_s},
        extra_ok=got > 0,
    )


# ---------------------------------------------------------------------------------------
# path independence of the magnet force's work
# ---------------------------------------------------------------------------------------

WORK_LOOP_S_M = 2e-3
WORK_LOOP_Z_M = 6e-3


def magnet_work_loop(orientation: str) -> CaseResult:
    """Work of all magnet forces on the unit around a closed loop at constant currents.

    A force from an energy (a co-energy at constant current) does no work around a closed
    path. The loop is the rectangle gap excursion s: 0 → 2 mm, lateral offset z: 0 →
    6 mm (counter-clockwise in (s, z), inside the guidance clearance); the unit's
    displacement is dy = σ·ds (s = σ·(y − w − r), σ = +1 repelling, −1 attracting) and dz,
    so W = ∮ σ·F_y ds + F_z dz, with F_y from the compiled levitation law
    :func:`magnets.magnet_forces` at I0 and F_z the sum of its edge force and the guidance
    pair's :func:`magnets.guidance_force` at bias (constants from ``pack``), each edge by
    ``scipy.integrate.quad``. |W| relative to the work along the first edge must be
    < 1e-6."""
    from scipy.integrate import quad

    p = ModelParams(magnet=MagnetParams(orientation=orientation))
    P = pack(p)
    sigma = 1.0 if orientation == "repelling" else -1.0
    args = (float(P[P_KMAG]), float(P[P_A2]), float(P[P_B2]), float(P[P_DELTA0]), sigma)
    gargs = (float(P[P_KMAGG]), float(P[P_AG]), float(P[P_DELTAG0]), sigma)
    i0 = float(P[P_I0])
    ig0 = float(P[P_IG0])

    def fy(s: float, z: float) -> float:
        return magnet_forces(i0, s, z, *args)[0]

    def fz(s: float, z: float) -> float:
        return magnet_forces(i0, s, z, *args)[1] + guidance_force(ig0, 0.0, z, *gargs)

    s1, z1 = WORK_LOOP_S_M, WORK_LOOP_Z_M
    opts = {"epsabs": 0.0, "epsrel": 1e-13, "limit": 200}
    edges = [
        quad(lambda s: sigma * fy(s, 0.0), 0.0, s1, **opts)[0],  # z = 0, s ↑
        quad(lambda z: fz(s1, z), 0.0, z1, **opts)[0],  # s = s1, z ↑
        -quad(lambda s: sigma * fy(s, z1), 0.0, s1, **opts)[0],  # z = z1, s ↓
        -quad(lambda z: fz(0.0, z), 0.0, z1, **opts)[0],  # s = 0, z ↓
    ]
    work = float(sum(edges))
    rel = abs(work) / abs(edges[0])
    thr = 1e-6
    return threshold(
        f"magnet_work_loop_{orientation}",
        f"{orientation} magnets at I0 / I_g0: work of (F_y, F_z) of the levitation magnet and "
        "the guidance pair (compiled magnet_forces + guidance_force) on "
        f"the unit around the loop s 0->{s1 * 1e3:g} mm, z 0->{z1 * 1e3:g} mm (dy = sigma ds), "
        "quad per edge: |loop work| / |work along the first edge| (0 for a conservative "
        "force)",
        rel,
        thr,
        rel < thr,
        info={"loop_work_J": work, "edge_work_J": edges, "sigma": sigma},
    )


__all__ = [
    "CURVE_CASES",
    "guidance_pole_attracting",
    "guidance_stiffness",
    "VEHICLE_MODE_NAMES",
    "StepMap",
    "curve_lateral_offset",
    "magnet_work_loop",
    "step_map_eigenvalues",
    "vehicle_eigenvalues",
    "vehicle_mode",
    "vehicle_unstable_pole_attracting",
    "weight_check",
]
