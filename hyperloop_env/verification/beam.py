"""Guideway beam cases: natural frequencies, the static modal series and the dynamic
amplification of a moving constant force.

``beam_frequency`` integrates the compiled :func:`~hyperloop_env.physics.vehicle.rhs`;
``static_midspan_deflection`` and ``moving_force_daf`` check the project's modal equations
(re-implemented here) against the closed forms of :mod:`hyperloop_env.verification.reference`.
The production-path guideway cases are in :mod:`hyperloop_env.verification.guideway`.
"""

from __future__ import annotations

import math
from typing import Any

import numba as nb
import numpy as np

from hyperloop_env.physics.guideway import footprint_weights, mode_shape
from hyperloop_env.physics.layout import (
    BEAM0,
    P_F0,
    P_I0,
    P_MODALMASS,
    P_NMODES,
    P_OMEGA1Y,
    P_SPAN,
    P_ZETA,
    beam_index,
    state_size,
)
from hyperloop_env.physics.model import pack
from hyperloop_env.physics.params import ModelParams
from hyperloop_env.verification.common import CaseResult, ConstantCurrentRhs, compare
from hyperloop_env.verification.reference import (
    beam_frequency_closed_form_hz,
    fe_beam_frequencies_hz,
    fryba_daf,
)

BEAM_MODES = (1, 2, 3)
DAF_ALPHAS = (0.25, 0.5, 0.75, 1.0)
# Approximate DAF values quoted in docs/model.md (Frýba; Olsson 1991), used only
# to sanity-check the analytical series.
DAF_LITERATURE = {0.25: 1.26, 0.5: 1.70, 0.75: 1.70, 1.0: 1.55}
DAF_LITERATURE_TOL = 0.03  # the quoted values are read off curves to ~2 digits


# ---------------------------------------------------------------------------------------
# beam natural frequencies
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
    f = ConstantCurrentRhs(P, np.zeros((3, 16)), spans, float(P[P_I0]))
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
    fd = ConstantCurrentRhs(Pd, np.zeros((3, 16)), spans, float(Pd[P_I0]))
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
    return compare(
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
# ---------------------------------------------------------------------------------------
# static midspan deflection
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
    return compare(
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
# ---------------------------------------------------------------------------------------
# moving constant force: dynamic amplification
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
    return compare(
        f"moving_force_daf_alpha_{alpha}",
        f"constant force crossing one span at alpha = v/(2 f1 L) = {alpha}: max midspan "
        f"deflection (crossing + 3 periods after) / (PL^3/48EI), project modal equations "
        f"({nm} modes, undamped, RK4) vs Fryba's analytical series (101 modes)",
        overall,
        ref,
        2e-2,
        info=info,
    )
