"""LQG gap controller: discrete LQR on the linearised vehicle with a steady-state Kalman
filter on the measured signals (no privileged state).

Design model (all from :func:`hyperloop_env.physics.linearize.linearize`, see
:mod:`agents.controllers.linear`): the 14-state vertical plane (heave, pitch, roll, 4 unit
heights and rates) + 4 coil-current states (first-order lag τ = ``coil_time_constant_s``,
omitted when τ = 0) + a track-disturbance model per unit: the guideway height under unit a, ``r_a``
(beam deflection + irregularity), as a second-order Gauss–Markov process
``r̈ = −ω_d²·r − 2ζ_d·ω_d·ṙ + w`` (ω_d = 2π·0.5 Hz, ζ_d = 0.7 — not 1, whose Jordan
blocks break the Riccati solver: a slowly varying "constant velocity" profile whose fast
part is carried by the process noise). The gap is
``s_a = σ·(y_a − r_a)`` and the magnet force sees the track through ``k_m·σ·r_a``
(k_m = 2F0/δ0). Integral states ``q_a = ∫ s_a dt`` remove steady offsets (curves, the
mean guideway sag). Everything is discretised with a zero-order hold at the control
interval (the simulator holds the command over the interval).

LQR (scipy.linalg.solve_discrete_are), Bryson-style weights: per step cost
``Σ_a (s_a/s_ref)² + (q_a/q_ref)² + (a_heave/a_ref)² + (ΔI_a/I_ref)²`` with
s_ref = 0.5 mm, q_ref = 0.5 mm·s, a_ref = 1 m/s² (capsule heave acceleration: the comfort
knob; a_ref = 2 gives ~5 % less gap RMS at 1000 km/h for ~20 % more W_k acceleration),
I_ref = 15 A. The disturbance modes are uncontrollable but stable, so the Riccati
equation is solvable and the gain contains the feed-forward from the estimated track.

Kalman filter (solve_discrete_are on the dual): measurements = gap excursions (4, σ_n =
20 µm), applied coil currents (4, 0.05 A; only with τ > 0) and capsule heave acceleration
(1, 0.05 m/s²) from the observation vector, plus weak pseudo-measurements "capsule
heave, pitch, roll ≈ 0" (σ = 2 mm): without them the common mode "vehicle and track
shifted together" (invisible in every gap) drifts under model mismatch and the loop
fails after ~6 s (found on 10 km runs); process noise = track acceleration
(σ_w = 100 m/s²/√Hz: the filter must follow 9–18 Hz span passing) and unmodelled unit
forces (1 m/s²/√Hz). The filter runs in predictor–corrector form with the *saturated*
command, so saturation does not corrupt the estimate; the integrator is clamped.
The lateral plane is not controllable by the levitation currents at equilibrium; with
``actuators="levitation+guidance"`` a second LQG of the same structure
(:class:`LateralLQRDesign`) drives the guidance pairs' differential currents from the
measured guidance gaps, guidance currents and capsule lateral acceleration; with
``actuators="levitation"`` the guidance pairs stay at bias (passive guidance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numba as nb
import numpy as np
from scipy.linalg import schur, solve_discrete_are

from agents.controllers.base import BaseController, ControlContext, control_context
from agents.controllers.linear import (
    LATERAL_STATES,
    VERTICAL_STATES,
    PlaneModel,
    c2d,
    lateral_model,
    vertical_model,
)
from hyperloop_env.physics.arrays import FLOAT32, aligned_copy, aligned_zeros, is_float
from hyperloop_env.physics.entry import compiled_entry, strided
from hyperloop_env.physics.params import MU0, ModelParams
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES

NU = N_UNITS
_UNIT_RATE_ROWS = tuple(VERTICAL_STATES.index(f"dy_{u}") for u in UNIT_NAMES)


@dataclass(frozen=True)
class LQRDesign:
    """Weights and noise levels (see the module docstring)."""

    s_ref_m: float = 0.5e-3
    q_ref_m_s: float = 0.5e-3
    a_ref_m_s2: float = 1.0
    i_ref_A: float = 15.0
    dist_omega_rad_s: float = 2 * math.pi * 0.5
    dist_zeta: float = 0.7
    dist_noise: float = 100.0
    force_noise: float = 1.0
    gap_noise_m: float = 2e-5
    current_noise_A: float = 0.05
    acc_noise_m_s2: float = 0.05
    anchor_m: float = 2e-3  # std of the pseudo-measurement capsule heave ≈ 0 [m]


@dataclass(frozen=True)
class LQGMatrices:
    Phi: np.ndarray
    Gam: np.ndarray
    C: np.ndarray  # measurement matrix (gaps, [currents], heave acc)
    K: np.ndarray  # (4, n + 4): state feedback on [x, q] [A]
    M: np.ndarray  # (n, n_meas): Kalman (measurement-update) gain
    C_s: np.ndarray  # gap rows (4, n)
    closed_loop_radius: float
    has_coil_states: bool
    # the LQR problem on [x, q] (q_{k+1} = q_k + dt·s_k), in coordinates scaled by ``sa``
    # (ξ̃ = ξ/sa): ξ̃⁺ = Pt·ξ̃ + Gt·u (u [A]), stage cost ξ̃ᵀQt ξ̃ + uᵀRu, value ξ̃ᵀSt ξ̃
    # (the Riccati solution: K = (R + GtᵀSt Gt)⁻¹GtᵀSt Pt / sa); used by the MPC
    Pt: np.ndarray | None = None
    Gt: np.ndarray | None = None
    Qt: np.ndarray | None = None
    R: np.ndarray | None = None
    St: np.ndarray | None = None
    sa: np.ndarray | None = None


def _design_scales(pos: list[float], rate: list[float], coil_A: float, coil: bool) -> np.ndarray:
    """Typical magnitudes of a plane's design states (the scaling of both Riccati
    problems): the vehicle positions ``pos`` [m or rad] and rates ``rate`` [m/s or
    rad/s], the coil currents ``coil_A`` [A] (if modelled), then per unit the track
    position 1 mm and rate 5 cm/s."""
    sx = pos + rate + ([coil_A] * NU if coil else [])
    return np.array(sx + [1e-3, 5e-2] * NU)


def _vertical_scales(coil: bool) -> np.ndarray:
    """Vertical plane: positions 1 mm (angles 1e-4 rad), rates 5 cm/s (5e-3 rad/s), coil
    currents 10 A."""
    return _design_scales(
        [1e-3, 1e-4, 1e-4] + [1e-3] * NU, [5e-2, 5e-3, 5e-3] + [5e-2] * NU, 10.0, coil
    )


def _sda(a: np.ndarray, b: np.ndarray, q: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Structure-preserving doubling for ``X = aᵀXa − aᵀXb(r + bᵀXb)⁻¹bᵀXa + q``
    (Chu, Fan, Lin, Wang 2004): quadratic convergence, robust where the QZ reordering of
    scipy's solver gives up on badly scaled problems."""
    n = a.shape[0]
    ak = a.copy()
    gk = b @ np.linalg.solve(r, b.T)
    hk = q.copy()
    eye = np.eye(n)
    for _ in range(200):
        w = eye + gk @ hk
        wa = np.linalg.solve(w, ak)
        wg = np.linalg.solve(w, gk)
        h_new = hk + ak.T @ hk @ wa
        gk = gk + ak @ wg @ ak.T
        ak = ak @ wa
        if np.max(np.abs(h_new - hk)) <= 1e-12 * max(1.0, np.max(np.abs(h_new))):
            return 0.5 * (h_new + h_new.T)
        hk = h_new
    raise np.linalg.LinAlgError("doubling algorithm for the Riccati equation did not converge")


