"""Verification of the simulator against analytical and independent numerical references.

Run ``python -m hyperloop_env.verification`` (a table) or ``... --json`` (one JSON object
keyed by case name). The exit code is 1 if any case fails, except the cases listed in
:data:`KNOWN_FAILURES` (documented physics bugs, reported as XFAIL; one that starts to pass
is an XPASS and fails the run until its entry is removed). Every case is also a function
returning a :class:`CaseResult`; :func:`run_all` runs them all.

"Production path" below means the real :class:`~hyperloop_env.physics.model.Simulator`
(``reset``, ``step``, its state ``sim.y`` and records) or the compiled
:func:`vehicle.rhs` / :func:`magnets.magnet_forces`. References come from
:mod:`hyperloop_env.verification.reference`, which never calls the code under test nor
its helpers (``natural_frequency_hz``, ``total_mass_kg``, ``linearize``).

Cases (names are stable)
------------------------
``beam_frequency_mode_{1,2,3}``
    Free vibration of one span, integrated with the compiled :func:`vehicle.rhs` (the
    vehicle is on other spans, so the span is unloaded; its modal damping is set to 0 so
    the measured frequency is the natural one): frequency from the zero crossings of the
    midspan-mode coordinate vs an independent Euler–Bernoulli finite-element beam (60
    Hermite cubic elements, consistent mass, simply supported, ``scipy.linalg.eigh``,
    from EI, ρA, L) (1e-4). The lateral plane's eigenfrequencies are reported as info.
``static_midspan_deflection``
    Modal static solution ``q_k = Q_k/(ρAL·ω_k²)`` for a point load at midspan (modal loads
    from :func:`guideway.footprint_weights` with a 0.2 mm footprint, 51 modes) vs
    ``PL³/(48EI)`` (0.1 %). (Checks the modal series, not the simulator.)
``static_deflection_initial_state``
    Production path: ``Simulator.reset`` of the default vehicle on a flexible, smooth
    guideway (start position hard-coded, ``model.X_START_M`` = 10 m: both sets on span 0).
    Midspan deflection of span 0 from the state vs the simply supported influence function
    (Roark) integrated over the four footprints with ``quad``, each carrying the published
    weight/4 (0.2 %: the 6-mode truncation costs 6e-4); the state must also stay put over
    200 steps at 1e-9 km/h (an equilibrium of ``rhs``).
``static_midspan_slow_crossing``
    Production path: the constant-force vehicle (below) crosses span 1 at α = 0.005; max
    midspan deflection over P·L³/(48EI) vs 1 (tolerance 2α: the undamped excess is ~α).
``moving_force_daf_alpha_{0.25,0.5,0.75,1.0}``
    A constant force crossing one simply supported span at ``α = v/(2 f1 L)``; dynamic
    amplification (maximum midspan deflection over the crossing and 3 periods of f1 of
    free vibration after it, divided by ``PL³/(48EI)``) from a re-implementation of the
    project's modal equations (same form as in ``vehicle.rhs``, footprint weights for the
    load position, 6 modes, damping 0, RK4 at ``ω_max·h = 0.05``) vs Frýba's closed-form
    undamped modal series (101 modes, during and after the passage) (2 %).
``moving_force_daf_sim_alpha_{0.25,0.5,0.75,1.0}``
    Production path: the full Simulator reduced to a constant moving force (nominal gap
    100 m so F ∝ 1/δ² varies by ~1e-4, set spacing 1 mm, pole length 1 cm, ζ = 0, straight,
    smooth, flexible) crosses span 1, which starts at rest; max midspan deflection from
    ``sim.y`` over the crossing and the free vibration until the slot is reused, over
    P·L³/(48EI) with P from the ``M_FY`` records, vs Frýba's series for each set (its
    force share, its entry time) at the same instants; v from α with f1 in closed form
    (2 %).
``guideway_load_coupling``
    Production ``rhs``: Newton's third law. Different unit gaps, currents and offsets,
    random modal states, front footprints straddling a support: every modal load
    (dq̇_k/dt minus the closed-form free vibration) equals −Σ_a F_a·W_k(x_a)/(ρAL), F_a
    recovered from the units' own equations, W_k by ``quad`` of φ_k over the footprint,
    both planes, both slots (1e-9 of the largest modal load).
``equilibrium_rigid``
    At rest on a rigid, straight, smooth guideway with the nominal current I0, the
    right-hand side on the initial state and the recorded capsule accelerations over 0.2 s
    vanish (< 1e-9·g), for the repelling and the attracting magnet.
``weight_check``
    Production path: the fixed point of the Simulator's one-step map at I0 (Newton), Σ of
    the four ``M_FY`` vs (15 000 + 22 000 kg)·9.81 m/s² (paper Table 1), and I0 vs
    δ0·√(4F0/(μ0N²A0)) (1e-9).
``integrator_vs_radau``
    The simulator's fixed-step RK4 (default 4 substeps per 1 ms) against
    ``solve_ivp(method="Radau", rtol=1e-8, atol=1e-11)`` on the same compiled right-hand
    side, 1 s at 1000 km/h with the default irregularity, constant I0; the span-slot
    switches of ``model._update_ring`` are reproduced by integrating piecewise between
    the (closed-form) switch times. RMS error of the four gap excursions < 1 % of their
    RMS. The wall-clock speed-up is reported as info.
``passive_stability_repelling`` / ``passive_instability_attracting``
    Eigenvalues of :func:`linearize.linearize` at equilibrium: all in the left half-plane
    for the repelling magnet; at least one positive real eigenvalue for the attracting one
    (compared, as info, with the rigid-body estimate ``√(2F0/(δ0·m_eff))``).
``vehicle_mode_{heave,pitch,roll,lateral,yaw}_{hz,zeta}``
    Production path: eigenvalues log(μ)/dt of the central-difference Jacobian of the
    Simulator's one-control-step map (RK4, rigid straight smooth guideway, ideal current
    source, repelling, I0) vs the 13-DOF vehicle whose M, C, K are assembled by hand from
    the parameters (primary/secondary per corner, corner kinematics, magnet gap stiffness
    2F0/δ0 and edge stiffness (2/π)F0/b2 derived on paper; ``scipy.linalg.eig``): natural
    frequency |λ|/2π and damping ratio −Re λ/|λ| of each capsule mode (1e-6).
``vehicle_eigenvalues_{repelling,attracting}``
    All 26 eigenvalues of the same map vs the 13-DOF reference (unit/frame modes and
    overdamped pairs included), paired by min-cost assignment (max rel. error < 1e-6).
``vehicle_unstable_pole_attracting``
    Largest real eigenvalue of the attracting vehicle, map vs 13-DOF (1e-6); the
    rigid-body estimate √(2g/δ0) is reported beside it.
``curve_lateral_offset_R200km`` / ``..._cant1deg`` / ``curve_lateral_offset_2000kmh_R200km``
    Production path: 12 s at 1000 (2000) km/h through a 300 m clothoid into R = 200 km (no
    cant / 1° cant), rigid, smooth, bias currents; mean ``M_LAT`` of the four units over
    the last 2 s vs the static lateral equilibrium of a unit under (m_v + m_m)/4·a_lat,
    a_lat = v²/R·cos θ − g·sin θ, balanced by the levitation edge force and the guidance
    pair written from the force laws, with the gap change of the reduced overlap
    (``brentq``) (1e-3).
``guidance_stiffness_{repelling,attracting}``
    Production rhs: −∂F_g/∂z of unit FL's guidance pair at bias by central differences vs
    ±4·F_g0/δg0 with F_g0 and the design-rule bias written out again (1e-6; the sign must
    match: restoring when repelling, destabilising when attracting).
``guidance_pole_attracting``
    The unstable pole of the attracting guidance pairs (the units' lateral twist mode,
    capsule at rest) from the Simulator's step map vs the closed form of
    m_u z̈ + c_s ż + (k_s + k_e − 4F_g0/δg0) z = 0 (1e-6).
``magnet_work_loop_{repelling,attracting}``
    Compiled ``magnet_forces`` at I0 and ``guidance_force`` at bias: work of all magnet
    forces on the unit (dy = σ·ds) around the rectangle s 0→2 mm, z 0→6 mm by ``quad``;
    |W| over the first edge's work < 1e-6 (forces from an energy do no work on a closed
    path; the edge force of a repelling magnet pushes the unit off its rail, of an
    attracting one pulls it back, MODEL.md).
``irregularity_variance_{vertical,lateral}``
    Sample variance of generated profiles (full period, mean over seeds) vs
    ``∫ S(Ω) dΩ`` over the band by ``scipy.integrate.quad`` (2 %). Over one full period
    the variance of the spectral representation is Σ_k S_k whatever the phases (S_k the
    PSD integrated over bin k), so the seeds agree to rounding and the sum equals the
    band integral. The reference integrates the spectrum written out again from MODEL.md
    (not ``irregularity.psd``); the class amplitudes are read from the parameter table.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Callable
from functools import partial
from typing import Any

import numba as nb
import numpy as np

from hyperloop_env.physics import irregularity as irr_mod
from hyperloop_env.physics.guideway import footprint_weights, mode_shape
from hyperloop_env.physics.layout import (
    BEAM0,
    M_ACC_HEAVE,
    M_ACC_YAW,
    M_GAP,
    NQ,
    P_A2,
    P_D1H,
    P_F0,
    P_G,
    P_I0,
    P_MODALMASS,
    P_NMODES,
    P_OMEGA1Y,
    P_SPAN,
    P_SPEED,
    P_XSTART,
    P_ZETA,
    beam_index,
    state_size,
)
from hyperloop_env.physics.linearize import linearize
from hyperloop_env.physics.model import Simulator, neutral_commands, pack
from hyperloop_env.physics.params import (
    IRREGULARITY_CLASSES,
    GuidewayParams,
    IrregularityParams,
    MagnetParams,
    ModelParams,
)
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES
from hyperloop_env.physics.vehicle import NU, U_GAP, rhs
from hyperloop_env.verification import guideway as vg
from hyperloop_env.verification import vehicle as vv
from hyperloop_env.verification.common import CaseResult, compare, threshold
from hyperloop_env.verification.reference import (
    beam_frequency_closed_form_hz,
    fe_beam_frequencies_hz,
    fryba_daf,
    german_track_psd,
)

BEAM_MODES = (1, 2, 3)
DAF_ALPHAS = (0.25, 0.5, 0.75, 1.0)
# Approximate DAF values quoted in shared/design/MODEL.md (Frýba; Olsson 1991), used only
# to sanity-check the analytical series.
DAF_LITERATURE = {0.25: 1.26, 0.5: 1.70, 0.75: 1.70, 1.0: 1.55}
DAF_LITERATURE_TOL = 0.03  # the quoted values are read off curves to ~2 digits


_compare = compare
_threshold = threshold


class _Rhs:
    """Python wrapper of the compiled right-hand side with constant currents."""

    def __init__(self, P: np.ndarray, irr: np.ndarray, spans: np.ndarray, current: float):
        self.P = P
        self.irr = irr
        self.spans = spans
        nm = int(P[P_NMODES])
        self.cur = neutral_commands(P)  # full command vector: guidance pairs at bias
        self.cur[: len(UNIT_NAMES)] = current
        self.wts = np.zeros((N_UNITS, 2, nm))
        self.uo = np.zeros((NU, N_UNITS))
        self.nfev = 0

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
        d = np.empty_like(y)
        rhs(t, y, self.P, self.irr, 0.0, self.cur, self.cur, self.spans, d, self.wts, self.uo)
        self.nfev += 1
        return d


# ---------------------------------------------------------------------------------------
# 1. beam natural frequencies
# ---------------------------------------------------------------------------------------


def _zero_crossing_frequency(t: np.ndarray, x: np.ndarray) -> float:
    """Mean frequency [Hz] from the upward zero crossings (linear interpolation)."""
    i = np.nonzero((x[:-1] < 0.0) & (x[1:] >= 0.0))[0]
    tc = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    if tc.size < 2:
        return math.nan
    return (tc.size - 1) / (tc[-1] - tc[0])


BEAM_FREQ_TOL = 1e-4
"""Tolerance of ``beam_frequency_mode_*``: the zero-crossing measurement (RK4 at 200 steps
per period, 20 periods) is good to ~1e-8 and the 60-element FE reference to < 1e-6."""


def beam_frequency(mode: int, params: ModelParams | None = None) -> CaseResult:
    """Natural frequency of vertical mode ``mode`` of a span, measured from a free
    vibration simulated with the compiled ``vehicle.rhs``, against an independent
    Euler–Bernoulli finite-element model of the span
    (:func:`reference.fe_beam_frequencies_hz`, 60 Hermite cubic elements,
    consistent mass, built from EI, ρA and L)."""
    p = params if params is not None else ModelParams()
    g = p.guideway
    P = pack(p)
    P[P_ZETA] = 0.0  # undamped: the zero-crossing frequency is the natural frequency
    nm = int(P[P_NMODES])
    if not 1 <= mode <= nm:
        raise ValueError(f"mode must be in [1, {nm}], got {mode!r}")
    n_state = state_size(nm)
    y = np.zeros(n_state)
    # the vehicle stands on spans 0/-1 while the two slots hold spans far ahead: the
    # magnet footprints miss them, so the slots vibrate freely
    spans = np.array([1000, 1001], dtype=np.int64)
    f = _Rhs(P, np.zeros((3, 16)), spans, float(P[P_I0]))
    iq = beam_index(0, 0, 0, mode - 1, nm)
    y[iq] = 1e-3
    n_fe = max(mode, 3)
    f_fe = fe_beam_frequencies_hz(
        g.bending_stiffness_Nm2, g.mass_per_length_kg_per_m, g.span_m, n_fe
    )
    f_fe_lat = fe_beam_frequencies_hz(
        g.lateral_bending_stiffness_Nm2, g.mass_per_length_kg_per_m, g.span_m, n_fe
    )
    f_ref = float(f_fe[mode - 1])
    n_per, n_cyc = 200, 20
    h = 1.0 / (f_ref * n_per)
    n = n_per * n_cyc
    ts = np.arange(n + 1) * h
    xs = np.empty(n + 1)
    xs[0] = y[iq]
    # the vehicle sits at its equilibrium on a straight rigid-looking track (no load
    # reaches the slots, w = 0 under the units): only the span moves
    for j in range(n):
        t = ts[j]
        k1 = f(t, y)
        k2 = f(t + h / 2, y + h / 2 * k1)
        k3 = f(t + h / 2, y + h / 2 * k2)
        k4 = f(t + h, y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        xs[j + 1] = y[iq]
    f_meas = _zero_crossing_frequency(ts, xs)
    beam = y[BEAM0:]
    other = np.delete(beam, [iq - BEAM0, iq - BEAM0 + nm])
    # eigenvalues of the numerically linearised guideway blocks (default damping), slot 0,
    # vertical (plane 0) and lateral (plane 1) planes
    Pd = pack(p)
    fd = _Rhs(Pd, np.zeros((3, 16)), spans, float(Pd[P_I0]))
    nb_ = 2 * nm  # one slot and plane: displacements then rates
    y0 = np.zeros(n_state)
    eps = 1e-6
    f_eig = []
    for plane in (0, 1):
        b0 = beam_index(0, plane, 0, 0, nm)
        J = np.zeros((nb_, nb_))
        for c in range(nb_):
            e = y0.copy()
            e[b0 + c] = eps
            J[:, c] = (fd(0.0, e)[b0 : b0 + nb_] - fd(0.0, y0)[b0 : b0 + nb_]) / eps
        lam = np.linalg.eigvals(J)
        f_eig.append(np.sort(np.abs(lam[lam.imag > 0])) / (2 * math.pi))
    return _compare(
        f"beam_frequency_mode_{mode}",
        f"vertical bending mode {mode} of a {g.span_m:g} m span: free vibration of the "
        "compiled guideway equations (zero crossings, undamped) vs an independent "
        "Euler-Bernoulli FE beam (60 Hermite cubic elements, consistent mass, eigh) [Hz]",
        f_meas,
        f_ref,
        BEAM_FREQ_TOL,
        info={
            "closed_form_hz": beam_frequency_closed_form_hz(
                mode, g.bending_stiffness_Nm2, g.mass_per_length_kg_per_m, g.span_m
            ),
            "eigenvalue_frequency_hz": float(f_eig[0][mode - 1]),
            "eigenvalue_rel_error": float(abs(f_eig[0][mode - 1] - f_ref) / f_ref),
            "lateral_eigenvalue_frequency_hz": float(f_eig[1][mode - 1]),
            "lateral_fe_hz": float(f_fe_lat[mode - 1]),
            "lateral_rel_error": float(
                abs(f_eig[1][mode - 1] - f_fe_lat[mode - 1]) / f_fe_lat[mode - 1]
            ),
            "max_other_modal_coordinate": float(np.abs(other).max()),
        },
    )


# ---------------------------------------------------------------------------------------
# 2. static midspan deflection
# ---------------------------------------------------------------------------------------


def static_midspan_series(
    P: np.ndarray, force: float, n_modes: int, half_len: float = 1e-4
) -> float:
    """Midspan deflection [m] (positive down) of one span under a load ``force`` [N]
    spread over ``2·half_len`` at midspan: Σ_k Q_k/(ρAL·ω_k²)·φ_k(L/2), Q_k = F·W_k."""
    span = float(P[P_SPAN])
    w = np.zeros(n_modes)
    footprint_weights(span / 2, half_len, 0.0, span, w)
    k = np.arange(1, n_modes + 1)
    omega = P[P_OMEGA1Y] * k**2
    q = force * w / (P[P_MODALMASS] * omega**2)
    phi = np.array([mode_shape(span / 2, kk, span) for kk in k])
    return float(q @ phi)


def static_midspan_deflection(params: ModelParams | None = None) -> CaseResult:
    p = params if params is not None else ModelParams()
    g = p.guideway
    P = pack(p)
    force = float(P[P_F0])
    ref = force * g.span_m**3 / (48 * g.bending_stiffness_Nm2)
    n = 51
    val = static_midspan_series(P, force, n)
    val_default = static_midspan_series(P, force, g.n_modes)
    return _compare(
        "static_midspan_deflection",
        f"point load at midspan, modal static solution q_k = Q_k/(rhoAL omega_k^2) with "
        f"{n} modes (footprint_weights, 0.2 mm footprint) vs PL^3/(48EI) [m]",
        val,
        ref,
        1e-3,
        info={
            "n_modes": n,
            f"computed_with_{g.n_modes}_modes": val_default,
            f"rel_error_with_{g.n_modes}_modes": abs(val_default - ref) / ref,
        },
    )


# ---------------------------------------------------------------------------------------
# 3. moving constant force: dynamic amplification
# ---------------------------------------------------------------------------------------


RK4_STAGES = 4


@nb.njit(cache=True)
def _moving_force_rk4(
    omega1: float,
    zeta: float,
    modal_mass: float,
    span: float,
    half_len: float,
    force: float,
    speed: float,
    n_modes: int,
    h: float,
    t_end: float,
) -> tuple[float, float]:
    """Modal equations of one span as in vehicle.rhs, ρAL(q̈_k + 2ζω_k q̇_k + ω_k² q_k) =
    −F·W_k(x(t)), load centre x = v·t, integrated from rest with RK4 (step h).
    Returns (max midspan deflection [m, positive down], during the crossing; overall)."""
    n = n_modes
    q = np.zeros(n)
    qd = np.zeros(n)
    wk = np.empty(n)
    om = np.empty(n)
    phi = np.empty(n)
    for k in range(n):
        om[k] = omega1 * (k + 1) * (k + 1)
        phi[k] = math.sqrt(2.0) * math.sin((k + 1) * math.pi / 2)
    kq = np.empty((RK4_STAGES, n))
    kv = np.empty((RK4_STAGES, n))
    qs = np.empty(n)
    vs = np.empty(n)
    n_steps = int(math.ceil(t_end / h))
    t_exit = (span + half_len) / speed
    max_during = 0.0
    max_all = 0.0
    for j in range(n_steps):
        t = j * h
        for s in range(RK4_STAGES):
            if s == 0:
                ts = t
                for k in range(n):
                    qs[k] = q[k]
                    vs[k] = qd[k]
            else:
                c = 0.5 * h if s < 3 else h
                ts = t + c
                for k in range(n):
                    qs[k] = q[k] + c * kq[s - 1, k]
                    vs[k] = qd[k] + c * kv[s - 1, k]
            footprint_weights(speed * ts, half_len, 0.0, span, wk)
            for k in range(n):
                kq[s, k] = vs[k]
                kv[s, k] = (
                    -2.0 * zeta * om[k] * vs[k] - om[k] * om[k] * qs[k] - force * wk[k] / modal_mass
                )
        mid = 0.0
        for k in range(n):
            q[k] += h / 6.0 * (kq[0, k] + 2.0 * kq[1, k] + 2.0 * kq[2, k] + kq[3, k])
            qd[k] += h / 6.0 * (kv[0, k] + 2.0 * kv[1, k] + 2.0 * kv[2, k] + kv[3, k])
            mid -= q[k] * phi[k]
        if mid > max_all:
            max_all = mid
        if (j + 1) * h <= t_exit and mid > max_during:
            max_during = mid
    return max_during, max_all


def moving_force_daf_numerical(
    alpha: float,
    params: ModelParams | None = None,
    n_modes: int | None = None,
    periods_after: float = 3.0,
    omega_h: float = 0.05,
) -> tuple[float, float]:
    """(DAF over the crossing only, DAF over crossing + free vibration) from the project's
    modal equations (undamped) with ``n_modes`` (default: the project's) modes."""
    p = params if params is not None else ModelParams()
    g = p.guideway
    P = pack(p)
    nm = g.n_modes if n_modes is None else int(n_modes)
    omega1 = float(P[P_OMEGA1Y])
    f1 = omega1 / (2 * math.pi)
    span = float(P[P_SPAN])
    speed = alpha * 2 * f1 * span
    force = float(P[P_F0])
    half_len = 1e-4
    h = omega_h / (omega1 * nm * nm)
    t_end = (span + half_len) / speed + periods_after / f1
    d_st = force * span**3 / (48 * g.bending_stiffness_Nm2)
    during, overall = _moving_force_rk4(
        omega1, 0.0, float(P[P_MODALMASS]), span, half_len, force, speed, nm, h, t_end
    )
    return during / d_st, overall / d_st


def moving_force_daf(alpha: float, params: ModelParams | None = None) -> CaseResult:
    p = params if params is not None else ModelParams()
    nm = p.guideway.n_modes
    during, overall = moving_force_daf_numerical(alpha, p)
    ref = fryba_daf(alpha)
    odd = np.arange(1, nm + 1, 2, dtype=float)
    static_trunc = float(np.sum(1.0 / odd**4) / (math.pi**4 / 96) - 1.0)
    lit = DAF_LITERATURE.get(alpha)
    info: dict[str, Any] = {
        "n_modes_numerical": nm,
        "numerical_daf_during_crossing": during,
        "static_truncation_rel_error": static_trunc,
    }
    if lit is not None:
        info["literature_daf"] = lit
        info["series_vs_literature_rel"] = abs(ref - lit) / lit
    return _compare(
        f"moving_force_daf_alpha_{alpha}",
        f"constant force crossing one span at alpha = v/(2 f1 L) = {alpha}: max midspan "
        f"deflection (crossing + 3 periods after) / (PL^3/48EI), project modal equations "
        f"({nm} modes, undamped, RK4) vs Fryba's analytical series (101 modes)",
        overall,
        ref,
        2e-2,
        info=info,
    )


# ---------------------------------------------------------------------------------------
# 4. equilibrium on a rigid guideway
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
        f = _Rhs(sim.P, sim.irr, sim.spans.copy(), i0)
        d = f(0.0, sim.y.copy())
        vals[f"{orientation}_rhs_max_over_g"] = float(np.abs(d[: 2 * NQ]).max() / g)
        rec = sim.run([i0] * 4, n_steps)
        vals[f"{orientation}_record_acc_max_over_g"] = float(
            np.abs(rec[:, M_ACC_HEAVE : M_ACC_YAW + 1]).max() / g
        )
        vals[f"{orientation}_max_gap_m"] = float(np.abs(rec[:, M_GAP : M_GAP + 4]).max())
    worst = max(v for k, v in vals.items() if k.endswith("_over_g"))
    thr = 1e-9
    return _threshold(
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
# 5. RK4 against Radau
# ---------------------------------------------------------------------------------------


def span_switch_times(P: np.ndarray, duration_s: float) -> list[tuple[float, int]]:
    """(time, span index) at which the front magnet footprint enters a new span, i.e.
    when ``model._update_ring`` gives that span a slot: x_front = X_START + v t + d1/2 +
    a2/2 = j·L."""
    span = float(P[P_SPAN])
    v = float(P[P_SPEED])
    xf0 = float(P[P_XSTART] + P[P_D1H] + 0.5 * P[P_A2])
    j = int(math.floor(xf0 / span)) + 1
    out = []
    while True:
        t = (j * span - xf0) / v
        if t >= duration_s:
            return out
        out.append((t, j))
        j += 1


def integrator_vs_radau(duration_s: float = 1.0, seed: int = 0) -> CaseResult:
    """RK4 simulator vs piecewise Radau on the same right-hand side (constant I0)."""
    from scipy.integrate import solve_ivp

    p = ModelParams()
    sim = Simulator(p)
    dt = p.simulation.control_dt_s
    n_steps = int(round(duration_s / dt))
    i0 = sim.nominal_current_A
    sim.reset(seed=seed)
    sim.run([i0] * 4, 2)  # compile / warm up
    rk4_wall = math.inf
    for _ in range(3):  # best of three: the run takes only ~10 ms
        sim.reset(seed=seed)
        y_init = sim.y.copy()
        spans = sim.spans.copy()
        t_a = time.perf_counter()
        rec = sim.run([i0] * 4, n_steps)
        rk4_wall = min(rk4_wall, time.perf_counter() - t_a)
    gap_rk4 = rec[:, M_GAP : M_GAP + 4]

    P = sim.P
    nm = int(P[P_NMODES])
    f = _Rhs(P, sim.irr, spans, i0)
    t_rec = np.arange(1, n_steps + 1) * dt
    switches = span_switch_times(P, duration_s)
    bounds = [0.0] + [t for t, _ in switches] + [n_steps * dt]
    y = y_init
    gaps = np.zeros((n_steps, N_UNITS))
    n_done = 0
    rtol, atol = 1e-8, 1e-11
    t_b = time.perf_counter()
    for piece in range(len(bounds) - 1):
        a, b = bounds[piece], bounds[piece + 1]
        if piece > 0:
            j = switches[piece - 1][1]
            slot = j % 2
            spans[slot] = j
            base = BEAM0 + slot * 4 * nm
            y = y.copy()
            y[base : base + 4 * nm] = 0.0
        te = t_rec[(t_rec > a) & (t_rec < b)]
        if piece == len(bounds) - 2:
            te = t_rec[t_rec > a]
        t_eval = np.append(te[te < b], b)
        sol = solve_ivp(f, (a, b), y, method="Radau", rtol=rtol, atol=atol, t_eval=t_eval)
        if not sol.success:
            raise RuntimeError(f"Radau failed on [{a}, {b}]: {sol.message}")
        for c in range(len(te)):
            f(float(sol.t[c]), sol.y[:, c])
            gaps[n_done] = f.uo[U_GAP]
            n_done += 1
        y = sol.y[:, -1]
    radau_wall = time.perf_counter() - t_b
    assert n_done == n_steps
    err = float(np.sqrt(np.mean((gap_rk4 - gaps) ** 2)))
    rms = float(np.sqrt(np.mean(gaps**2)))
    ratio = err / rms
    thr = 1e-2
    return _threshold(
        "integrator_vs_radau",
        f"RK4 simulator ({p.simulation.substeps} substeps per {dt * 1e3:g} ms) vs "
        f"solve_ivp Radau (rtol={rtol:g}, atol={atol:g}) on the compiled rhs, "
        f"{duration_s:g} s at {p.condition.speed_kmh:g} km/h, default irregularity, "
        "constant I0: RMS gap-excursion error / RMS gap excursion (4 units)",
        ratio,
        thr,
        ratio < thr,
        info={
            "duration_s": duration_s,
            "rms_error_m": err,
            "rms_gap_m": rms,
            "max_abs_error_m": float(np.abs(gap_rk4 - gaps).max()),
            "span_switches": len(switches),
            "rk4_wall_s": rk4_wall,
            "radau_wall_s": radau_wall,
            "radau_nfev": f.nfev,
            "speedup": radau_wall / rk4_wall,
        },
    )


# ---------------------------------------------------------------------------------------
# 6. passive stability
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
        return _threshold(
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
    return _threshold(
        "passive_instability_attracting",
        "attracting magnet, constant current I0: largest positive real eigenvalue of the "
        "linearised vehicle (must be > 0)",
        lam if real_pos.size else max_re,
        0.0,
        bool(real_pos.size > 0),
        info=info,
    )


# ---------------------------------------------------------------------------------------
# 7. irregularity variance
# ---------------------------------------------------------------------------------------


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
    return _compare(
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


# ---------------------------------------------------------------------------------------
# registry and CLI
# ---------------------------------------------------------------------------------------

CASES: dict[str, Callable[[], CaseResult]] = {}
for _m in BEAM_MODES:
    CASES[f"beam_frequency_mode_{_m}"] = partial(beam_frequency, _m)
CASES["static_midspan_deflection"] = static_midspan_deflection
CASES["static_deflection_initial_state"] = vg.static_deflection_initial_state
CASES["static_midspan_slow_crossing"] = vg.static_midspan_slow_crossing
for _a in DAF_ALPHAS:
    CASES[f"moving_force_daf_alpha_{_a}"] = partial(moving_force_daf, _a)
for _a in vg.SIM_DAF_ALPHAS:
    CASES[f"moving_force_daf_sim_alpha_{_a}"] = partial(vg.moving_force_daf_sim, _a)
CASES["guideway_load_coupling"] = vg.guideway_load_coupling
CASES["equilibrium_rigid"] = equilibrium_rigid
CASES["weight_check"] = vv.weight_check
CASES["integrator_vs_radau"] = integrator_vs_radau
CASES["passive_stability_repelling"] = partial(passive_stability, "repelling")
CASES["passive_instability_attracting"] = partial(passive_stability, "attracting")
for _n in vv.VEHICLE_MODE_NAMES:
    for _q in ("hz", "zeta"):
        CASES[f"vehicle_mode_{_n}_{_q}"] = partial(vv.vehicle_mode, _n, _q)
CASES["vehicle_eigenvalues_repelling"] = partial(vv.vehicle_eigenvalues, "repelling")
CASES["vehicle_eigenvalues_attracting"] = partial(vv.vehicle_eigenvalues, "attracting")
CASES["vehicle_unstable_pole_attracting"] = vv.vehicle_unstable_pole_attracting
for _c in vv.CURVE_CASES:
    CASES[_c] = partial(vv.curve_lateral_offset, _c)
CASES["guidance_stiffness_repelling"] = partial(vv.guidance_stiffness, "repelling")
CASES["guidance_stiffness_attracting"] = partial(vv.guidance_stiffness, "attracting")
CASES["guidance_pole_attracting"] = vv.guidance_pole_attracting
CASES["magnet_work_loop_repelling"] = partial(vv.magnet_work_loop, "repelling")
CASES["magnet_work_loop_attracting"] = partial(vv.magnet_work_loop, "attracting")
CASES["irregularity_variance_vertical"] = partial(irregularity_variance, False)
CASES["irregularity_variance_lateral"] = partial(irregularity_variance, True)
CASE_NAMES: tuple[str, ...] = tuple(CASES)

KNOWN_FAILURES: dict[str, str] = {}
"""Cases that fail on the current physics for a documented reason (a known bug). They are
run and reported as XFAIL; the exit code ignores them while they fail and counts them as a
failure once they pass (XPASS: remove the entry), like pytest's strict xfail."""


def run_all(names: list[str] | None = None) -> dict[str, CaseResult]:
    """Run the cases (all by default) in a stable order."""
    out = {}
    for name in names if names is not None else CASE_NAMES:
        if name not in CASES:
            raise ValueError(f"unknown case {name!r}; known: {', '.join(CASE_NAMES)}")
        out[name] = CASES[name]()
    return out


def outcome(name: str, r: CaseResult) -> str:
    """PASS, FAIL, XFAIL (a known failure that still fails) or XPASS (a known failure
    that now passes)."""
    if name in KNOWN_FAILURES:
        return "XPASS" if r.passed else "XFAIL"
    return "PASS" if r.passed else "FAIL"


def _fmt(x: float | None) -> str:
    return "-" if x is None else f"{x:.6g}"


def format_table(results: dict[str, CaseResult]) -> str:
    w = max(34, *(len(n) for n in results)) if results else 34
    lines = [
        f"{'case':{w}s} {'computed/value':>15s} {'reference/thr':>15s} "
        f"{'rel_error':>10s} {'tol':>8s}  result"
    ]
    for name, r in results.items():
        if r.computed is not None:
            a, b, e = _fmt(r.computed), _fmt(r.reference), f"{r.rel_error:.2e}"
        else:
            a, b, e = _fmt(r.value), _fmt(r.threshold), "-"
        lines.append(
            f"{name:{w}s} {a:>15s} {b:>15s} {e:>10s} {r.tolerance:8.1e}  {outcome(name, r)}"
        )
        if "speedup" in r.info:
            lines.append(
                f"{'':{w}s} RK4 {r.info['rk4_wall_s']:.3g} s, Radau {r.info['radau_wall_s']:.3g}"
                f" s: speed-up x{r.info['speedup']:.0f}"
            )
        if name in KNOWN_FAILURES:
            lines.append(f"{'':{w}s} known failure: {KNOWN_FAILURES[name]}")
    counts = {k: 0 for k in ("PASS", "FAIL", "XFAIL", "XPASS")}
    for name, r in results.items():
        counts[outcome(name, r)] += 1
    summary = f"{counts['PASS']}/{len(results)} passed"
    if counts["XFAIL"] or counts["XPASS"]:
        summary += f", {counts['XFAIL']} known failures (XFAIL), {counts['XPASS']} XPASS"
    lines.append(summary)
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Exit code 0 if every case passes except the known failures (which must still
    fail), else 1."""
    ap = argparse.ArgumentParser(
        prog="python -m hyperloop_env.verification", description=__doc__.splitlines()[0]
    )
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--case", action="append", choices=CASE_NAMES, help="run only these")
    args = ap.parse_args(argv)
    results = run_all(args.case)
    if args.json:
        out = {}
        for k, r in results.items():
            d = r.to_dict()
            if k in KNOWN_FAILURES:
                d["known_failure"] = KNOWN_FAILURES[k]
                d["outcome"] = outcome(k, r)
            out[k] = d
        print(json.dumps(out, indent=2))
    else:
        print(format_table(results))
    ok = all(outcome(k, r) in ("PASS", "XFAIL") for k, r in results.items())
    return 0 if ok else 1
