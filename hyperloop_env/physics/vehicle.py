"""Equations of motion of the capsule, the four magnet units and the guideway (compiled).

Bodies (paper eq. 7–10, written out in docs/model.md; signs in
:mod:`hyperloop_env.physics.params`). Coordinates are displacements from static
equilibrium on a straight, level, rigid guideway, so gravity enters only through the
static preloads and the deviation g_eff − g in curves.

Unit a (mass m_u = m_m/4) at (x_a, z_a⁰) = (±d1/2, ∓d2/2) from the capsule's geometric
centre, whose centre of gravity sits at (x_g, z_g) (0 unless a payload is off-centre); the
capsule coordinates are those of its centre of gravity::

    corner of the capsule above it   Y_a = y_c + (x_a − x_g)·θ − (z_a⁰ − z_g)·φ,
                                     Z_a = z_c + (x_a − x_g)·ψ
    primary (on the capsule, +y)     P_a = P_a⁰ + K_h/4·(y_a − Y_a) + C_h/4·(ẏ_a − Ẏ_a)
                                     (P_a⁰: the corner's static load, m_v g/4 when centred)
    secondary (on the capsule, +z)   G_a = K_z/4·(z_a − Z_a) + c_z/4·(ż_a − Ż_a)
    m_u ÿ_a = F_y,a − P_a − m_u·g_eff(x_a)
    m_u z̈_a = F_z,a − G_a + m_u·a_lat(x_a)

Capsule (mass m_v; inertias I_pitch, I_roll, I_yaw)::

    m_v ÿ_c = Σ P_a − m_v·g_eff(x_c)           I_pitch θ̈ = Σ (x_a − x_g)·P_a
    I_roll φ̈ = Σ −(z_a⁰ − z_g)·P_a              m_v z̈_c = Σ G_a + m_v·a_lat(x_c)
    I_yaw ψ̈ = Σ (x_a − x_g)·G_a

(m_v includes a payload). The vehicle moves along the track at x_c(t) = x_0 + v_0·t +
a·t²/2 with speed v(t) = v_0 + a·t (a = 0 unless a speed profile is given); the curve loads
use v(t).

The suspension acts at the capsule's centre height (no roll–lateral coupling) and the
gyroscopic products of eq. 8 (second order in the small rates) are neglected.

Magnet gap and lateral offset (eq. 6 with deflection and irregularity)::

    s_a = σ·(y_a − w(x_a) − r_side(x_a)),   z_rel,a = z_a − w_z(x_a) − r_lat(x_a)

Lateral magnet forces on unit a (:mod:`hyperloop_env.physics.magnets`): the levitation
magnet's edge force F_z,a(I_a, s_a, z_rel,a) and the guidance pair's force
F_g,a(ΔI_a, z_rel,a); ``F_z,a`` in the equations above is their sum.

Guideway: two span slots (the spans under the vehicle), each with n modes in the
vertical and the lateral plane, loaded by −F_y,a and −(F_z,a + F_g,a) over the magnet
footprint (Newton's third law; see :mod:`hyperloop_env.physics.guideway`).

Currents: ``i_start`` / ``i_cmd`` are full command vectors (``actuators.command_slices()``):
``N_UNITS`` channels per registered actuator kind, the levitation coil currents first, then
the guidance pairs' differential currents, then any registered kind's; each follows the
first-order coil lag of :func:`coil_current`.

Force laws (``layout.FORCE_LAWS``, an actuator kind's ``force_law``): the built-in kinds'
laws — the levitation magnet (:func:`~hyperloop_env.physics.magnets.magnet_forces_from`,
F_y and the edge force F_z) and the guidance pair
(:func:`~hyperloop_env.physics.magnets.guidance_force`, lateral, bias = the kind's
reference current) — are written out in :func:`rhs_loaded`; a registered kind's force on
unit a comes from :func:`kind_force` (the same laws, selected by the kind's law id, with
the kind's own current and reference), added to the unit's vertical and lateral forces and,
opposite, to the guideway's. A new law is one more branch of :func:`kind_force` and one
more id in ``layout.FORCE_LAWS``.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from hyperloop_env.physics.guideway import footprint_angles, footprint_fill
from hyperloop_env.physics.irregularity import ROW_LATERAL, sample
from hyperloop_env.physics.layout import (
    BEAM0,
    CMD_GUID,
    CMD_LEV,
    K_LAW,
    K_REF,
    KIND_STRIDE,
    LAW_GUIDANCE,
    LAW_LEVITATION,
    N_BUILTIN_KINDS,
    NQ,
    P_A2,
    P_ACCEL,
    P_AG,
    P_B2,
    P_CANT,
    P_CP,
    P_CS,
    P_CURVE0,
    P_D1H,
    P_D2H,
    P_DELTA0,
    P_DELTAG0,
    P_FPREU,
    P_G,
    P_IG0,
    P_IPITCH,
    P_IROLL,
    P_IRRDX,
    P_IYAW,
    P_KAPPA,
    P_KINDS,
    P_KMAG,
    P_KMAGG,
    P_KP,
    P_KS,
    P_MC,
    P_MODALMASS,
    P_MU,
    P_NMODES,
    P_OMEGA1Y,
    P_OMEGA1Z,
    P_RIGID,
    P_SIGMA,
    P_SPAN,
    P_SPEED,
    P_TAU,
    P_TRANS,
    P_XCG,
    P_XSTART,
    P_ZCG,
    P_ZETA,
    Q_HEAVE,
    Q_LAT,
    Q_PITCH,
    Q_ROLL,
    Q_UY,
    Q_UZ,
    Q_YAW,
)
from hyperloop_env.physics.magnets import guidance_force, magnet_forces_from
from hyperloop_env.physics.track import curve_loads
from hyperloop_env.physics.units import N_UNITS

N_SETS_UNITS = N_UNITS // 2  # units per levitation set (left and right)

# rows of the per-unit output block written by rhs()
U_GAP = 0
U_LAT = 1
U_W = 2
U_WZ = 3
U_FY = 4
U_FZ = 5
U_I = 6
U_FG = 7  # guidance pair lateral force
U_IG = 8  # guidance differential current
U_EU = 9  # scratch: z_rel/δ0
U_EATAN = 10  # scratch: arctan(z_rel/δ0)
U_ELOG = 11  # scratch: ln(1 + (z_rel/δ0)²)
NU = 12


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def unit_offsets(a: int, d1h: float, d2h: float) -> tuple[float, float]:
    """(x_a, z_a⁰) of unit a ∈ {0: FL, 1: FR, 2: RL, 3: RR} relative to the capsule centre
    (even units on the left, the first levitation set in front)."""
    xo = d1h if a < N_SETS_UNITS else -d1h
    zo = -d2h if a % 2 == 0 else d2h
    return xo, zo


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def coil_current(t: float, t0: float, i_start: float, i_cmd: float, tau: float) -> float:
    """First-order coil lag I(t) = I_cmd + (I_start − I_cmd)·exp(−(t − t0)/τ) [A], exact
    within a control step (I_cmd held); τ = 0 is an ideal current source."""
    if tau <= 0.0:
        return i_cmd
    return i_cmd + (i_start - i_cmd) * math.exp(-(t - t0) / tau)


# ---- stage loads: what the right-hand side needs that depends on time only ---------------
# The integrator evaluates the right-hand side at a few times per substep (RK4: t, t + h/2
# twice, t + h) and the end of one substep is, mostly bit for bit, the start of the next.
# Everything that depends on the time but not on the state — the footprint weights (the
# cosines), the profile samples, the curve loads and the coil currents at the units'
# positions — is computed once per distinct time into a "stage loads" block ``tl``
# (float64[stage_loads_size(n_modes)]) by :func:`stage_positions` and
# :func:`stage_currents`; :func:`rhs_loaded` then does the state-dependent part.
# :func:`rhs` is the two in sequence: the same arithmetic in the same order, so the cached
# evaluation is bit-identical to calling rhs at every stage.
#
# The two units of a levitation set sit at the same x (unit_offsets), so they share the
# footprint weights, the lateral profile sample, the curve loads and the deflection under
# them: those are stored once per set.
N_SETS = N_UNITS // N_SETS_UNITS  # levitation sets (front, rear)
TL_HIT = 0  # N_SETS x 2 flags: 1.0 if the footprint of set st touches span slot sl
TL_UNIT = TL_HIT + N_SETS * 2  # per unit a: TL_UNIT + a * TL_PER_UNIT + TL_R*
TL_RY = 0  # vertical profile under the unit (its side's row) [m]
TL_RZ = 1  # lateral profile under the unit [m]
TL_ALAT = 2  # lateral curve load at the unit [m/s²]
TL_GEFF = 3  # effective gravity at the unit [m/s²]
TL_PER_UNIT = 4
TL_C = TL_UNIT + N_UNITS * TL_PER_UNIT  # (a_lat, g_eff) at the capsule centre
TL_COS = TL_C + 2  # scratch: cos θ1, cos θ2 of the footprint of set st in slot sl
TL_W = TL_COS + N_SETS * 2 * 2  # footprint weights: TL_W + (st * 2 + sl) * n_modes + k
# then the n_commands currents at the stage time [A], at stage_currents_start(P)


def stage_loads_size(n_modes: int, n_commands: int) -> int:
    """Length of one stage loads block for ``n_modes`` modes per span and plane and a full
    command vector of ``n_commands`` channels."""
    return TL_W + N_SETS * 2 * n_modes + n_commands


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def stage_currents_start(P: np.ndarray) -> int:
    """Index in a stage loads block of the first coil current (after the weights)."""
    return TL_W + N_SETS * 2 * int(P[P_NMODES])


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def kind_force(
    law: int,
    cur: float,
    ref: float,
    s: float,
    zrel: float,
    eatan: float,
    elog: float,
    P: np.ndarray,
) -> tuple[float, float]:
    """(F_y, F_z) [N] on a unit from a registered actuator kind with force law ``law``
    (``layout.FORCE_LAWS``), current ``cur`` [A] and reference ``ref`` [A], at gap excursion
    ``s`` and lateral offset ``zrel`` [m] (``eatan``, ``elog``: arctan and ln(1 + u²) of
    u = zrel/δ0). ``levitation``: a levitation magnet of the unit's geometry carrying
    ``cur``; ``guidance``: a guidance pair of the unit's geometry at bias ``ref`` with
    differential current ``cur``. An unknown law gives NaN (the run then ends in contact)."""
    if law == LAW_LEVITATION:
        return magnet_forces_from(
            cur, s, zrel, eatan, elog, P[P_KMAG], P[P_A2], P[P_B2], P[P_DELTA0], P[P_SIGMA]
        )
    if law == LAW_GUIDANCE:
        return 0.0, guidance_force(ref, cur, zrel, P[P_KMAGG], P[P_AG], P[P_DELTAG0], P[P_SIGMA])
    return math.nan, math.nan


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def stage_positions(
    t: float, P: np.ndarray, irr: np.ndarray, spans: np.ndarray, tl: np.ndarray, row: int
) -> None:
    """Fill the position-dependent part of the stage loads block ``tl[row]`` at time t:
    footprint weights of each set in each span slot, profile samples and curve loads."""
    nm = int(P[P_NMODES])
    acc = P[P_ACCEL]
    v = P[P_SPEED] + acc * t  # speed v(t) = v0 + a·t
    g = P[P_G]
    d1h = P[P_D1H]
    d2h = P[P_D2H]
    half = 0.5 * P[P_A2]
    span = P[P_SPAN]
    dx = P[P_IRRDX]
    kappa = P[P_KAPPA]
    cant = P[P_CANT]
    x0c = P[P_CURVE0]
    ltr = P[P_TRANS]
    rigid = P[P_RIGID] > 0.5
    xc = P[P_XSTART] + P[P_SPEED] * t + 0.5 * acc * t * t
    if not rigid:
        # footprint_weights_into of each set and slot, in phases: the angles, then the
        # cosines (independent calls the CPU overlaps), then the recurrences
        for st in range(N_SETS):
            xo, _ = unit_offsets(st * N_SETS_UNITS, d1h, d2h)
            for sl in range(2):
                c = st * 2 + sl
                hit, th1, th2 = footprint_angles(xc + xo, half, spans[sl] * span, span)
                tl[row, TL_HIT + c] = 1.0 if hit else 0.0
                tl[row, TL_COS + 2 * c] = th1
                tl[row, TL_COS + 2 * c + 1] = th2
        for c in range(N_SETS * 2):
            if tl[row, TL_HIT + c] > 0.5:
                tl[row, TL_COS + 2 * c] = math.cos(tl[row, TL_COS + 2 * c])
                tl[row, TL_COS + 2 * c + 1] = math.cos(tl[row, TL_COS + 2 * c + 1])
        for c in range(N_SETS * 2):
            wb = TL_W + c * nm
            if tl[row, TL_HIT + c] > 0.5:
                c1 = tl[row, TL_COS + 2 * c]
                c2 = tl[row, TL_COS + 2 * c + 1]
                footprint_fill(c1, c2, half, span, tl, row, wb, nm)
            else:
                for k in range(nm):
                    tl[row, wb + k] = 0.0
    for st in range(N_SETS):
        a0 = st * N_SETS_UNITS
        xo, _ = unit_offsets(a0, d1h, d2h)
        xa = xc + xo
        rz = sample(irr, ROW_LATERAL, xa, dx)
        _, alat_a, geff_a = curve_loads(xa, v, kappa, cant, x0c, ltr, g)
        for a in range(a0, a0 + N_SETS_UNITS):
            ub = TL_UNIT + a * TL_PER_UNIT
            tl[row, ub + TL_RY] = sample(irr, a % 2, xa, dx)
            tl[row, ub + TL_RZ] = rz
            tl[row, ub + TL_ALAT] = alat_a
            tl[row, ub + TL_GEFF] = geff_a
    _, alat_c, geff_c = curve_loads(xc, v, kappa, cant, x0c, ltr, g)
    tl[row, TL_C] = alat_c
    tl[row, TL_C + 1] = geff_c


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def stage_currents(
    t: float,
    t0: float,
    i_start: np.ndarray,
    i_cmd: np.ndarray,
    P: np.ndarray,
    tl: np.ndarray,
    row: int,
) -> None:
    """Fill the coil currents of the stage loads block ``tl[row]`` at time t
    (:func:`coil_current` of every command channel)."""
    tau = P[P_TAU]
    tc = stage_currents_start(P)
    for c in range(i_start.shape[0]):
        tl[row, tc + c] = coil_current(t, t0, i_start[c], i_cmd[c], tau)


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def rhs_loaded(
    y: np.ndarray, P: np.ndarray, tl: np.ndarray, row: int, dydt: np.ndarray, uo: np.ndarray
) -> None:
    """dy/dt for the state y with the stage loads block ``tl[row]`` of its time (see
    :func:`rhs`); writes the per-unit outputs to ``uo`` (float64[NU, N_UNITS]).

    Deliberately one long function: it is the numba-compiled right-hand side evaluated at
    every RK4 stage, and splitting it into helpers would add calls and state passing in the
    hot loop and could change the floating-point evaluation order (bit-identity)."""
    nm = int(P[P_NMODES])
    d1h = P[P_D1H]
    d2h = P[P_D2H]
    sigma = P[P_SIGMA]
    mu = P[P_MU]
    mc = P[P_MC]
    kp = P[P_KP]
    cp = P[P_CP]
    ks = P[P_KS]
    cs = P[P_CS]
    xcg = P[P_XCG]
    zcg = P[P_ZCG]
    rigid = P[P_RIGID] > 0.5
    ig0 = P[P_IG0]
    kmag = P[P_KMAG]
    a2 = P[P_A2]
    b2 = P[P_B2]
    delta0 = P[P_DELTA0]
    kmg = P[P_KMAGG]
    area_g = P[P_AG]
    gap_g = P[P_DELTAG0]
    tc = TL_W + N_SETS * 2 * nm  # stage_currents_start
    n_kinds = (P.shape[0] - P_KINDS) // KIND_STRIDE

    for i in range(NQ):
        dydt[i] = y[NQ + i]

    # guideway: free vibration part; magnet loads are added below
    if not rigid:
        mm = P[P_MODALMASS]
        m2zeta = -2.0 * P[P_ZETA]
        for sl in range(2):
            for plane in range(2):
                w1 = P[P_OMEGA1Y] if plane == 0 else P[P_OMEGA1Z]
                base = BEAM0 + (sl * 2 + plane) * 2 * nm  # beam_index(sl, plane, 0, 0)
                for k in range(nm):
                    wk = w1 * (k + 1) * (k + 1)
                    q = y[base + k]
                    qd = y[base + nm + k]
                    dydt[base + k] = qd
                    dydt[base + nm + k] = m2zeta * wk * qd - wk * wk * q
    else:
        mm = 1.0
        for i in range(BEAM0, y.shape[0]):
            dydt[i] = 0.0

    # guideway deflection under the footprint of each set (vertical, lateral)
    w_front = 0.0
    wz_front = 0.0
    w_rear = 0.0
    wz_rear = 0.0
    if not rigid:
        for st in range(N_SETS):
            w = 0.0
            wz = 0.0
            for sl in range(2):
                if tl[row, TL_HIT + st * 2 + sl] > 0.5:
                    wb = TL_W + (st * 2 + sl) * nm
                    by = BEAM0 + (sl * 2) * 2 * nm
                    bz = BEAM0 + (sl * 2 + 1) * 2 * nm
                    for k in range(nm):
                        w += y[by + k] * tl[row, wb + k]
                        wz += y[bz + k] * tl[row, wb + k]
            if st == 0:
                w_front = w
                wz_front = wz
            else:
                w_rear = w
                wz_rear = wz

    # gap and lateral offset of every unit first, then the transcendental functions of the
    # edge force unit after unit (independent calls the CPU can overlap, where one unit's
    # whole chain at a time serialised them), then the rest: the same operations on the
    # same values as magnets.magnet_forces, only ordered differently
    for a in range(N_UNITS):
        st = 0 if a < N_SETS_UNITS else 1
        w = w_front if st == 0 else w_rear
        wz = wz_front if st == 0 else wz_rear
        ub = TL_UNIT + a * TL_PER_UNIT
        uo[U_GAP, a] = sigma * (y[Q_UY + a] - w - tl[row, ub + TL_RY])
        zrel = y[Q_UZ + a] - wz - tl[row, ub + TL_RZ]
        uo[U_LAT, a] = zrel
        uo[U_W, a] = w
        uo[U_WZ, a] = wz
        uo[U_EU, a] = zrel / delta0
    for a in range(N_UNITS):
        uo[U_EATAN, a] = math.atan(uo[U_EU, a])
    for a in range(N_UNITS):
        u = uo[U_EU, a]
        uo[U_ELOG, a] = math.log1p(u * u)

    sum_p = 0.0
    m_pitch = 0.0
    m_roll = 0.0
    sum_g = 0.0
    m_yaw = 0.0
    for a in range(N_UNITS):
        st = 0 if a < N_SETS_UNITS else 1
        xo, zo = unit_offsets(a, d1h, d2h)
        ub = TL_UNIT + a * TL_PER_UNIT
        s = uo[U_GAP, a]
        zrel = uo[U_LAT, a]
        cur = tl[row, tc + CMD_LEV + a]
        fy, fz = magnet_forces_from(
            cur, s, zrel, uo[U_EATAN, a], uo[U_ELOG, a], kmag, a2, b2, delta0, sigma
        )
        dig = tl[row, tc + CMD_GUID + a]
        fg = guidance_force(ig0, dig, zrel, kmg, area_g, gap_g, sigma)
        uo[U_FY, a] = fy
        uo[U_FZ, a] = fz
        uo[U_I, a] = cur
        uo[U_FG, a] = fg
        uo[U_IG, a] = dig
        fz = fz + fg  # total lateral magnet force on the unit
        for k in range(N_BUILTIN_KINDS, n_kinds):  # registered kinds (kind_force)
            kb = P_KINDS + k * KIND_STRIDE
            fyk, fzk = kind_force(
                int(P[kb + K_LAW]),
                tl[row, tc + k * N_UNITS + a],
                P[kb + K_REF],
                s,
                zrel,
                uo[U_EATAN, a],
                uo[U_ELOG, a],
                P,
            )
            fy = fy + fyk
            fz = fz + fzk

        # corner above the unit, relative to the capsule's centre of gravity
        xg = xo - xcg
        zg = zo - zcg
        corner_y = y[Q_HEAVE] + xg * y[Q_PITCH] - zg * y[Q_ROLL]
        corner_yd = y[NQ + Q_HEAVE] + xg * y[NQ + Q_PITCH] - zg * y[NQ + Q_ROLL]
        pa = P[P_FPREU + a] + kp * (y[Q_UY + a] - corner_y) + cp * (y[NQ + Q_UY + a] - corner_yd)
        corner_z = y[Q_LAT] + xg * y[Q_YAW]
        corner_zd = y[NQ + Q_LAT] + xg * y[NQ + Q_YAW]
        ga = ks * (y[Q_UZ + a] - corner_z) + cs * (y[NQ + Q_UZ + a] - corner_zd)
        dydt[NQ + Q_UY + a] = (fy - pa) / mu - tl[row, ub + TL_GEFF]
        dydt[NQ + Q_UZ + a] = (fz - ga) / mu + tl[row, ub + TL_ALAT]
        sum_p += pa
        m_pitch += xg * pa
        m_roll -= zg * pa
        sum_g += ga
        m_yaw += xg * ga

        if not rigid:
            # a slot the footprint misses has zero weights: its load terms are ±0 and
            # leave the rates unchanged, unless a force is not finite (then keep them so
            # the non-finite value propagates as it would)
            every = not (math.isfinite(fy) and math.isfinite(fz))
            for sl in range(2):
                if every or tl[row, TL_HIT + st * 2 + sl] > 0.5:
                    wb = TL_W + (st * 2 + sl) * nm
                    by = BEAM0 + (sl * 2) * 2 * nm + nm
                    bz = BEAM0 + (sl * 2 + 1) * 2 * nm + nm
                    for k in range(nm):
                        wk = tl[row, wb + k]
                        dydt[by + k] -= fy * wk / mm
                        dydt[bz + k] -= fz * wk / mm

    dydt[NQ + Q_HEAVE] = sum_p / mc - tl[row, TL_C + 1]
    dydt[NQ + Q_LAT] = sum_g / mc + tl[row, TL_C]
    dydt[NQ + Q_PITCH] = m_pitch / P[P_IPITCH]
    dydt[NQ + Q_ROLL] = m_roll / P[P_IROLL]
    dydt[NQ + Q_YAW] = m_yaw / P[P_IYAW]


@nb.njit(cache=True, error_model="numpy")
def rhs(
    t: float,
    y: np.ndarray,
    P: np.ndarray,
    irr: np.ndarray,
    t0: float,
    i_start: np.ndarray,
    i_cmd: np.ndarray,
    spans: np.ndarray,
    dydt: np.ndarray,
    wts: np.ndarray,
    uo: np.ndarray,
) -> None:
    """dy/dt at time t. ``spans`` (int64[2]) holds the span index of each slot; ``wts``
    (float64[N_UNITS, 2, n]) receives the footprint weights of each unit in each slot and
    ``uo`` (float64[NU, N_UNITS]) the per-unit outputs.

    :func:`stage_positions`, :func:`stage_currents` and :func:`rhs_loaded` in sequence (the
    integrator calls them itself to reuse the time-only part between stages)."""
    nm = int(P[P_NMODES])
    tl = np.zeros((1, TL_W + N_SETS * 2 * nm + i_start.shape[0]))  # stage_loads_size
    stage_positions(t, P, irr, spans, tl, 0)
    stage_currents(t, t0, i_start, i_cmd, P, tl, 0)
    rhs_loaded(y, P, tl, 0, dydt, uo)
    for a in range(N_UNITS):
        st = 0 if a < N_SETS_UNITS else 1
        for sl in range(2):
            wb = TL_W + (st * 2 + sl) * nm
            for k in range(nm):
                wts[a, sl, k] = tl[0, wb + k]