def _dare(a: np.ndarray, b: np.ndarray, q: np.ndarray, r: np.ndarray) -> np.ndarray:
    """solve_discrete_are, falling back to the doubling algorithm if ordqz gives up."""
    try:
        return solve_discrete_are(a, b, q, r)
    except (ValueError, np.linalg.LinAlgError):
        return _sda(a, b, q, r)


def design_lqg(ctx: ControlContext | Any, design: LQRDesign | None = None) -> LQGMatrices:
    """Discrete LQR gain and steady-state Kalman gain for the plant of ``ctx`` (cached per
    parameter set and design)."""
    ctx = control_context(ctx)
    return _design_cached(ctx.params, design if design is not None else LQRDesign())


def _design_plane(
    vm: PlaneModel,
    dt: float,
    unit_mass_kg: float,
    track_stiffness_N_m: float,
    unit_rate_rows: tuple[int, ...],
    scales: np.ndarray,
    gap_ref_m: float,
    anchor_std: tuple[float, ...],
    d: LQRDesign | LateralLQRDesign,
) -> LQGMatrices:
    """The LQG design of one plane (module docstring), the same for both planes.

    ``vm``: the plane's model; ``dt`` [s]: the control interval; ``unit_mass_kg``: the mass
    of one unit's frame share; ``track_stiffness_N_m``: the force on a unit per metre of
    track displacement under it (the coupling of the track-disturbance states);
    ``unit_rate_rows``: the rows of the unit rates in ``vm.A``; ``scales``: the typical
    state magnitudes (:func:`_design_scales`); ``gap_ref_m``: the gap weight's reference;
    ``anchor_std``: the standard deviations of the pseudo-measurements "first vehicle
    states ≈ 0" [m or rad]; ``d``: the weights and noise levels."""
    nv = vm.n  # vehicle (+ coil) states
    n = nv + 2 * NU
    if len(scales) != n:
        raise ValueError(f"{len(scales)} state scales for a design of {n} states")
    Phi, Gam, C_s, c_acc = _plane_model(
        vm, dt, unit_mass_kg, track_stiffness_N_m, unit_rate_rows, d
    )
    K, radius, lqr_scaled, Qs, R, S, sa = _plane_lqr(Phi, Gam, C_s, c_acc, dt, scales, gap_ref_m, d)
    C, Mk, has_coil = _plane_kalman(vm, Phi, C_s, c_acc, dt, unit_rate_rows, scales, anchor_std, d)
    return LQGMatrices(Phi, Gam, C, K, Mk, C_s, radius, has_coil, *lqr_scaled, Qs, R, S, sa)


def _plane_model(
    vm: PlaneModel,
    dt: float,
    unit_mass_kg: float,
    track_stiffness_N_m: float,
    unit_rate_rows: tuple[int, ...],
    d: LQRDesign | LateralLQRDesign,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The plane's design model: the vehicle (and coil) states with a second-order
    track-disturbance state per unit, discretised (ZOH); (Φ, Γ, the gap rows C_s, the
    acceleration row c_acc)."""
    nv = vm.n  # vehicle (+ coil) states
    n = nv + 2 * NU
    A = np.zeros((n, n))
    A[:nv, :nv] = vm.A
    B = np.zeros((n, NU))
    B[:nv] = vm.B
    for a in range(NU):
        ir, iv = nv + 2 * a, nv + 2 * a + 1
        A[ir, iv] = 1.0
        A[iv, ir] = -(d.dist_omega_rad_s**2)
        A[iv, iv] = -2 * d.dist_zeta * d.dist_omega_rad_s
        A[unit_rate_rows[a], ir] = track_stiffness_N_m / unit_mass_kg
    C_s = np.zeros((NU, n))  # gap s_a = σ·(y_a − r_a)
    C_s[:, :nv] = vm.C_gap
    for a in range(NU):
        C_s[a, nv + 2 * a] = -vm.sigma
    c_acc = np.zeros(n)
    c_acc[:nv] = vm.c_acc
    Phi, Gam = c2d(A, B, dt)
    return Phi, Gam, C_s, c_acc


def _plane_lqr(
    Phi: np.ndarray,
    Gam: np.ndarray,
    C_s: np.ndarray,
    c_acc: np.ndarray,
    dt: float,
    scales: np.ndarray,
    gap_ref_m: float,
    d: LQRDesign | LateralLQRDesign,
) -> tuple[
    np.ndarray,
    float,
    tuple[np.ndarray, np.ndarray],
    np.ndarray,
    np.ndarray,
    np.ndarray,
    np.ndarray,
]:
    """The LQR on [x, q] (q the gap integral) in scaled coordinates: (K in the original
    coordinates, the closed loop's spectral radius, the scaled (Φ̃, Γ̃), the scaled Q, R, the
    Riccati solution S, the scales sa)."""
    n = Phi.shape[0]
    # LQR on [x, q], q_{k+1} = q_k + dt·s_k
    na = n + NU
    Pa = np.zeros((na, na))
    Pa[:n, :n] = Phi
    Pa[n:, :n] = dt * C_s
    Pa[n:, n:] = np.eye(NU)
    Ga = np.vstack([Gam, np.zeros((NU, NU))])
    Q = np.zeros((na, na))
    Q[:n, :n] = C_s.T @ C_s / gap_ref_m**2 + np.outer(c_acc, c_acc) / d.a_ref_m_s2**2
    Q[n:, n:] = np.eye(NU) / d.q_ref_m_s**2
    Q += 1e-9 * np.eye(na) * np.trace(Q) / na  # regularise the unweighted directions
    R = np.eye(NU) / d.i_ref_A**2
    sa = np.concatenate([scales, np.full(NU, 1e-4)])
    Pt, Gt = Pa / sa[:, None] * sa[None, :], Ga / sa[:, None]
    S = _dare(Pt, Gt, Q * np.outer(sa, sa), R)
    K = np.linalg.solve(R + Gt.T @ S @ Gt, Gt.T @ S @ Pt) / sa[None, :]
    lqr_scaled = (Pt, Gt)
    radius = float(np.max(np.abs(np.linalg.eigvals(Pa - Ga @ K))))
    return K, radius, lqr_scaled, Q * np.outer(sa, sa), R, S, sa


def _plane_kalman(
    vm: PlaneModel,
    Phi: np.ndarray,
    C_s: np.ndarray,
    c_acc: np.ndarray,
    dt: float,
    unit_rate_rows: tuple[int, ...],
    scales: np.ndarray,
    anchor_std: tuple[float, ...],
    d: LQRDesign | LateralLQRDesign,
) -> tuple[np.ndarray, np.ndarray, bool]:
    """The steady-state Kalman filter on the measured gaps, currents (with a coil lag) and
    acceleration, plus the anchoring pseudo-measurements: (the measurement matrix C, the
    gain M, whether the currents are measured)."""
    nv = vm.n
    n = Phi.shape[0]
    rows = [C_s]
    noise = [d.gap_noise_m] * NU
    has_coil = vm.tau_s > 0
    if has_coil:
        Cc = np.zeros((NU, n))
        Cc[:, :nv] = vm.C_cur
        rows.append(Cc)
        noise += [d.current_noise_A] * NU
    rows.append(c_acc[None])
    noise.append(d.acc_noise_m_s2)
    # pseudo-measurements "capsule position and angles ≈ 0" (weak prior): the common mode
    # "vehicle and track shifted together" leaves every gap unchanged and is otherwise
    # observable only through the slow disturbance model, so model mismatch (the mean sag
    # of the flexible guideway, nonlinearity) makes the estimate drift
    anchor = np.zeros((len(anchor_std), n))
    for k in range(len(anchor_std)):
        anchor[k, k] = 1.0
    rows.append(anchor)
    noise += list(anchor_std)
    C = np.vstack(rows)
    G = np.zeros((n, 2 * NU))
    for a in range(NU):
        G[nv + 2 * a + 1, a] = d.dist_noise
        G[unit_rate_rows[a], NU + a] = d.force_noise
    Qn = G @ G.T * dt
    # solve in scaled coordinates (mm, cm/s, 10 A; measurements per noise std): the raw
    # problem spans ~12 orders of magnitude and ordqz fails on it for the attracting magnet
    sx = scales
    sy = np.asarray(noise)
    Pt = _dare(
        Phi.T / sx[None, :] * sx[:, None],
        (C * sx[None, :] / sy[:, None]).T,
        Qn / np.outer(sx, sx) + 1e-9 * np.eye(n),
        np.eye(len(sy)),
    )
    Ct = C * sx[None, :] / sy[:, None]
    Mt = Pt @ Ct.T @ np.linalg.inv(Ct @ Pt @ Ct.T + np.eye(len(sy)))
    Mk = Mt * sx[:, None] / sy[None, :]
    return C, Mk, has_coil


@lru_cache(maxsize=64)
def _design_cached(p: ModelParams, d: LQRDesign) -> LQGMatrices:
    ctx = control_context(p)
    vm = vertical_model(ctx.params)
    p = ctx.params
    f0 = p.vehicle.total_mass_kg * p.simulation.gravity_m_s2 / NU
    km = 2.0 * f0 / p.magnet.nominal_gap_m  # ∂F/∂r = σ·k_m
    return _design_plane(
        vm,
        ctx.dt_s,
        p.vehicle.frame_mass_kg / NU,
        km * vm.sigma,
        _UNIT_RATE_ROWS,
        _vertical_scales(vm.tau_s > 0),
        d.s_ref_m,
        (d.anchor_m, d.anchor_m / 8.0, d.anchor_m / 1.0),  # heave, pitch, roll
        d,
    )


# ---------------------------------------------------------------------------------------
# lateral plane (guidance pairs), used when the actuator set includes "guidance"
# ---------------------------------------------------------------------------------------

_UNIT_LAT_RATE_ROWS = tuple(LATERAL_STATES.index(f"dz_{u}") for u in UNIT_NAMES)


@dataclass(frozen=True)
class LateralLQRDesign:
    """Weights and noise levels of the lateral LQG (the guidance loops): the same structure
    as the vertical one (module docstring) with the guidance gap excursion z_a in place of
    the gap, the capsule's lateral acceleration in place of its heave acceleration, the
    guideway's lateral position under each unit as the track disturbance (its coupling to
    the unit is the magnetic lateral stiffness σ·4F_g0/δg0 − σ·(2/π)F0/b2), the pairs'
    differential currents as inputs (I_ref = 5 A of the ≈ 16 A bias) and pseudo-measurements
    "capsule lateral, yaw ≈ 0"."""

    z_ref_m: float = 0.5e-3
    q_ref_m_s: float = 0.5e-3
    a_ref_m_s2: float = 1.0
    i_ref_A: float = 5.0
    dist_omega_rad_s: float = 2 * math.pi * 0.5
    dist_zeta: float = 0.7
    dist_noise: float = 100.0
    force_noise: float = 1.0
    gap_noise_m: float = 2e-5
    current_noise_A: float = 0.05
    acc_noise_m_s2: float = 0.05
    anchor_m: float = 2e-3


def _lateral_scales(coil: bool) -> np.ndarray:
    """Lateral plane: positions 1 mm (yaw 1e-4 rad), rates 5 cm/s (5e-3 rad/s), coil
    currents 5 A."""
    return _design_scales([1e-3, 1e-4] + [1e-3] * NU, [5e-2, 5e-3] + [5e-2] * NU, 5.0, coil)


def design_lateral_lqg(
    ctx: ControlContext | Any, design: LateralLQRDesign | None = None
) -> LQGMatrices:
    """Discrete LQR and steady-state Kalman gains of the lateral plane (cached)."""
    ctx = control_context(ctx)
    return _lateral_cached(ctx.params, design if design is not None else LateralLQRDesign())


@lru_cache(maxsize=64)
def _lateral_cached(p: ModelParams, d: LateralLQRDesign) -> LQGMatrices:
    ctx = control_context(p)
    vm = lateral_model(ctx.params)
    p = ctx.params
    sigma = p.magnet.orientation_sign
    f0 = p.vehicle.total_mass_kg * p.simulation.gravity_m_s2 / NU
    gd = p.guidance
    ig0 = ctx.guidance_bias_A
    f_g0 = (
        MU0
        * gd.turns**2
        / 4.0
        * ig0**2
        * p.magnet.pole_length_m
        * gd.pole_height_m
        / (gd.nominal_gap_m**2)
    )
    k_mag = sigma * 4.0 * f_g0 / gd.nominal_gap_m - sigma * 2.0 / math.pi * f0 / (
        p.magnet.pole_width_m
    )
    return _design_plane(
        vm,
        ctx.dt_s,
        p.vehicle.frame_mass_kg / NU,
        k_mag,  # F = −k_mag·(z − r)
        _UNIT_LAT_RATE_ROWS,
        _lateral_scales(vm.tau_s > 0),
        d.z_ref_m,
        (d.anchor_m, d.anchor_m / 8.0),  # capsule lateral and yaw
        d,
    )


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def _next8(A, j, k):  # pragma: no cover - compiled
    """The first input ``k' ≥ k`` with a coefficient not zero in rows ``j … j+7`` of ``A``
    (``A.shape[1]``: none)."""
    while k < A.shape[1] and (
        A[j, k] == 0.0
        and A[j + 1, k] == 0.0
        and A[j + 2, k] == 0.0
        and A[j + 3, k] == 0.0
        and A[j + 4, k] == 0.0
        and A[j + 5, k] == 0.0
        and A[j + 6, k] == 0.0
        and A[j + 7, k] == 0.0
    ):
        k += 1
    return k


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def _next4(A, j, k):  # pragma: no cover - compiled
    """:func:`_next8` for rows ``j … j+3``."""
    while k < A.shape[1] and (
        A[j, k] == 0.0 and A[j + 1, k] == 0.0 and A[j + 2, k] == 0.0 and A[j + 3, k] == 0.0
    ):
        k += 1
    return k


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def _next1(A, j, k):  # pragma: no cover - compiled
    """:func:`_next8` for row ``j``."""
    while k < A.shape[1] and A[j, k] == 0.0:
        k += 1
    return k


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def _block8(A, X, out, j):  # pragma: no cover - compiled
    """Rows ``j … j+7`` of ``out`` += their terms, two inputs per pass over the batch."""
    nk, n = A.shape[1], X.shape[1]
    o0, o1, o2, o3 = out[j], out[j + 1], out[j + 2], out[j + 3]
    o4, o5, o6, o7 = out[j + 4], out[j + 5], out[j + 6], out[j + 7]
    k = _next8(A, j, 0)
    while k < nk:
        c0, c1, c2, c3 = A[j, k], A[j + 1, k], A[j + 2, k], A[j + 3, k]
        c4, c5, c6, c7 = A[j + 4, k], A[j + 5, k], A[j + 6, k], A[j + 7, k]
        x = X[k]
        k2 = _next8(A, j, k + 1)
        if k2 == nk:
            for i in range(n):
                xi = x[i]
                o0[i] += xi * c0
                o1[i] += xi * c1
                o2[i] += xi * c2
                o3[i] += xi * c3
                o4[i] += xi * c4
                o5[i] += xi * c5
                o6[i] += xi * c6
                o7[i] += xi * c7
            return
        d0, d1, d2, d3 = A[j, k2], A[j + 1, k2], A[j + 2, k2], A[j + 3, k2]
        d4, d5, d6, d7 = A[j + 4, k2], A[j + 5, k2], A[j + 6, k2], A[j + 7, k2]
        z = X[k2]
        for i in range(n):
            xi = x[i]
            zi = z[i]
            o0[i] = (o0[i] + xi * c0) + zi * d0
            o1[i] = (o1[i] + xi * c1) + zi * d1
            o2[i] = (o2[i] + xi * c2) + zi * d2
            o3[i] = (o3[i] + xi * c3) + zi * d3
            o4[i] = (o4[i] + xi * c4) + zi * d4
            o5[i] = (o5[i] + xi * c5) + zi * d5
            o6[i] = (o6[i] + xi * c6) + zi * d6
            o7[i] = (o7[i] + xi * c7) + zi * d7
        k = _next8(A, j, k2 + 1)


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def _block4(A, X, out, j):  # pragma: no cover - compiled
    """:func:`_block8` for rows ``j … j+3``."""
    nk, n = A.shape[1], X.shape[1]
    o0, o1, o2, o3 = out[j], out[j + 1], out[j + 2], out[j + 3]
    k = _next4(A, j, 0)
    while k < nk:
        c0, c1, c2, c3 = A[j, k], A[j + 1, k], A[j + 2, k], A[j + 3, k]
        x = X[k]
        k2 = _next4(A, j, k + 1)
        if k2 == nk:
            for i in range(n):
                xi = x[i]
                o0[i] += xi * c0
                o1[i] += xi * c1
                o2[i] += xi * c2
                o3[i] += xi * c3
            return
        d0, d1, d2, d3 = A[j, k2], A[j + 1, k2], A[j + 2, k2], A[j + 3, k2]
        z = X[k2]
        for i in range(n):
            xi = x[i]
            zi = z[i]
            o0[i] = (o0[i] + xi * c0) + zi * d0
            o1[i] = (o1[i] + xi * c1) + zi * d1
            o2[i] = (o2[i] + xi * c2) + zi * d2
            o3[i] = (o3[i] + xi * c3) + zi * d3
        k = _next4(A, j, k2 + 1)


@nb.njit(inline="always", error_model="numpy", _nrt=False)
def _block1(A, X, out, j):  # pragma: no cover - compiled
    """:func:`_block8` for row ``j``."""
    nk, n = A.shape[1], X.shape[1]
    o = out[j]
    k = _next1(A, j, 0)
    while k < nk:
        c = A[j, k]
        x = X[k]
        k2 = _next1(A, j, k + 1)
        if k2 == nk:
            for i in range(n):
                o[i] += x[i] * c
            return
        d = A[j, k2]
        z = X[k2]
        for i in range(n):
            o[i] = (o[i] + x[i] * c) + z[i] * d
        k = _next1(A, j, k2 + 1)


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def accumulate_rows(A, X, out):  # pragma: no cover - compiled
    """``out = A @ X`` (``X`` (nk, N) with the rows of the batch in its inner dimension): each
    sum over k in order from +0 as NumPy's element-wise steps round, skipping the exact zeros
    of ``A`` where a whole block's are zero (adding such a term, ±0 for a finite X, changes
    nothing, so the results are those of skipping every zero term): eight outputs at a time
    (then four, then one) share every pass over the rows of ``X``, and each pass adds the
    block's next two terms, one after the other (an output is loaded and stored once per
    two terms; the same sums, term by term)."""
    nj = A.shape[0]
    for j in range(nj):
        o = out[j]
        for i in range(X.shape[1]):
            o[i] = 0.0
    j = 0
    while j + 8 <= nj:
        _block8(A, X, out, j)
        j += 8
    while j + 4 <= nj:
        _block4(A, X, out, j)
        j += 4
    while j < nj:
        _block1(A, X, out, j)
        j += 1


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def lqg_command(obs, src, scale, K, W, S):  # pragma: no cover - compiled
    """The first half of :func:`lqg_step`: the live measurements of ``obs`` into ``W``
    (``y_m = obs[i, src[m]]·scale[m]``, non-finite → 0) and ``S = K·[z; y; q]``, the
    command before its gain ``−a`` and clip."""
    n = W.shape[0] - src.shape[0] - 2 * K.shape[0]
    n_rows = obs.shape[0]
    for m in range(src.shape[0]):
        c = src[m]
        s = scale[m]
        y = W[n + m]
        for i in range(n_rows):
            v = np.float64(obs[i, c]) * s
            y[i] = v if math.isfinite(v) else 0.0
    accumulate_rows(K, W[: W.shape[0] - K.shape[0]], S)


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def lqg_update(F, scal, W, Z, S, out, col0):  # pragma: no cover - compiled
    """The second half of :func:`lqg_step`: the clipped command ``u = clip(−a·S)`` out and
    into ``W``, the integrator and the estimator's time update."""
    n = F.shape[0]
    nu = S.shape[0]
    nl = W.shape[0] - n - 2 * nu
    a, lo, hi, dt, qmax = scal[0], scal[1], scal[2], scal[3], scal[4]
    n_rows = S.shape[1]
    q0 = n + nl
    u0 = q0 + nu
    for b in range(nu):
        sb = S[b]
        qb = W[q0 + b]
        yb = W[n + b]
        ub = W[u0 + b]
        for i in range(n_rows):
            u = -a * sb[i]
            u = lo if u < lo else u
            u = hi if u > hi else u
            out[i, col0 + b] = u
            ub[i] = u / a
            q = qb[i] + dt * yb[i]
            q = -qmax if q < -qmax else q
            q = qmax if q > qmax else q
            qb[i] = q
    accumulate_rows(F, W, Z)
    for j in range(n):
        w = W[j]
        z = Z[j]
        for i in range(n_rows):
            w[i] = z[i]


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def lqg_step(obs, src, scale, K, F, scal, W, Z, S, out, col0):  # pragma: no cover - compiled
    """One step of one plane's LQG (:class:`_PlaneLQG`) for every row i of ``obs``
    (N, obs_size), in the estimator coordinates ``z``. The states are stored transposed, the
    rows of the batch in the inner dimension, so that every product runs over the rows in its
    inner loop (vectorised, :func:`accumulate_rows`): ``W`` (n + nl + 2·NU, N) holds
    ``[z; y; q; u/a]`` — the estimator state, the nl live measurements ``y_m = obs[i, src[m]]
    · scale[m]`` (non-finite → 0; the first NU are the gaps), the gap integrator and the
    command sent, in A. With ``scal = (a_per_A, lo, hi, dt, qmax)``:

        u = clip(−a·K·[z; y; q], lo, hi)      (out[i, col0 + b] = u_b)
        q ← clip(q + dt·y_gaps, ±qmax)
        z ← F·[z; y; ·; u/a]                   (F's q columns are 0)

    ``Z`` (n, N) and ``S`` (NU, N) are scratch. Two halves, :func:`lqg_command` and
    :func:`lqg_update` (a controller can change the command in between)."""
    lqg_command(obs, src, scale, K, W, S)
    lqg_update(F, scal, W, Z, S, out, col0)


_STEP_ENTRIES: dict[np.dtype, Any] = {}
""":func:`lqg_step` by the observation's dtype (:func:`lqg_step_entry`)."""


def lqg_step_entry(dt: np.dtype) -> Any:
    """:func:`lqg_step` for observations of dtype ``dt`` (float32 or float64, two dimensions,
    any layout) and a plane's own arrays (:class:`_PlaneLQG`: C-contiguous), called without
    numba's type dispatch (:mod:`hyperloop_env.physics.entry`)."""
    f = _STEP_ENTRIES.get(dt)
    if f is None:
        i1, f1, f2 = nb.int64[::1], nb.float64[::1], nb.float64[:, ::1]
        f = compiled_entry(
            lqg_step, strided(dt, 2), i1, f1, f2, f2, f1, f2, f2, f2, nb.float32[:, ::1], nb.int64
        )
        _STEP_ENTRIES[dt] = f
    return f


class _PlaneLQG:
    """The running LQG of one plane: measurement update, clamped integrator, saturated
    command, time update (module docstring), for a batch of independent vehicles.

    The law, with ``x`` the predicted state x̂⁻ (n,), ``y`` the measurements (gaps [m],
    currents [A], acceleration [m/s²], non-finite → 0; the pseudo-measurements are 0), ``q``
    the gap integrator and ``a = a_per_A`` (action per A)::

        x_u = x + M·(y − C·x)                          measurement update
        u   = clip(−a·(K_x·x_u + K_q·q), lo, hi)        command (action units)
        q  ← clip(q + dt·y_gaps, ±qmax)
        x  ← Φ·x_u + Γ·u/a                              time update, the command sent

    is run in an equivalent realisation that costs half the arithmetic: with
    ``A₁ = Φ·(I − M·C)`` in real Schur form ``A₁ = V·T·Vᵀ`` (V orthogonal, T
    quasi-upper-triangular) and ``x = V·z``::

        u  = clip(−a·(K_x(I − MC)V·z + K_x·M·y + K_q·q), lo, hi)
        z ← T·z + Vᵀ·Φ·M·y + Vᵀ·Γ·u/a

    — the same map up to rounding (an orthogonal change of coordinates; the zero
    pseudo-measurements drop out), one compiled call per step (:func:`lqg_step`).
    ``src``/``scale``: where the measurements are in the observation and their units
    (``src < 0``: a pseudo-measurement)."""

    def __init__(
        self,
        m: LQGMatrices,
        a_per_A: float,
        lo: float,
        hi: float,
        dt: float,
        q_scale_A: float,
        src: np.ndarray,
        scale: np.ndarray,
    ) -> None:
        n = m.Phi.shape[0]
        self.n = n
        self.Phi, self.Gam, self.C, self.M = m.Phi, m.Gam, m.C, m.M
        self.Kx = np.ascontiguousarray(m.K[:, :n])
        self.Kq = np.ascontiguousarray(m.K[:, n:])
        self.a_per_A = a_per_A
        self.lo, self.hi, self.dt = lo, hi, dt
        self.qmax = q_scale_A / max(1e-12, float(np.abs(self.Kq).max()))
        src = np.asarray(src, dtype=np.int64)
        self.src, self.scale = src, np.asarray(scale, dtype=np.float64)  # all measurements
        live = np.flatnonzero(src >= 0)
        if not np.array_equal(live[:NU], np.arange(NU)):
            raise ValueError("the first four measurements must be the gaps (the integrator's)")
        nl = live.size
        imc = np.eye(n) - m.M @ m.C
        T, V = schur(m.Phi @ imc, output="real")
        self.V = V  # x = V·z
        F = np.zeros((n, n + nl + 2 * NU))
        F[:, :n] = T
        F[:, n : n + nl] = V.T @ (m.Phi @ m.M[:, live])
        F[:, n + nl + NU :] = V.T @ m.Gam
        K = np.hstack([self.Kx @ imc @ V, (self.Kx @ m.M)[:, live], self.Kq])
        self._nl = nl
        self._const = (
            aligned_copy(src[live]),
            aligned_copy(np.asarray(scale, dtype=np.float64)[live]),
            aligned_copy(K),
            aligned_copy(F),
            np.array([a_per_A, lo, hi, dt, self.qmax], dtype=np.float64),
        )  # lqg_step's constant arguments (on cache lines: hyperloop_env.physics.arrays)
        self._batch = self._new_state(0)  # (W, Z, S) of act_batch, sized by reset_batch
        self._single = self._new_state(1)  # of the single-vehicle act

    def _new_state(self, n_rows: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        rows = self.n + self._nl + 2 * NU
        return (
            aligned_zeros((rows, n_rows)),
            aligned_zeros((self.n, n_rows)),
            aligned_zeros((NU, n_rows)),
        )

    def reset(self) -> None:
        """Zero the single-vehicle state."""
        self._single[0][:] = 0.0

    def reset_batch(self, mask: np.ndarray) -> None:
        """Zero the batch rows where ``mask`` is True (a new size starts a fresh batch)."""
        m = np.asarray(mask, dtype=bool)
        if m.shape[0] != self._batch[0].shape[1]:
            self._batch = self._new_state(m.shape[0])
            return
        self._batch[0][:, m] = 0.0

    def step(self, obs: np.ndarray, out: np.ndarray, col0: int, single: bool = False) -> None:
        """One step for the rows of ``obs`` (N, obs_size): the commands go to
        ``out[:, col0:col0 + NU]``; ``single``: the single-vehicle state (N = 1)."""
        W, Z, S = self._single if single else self._batch
        lqg_step(obs, *self._const, W, Z, S, out, col0)

    def estimate(self, single: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """The predicted state x̂⁻ (N, n) in the design model's coordinates and the gap
        integrator q (N, NU) [m·s], per row of the batch (or of the single vehicle)."""
        W = (self._single if single else self._batch)[0]
        q0 = self.n + self._nl
        return (self.V @ W[: self.n]).T, W[q0 : q0 + NU].T.copy()


def _measurement_map(
    n_meas: int,
    gap0: int,
    gap_scale: float,
    cur0: int | None,
    cur_scale: float,
    acc: int,
    acc_scale: float,
) -> tuple[np.ndarray, np.ndarray]:
    """(src, scale) of a plane's measurements: the gaps, the currents (if modelled), the
    acceleration, then pseudo-measurements (0)."""
    src = np.full(n_meas, -1, dtype=np.int64)
    scale = np.zeros(n_meas)
    src[0:NU], scale[0:NU] = np.arange(gap0, gap0 + NU), gap_scale
    k = NU
    if cur0 is not None:
        src[NU : 2 * NU], scale[NU : 2 * NU] = np.arange(cur0, cur0 + NU), cur_scale
        k = 2 * NU
    src[k], scale[k] = acc, acc_scale
    return src, scale


class LQRController(BaseController):
    """Observer-based LQR (LQG) on the measured gaps, coil currents and heave
    acceleration (see the module docstring); :meth:`act` and :meth:`act_batch` run the same
    compiled law (:class:`_PlaneLQG`), the first on a batch of one."""

    name = "lqr"

    def __init__(
        self,
        env_or_params: Any = None,
        design: LQRDesign | None = None,
        action_scale: float | None = None,
        lateral_design: LateralLQRDesign | None = None,
    ) -> None:
        self.ctx = control_context(env_or_params, action_scale)
        self.design = design if design is not None else LQRDesign()
        m = design_lqg(self.ctx, self.design)
        self.matrices = m
        ctx = self.ctx
        spec = ctx.observation
        self._obs_size = spec.size
        self._lev = ctx.actuators.slice("levitation")
        self._n_act = ctx.n_actions
        self.lateral: _PlaneLQG | None = None
        if "guidance" in ctx.actuators.kinds:
            ml = design_lateral_lqg(ctx, lateral_design)
            self.lateral_matrices = ml
            ig0 = ctx.guidance_bias_A
            dmax = min(ig0, ctx.params.guidance.max_current_A - ig0)
            ga = 1.0 / (ig0 * ctx.action_scale)
            lim = min(1.0, dmax * ga)
            src, scale = _measurement_map(
                ml.C.shape[0],
                spec.start("lateral"),
                ctx.params.guidance.clearance_m,
                spec.start("current_guidance") if ml.has_coil_states else None,
                ig0,
                spec.start("acc") + 1,
                ctx.gravity_m_s2,
            )
            self.lateral = _PlaneLQG(ml, ga, -lim, lim, ctx.dt_s, dmax, src, scale)
            self._guid = ctx.actuators.slice("guidance")
        src, scale = _measurement_map(
            m.C.shape[0],
            spec.start("gap"),
            ctx.clearance_m,
            spec.start("current") if m.has_coil_states else None,
            ctx.nominal_current_A,
            spec.start("acc"),
            ctx.gravity_m_s2,
        )
        lo, hi = ctx.action_limits()
        # integrator clamp: Kq·q alone within ±(the full current range)
        self.vertical = _PlaneLQG(
            m,
            1.0 / (ctx.nominal_current_A * ctx.action_scale),
            lo,
            hi,
            ctx.dt_s,
            ctx.nominal_current_A * ctx.action_scale,
            src,
            scale,
        )
        self._planes: tuple[tuple[_PlaneLQG, int], ...] = ((self.vertical, self._lev.start),)
        if self.lateral is not None:
            self._planes += ((self.lateral, self._guid.start),)
        self.reset()

    def _obs2d(self, obs: np.ndarray, ndim: int) -> np.ndarray:
        o = np.asarray(obs)
        dt = o.dtype
        if not is_float(dt):
            o = o.astype(np.float64)
        if o.ndim != ndim or o.shape[-1] != self._obs_size:
            want = f"(N, {self._obs_size})" if ndim == 2 else f"({self._obs_size},)"
            raise ValueError(f"obs must have shape {want}, got {o.shape}")
        return o

    def reset_batch(self, mask: np.ndarray) -> None:
        """Reset the estimator/integrator states of the rows where ``mask`` is True (the
        state of :meth:`act_batch`; a new mask size starts a fresh batch)."""
        for p, _ in self._planes:
            p.reset_batch(mask)

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        """Actions for N independent vehicles, ``(N, obs_size) -> (N, n_act)`` float32 (other
        actuators at their bias, 0), compiled (:func:`lqg_step`)."""
        o = self._obs2d(obs, 2)
        n = o.shape[0]
        if self.vertical._batch[0].shape[1] != n:
            self.reset_batch(np.ones(n, dtype=bool))
        out = np.zeros((n, self._n_act), dtype=np.float32)
        dt = o.dtype
        step = _STEP_ENTRIES.get(FLOAT32 if dt is FLOAT32 else dt) or lqg_step_entry(dt)
        for p, col0 in self._planes:
            step(o, *p._const, *p._batch, out, col0)  # = p.step(o, out, col0)
        return out

    def reset(self, seed: int | None = None) -> None:
        for p, _ in self._planes:
            p.reset()

    def act(self, obs: np.ndarray) -> np.ndarray:
        """The action for one vehicle, ``(obs_size,) -> (n_act,)`` float32: row 0 of the
        batched law on a batch of one (its own state, apart from :meth:`act_batch`'s)."""
        o = self._obs2d(obs, 1)[None, :]
        out = np.zeros((1, self._n_act), dtype=np.float32)
        for p, col0 in self._planes:
            p.step(o, out, col0, single=True)
        return out[0]
