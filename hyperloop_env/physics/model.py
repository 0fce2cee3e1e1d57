"""The simulator: fixed-step RK4 over one control interval, single and batched.

Use :class:`Simulator` for one vehicle and :class:`BatchSimulator` for N independent
vehicles advanced in one compiled, multi-threaded call. Both reset from a seed (which
draws the guideway irregularity) and advance by one control interval given the four
commanded coil currents [A] in the order FL, FR, RL, RR.

Currents: non-finite values raise ``ValueError``; finite values outside the physical range
are clipped to it: levitation currents to ``[0, MagnetParams.max_current_A]`` (force ∝ I²,
a negative current is not a different force), guidance differential currents to
``±min(I_g0, GuidanceParams.max_current_A − I_g0)`` (both coils of a pair in [0, I_max]).
The currents actually applied are reported in the measurement.

Each step writes a measurement record (see :mod:`hyperloop_env.physics.layout`, ``M_*``):
gap excursions, lateral offsets, guideway deflection under each unit, applied currents,
capsule accelerations, position, time, curvature and a contact flag
(any |s_a| ≥ Ω or any guidance gap excursion |z_rel,a| ≥ Ω_g, checked at the end of each
control interval).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numba as nb
import numpy as np

from hyperloop_env.physics import irregularity as irr_mod
from hyperloop_env.physics.actuators import ACTUATOR_KINDS, ActuatorSet, record_slot
from hyperloop_env.physics.guideway import footprint_weights
from hyperloop_env.physics.layout import (
    A_FAULTED,
    A_FROZEN,
    A_I,
    A_SPAN0,
    A_SPAN1,
    A_STEPS,
    A_T,
    BEAM0,
    CMD_LEV,
    FORCE_LAWS,
    K_HI,
    K_LAW,
    K_LO,
    K_NEUTRAL,
    K_RECORD,
    K_REF,
    KIND_STRIDE,
    M_ACC_HEAVE,
    M_ACC_LAT,
    M_ACC_PITCH,
    M_ACC_ROLL,
    M_ACC_YAW,
    M_ALAT,
    M_CONTACT,
    M_FG,
    M_FINITE,
    M_FY,
    M_FZ,
    M_GAP,
    M_KAPPA,
    M_LAT,
    M_SPEED,
    M_T,
    M_W,
    M_WZ,
    M_X,
    N_SLOTS,
    NQ,
    P_A2,
    P_ACCEL,
    P_AG,
    P_B2,
    P_CANT,
    P_CLEAR,
    P_CP,
    P_CS,
    P_CURVE0,
    P_D1H,
    P_D2H,
    P_DELTA0,
    P_DELTAG0,
    P_DIGMAX,
    P_DT,
    P_F0,
    P_FAULT_FREEZE,
    P_FAULT_HI,
    P_FAULT_LO,
    P_FAULT_T,
    P_FAULT_UNIT,
    P_FPRE,
    P_FPREU,
    P_G,
    P_GCLEAR,
    P_I0,
    P_IG0,
    P_IMAX,
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
    P_NSUB,
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
    RECORD_FIELDS,
    SLOT_STRIDE,
    aux_size,
    beam_index,
    kind_param,
    param_size,
    state_size,
)
from hyperloop_env.physics.magnets import guidance_bias_current_A, nominal_current_A
from hyperloop_env.physics.params import MU0, ModelParams
from hyperloop_env.physics.track import curve_loads
from hyperloop_env.physics.units import N_UNITS
from hyperloop_env.physics.vehicle import (
    U_FG,
    U_FY,
    U_FZ,
    U_GAP,
    U_LAT,
    U_W,
    U_WZ,
    coil_current,
    rhs_loaded,
    stage_currents,
    stage_currents_start,
    stage_positions,
    unit_offsets,
)

X_START_M = 10.0
"""Default initial capsule-centre position [m] (``SimulationParams.start_position_m``):
both levitation sets on the first span."""


def pack(params: ModelParams) -> np.ndarray:
    """Flatten ``params`` into the float64 parameter vector the kernels read (with a block
    for every registered actuator kind)."""
    v, m, g, c = params.vehicle, params.magnet, params.guideway, params.condition
    sim = params.simulation
    P = np.zeros(param_size(len(ACTUATOR_KINDS)))
    grav = sim.gravity_m_s2
    f0 = v.total_mass_kg * grav / N_UNITS
    P[P_MC] = v.loaded_capsule_mass_kg
    P[P_IPITCH] = v.capsule_pitch_inertia_kgm2
    P[P_IROLL] = v.roll_inertia_kgm2
    P[P_IYAW] = v.yaw_inertia_kgm2
    P[P_MU] = v.frame_mass_kg / N_UNITS
    P[P_KP] = v.primary_stiffness_N_per_m / N_UNITS
    P[P_CP] = v.primary_damping_Ns_per_m / N_UNITS
    P[P_KS] = v.secondary_stiffness_N_per_m / N_UNITS
    P[P_CS] = v.secondary_damping_Ns_per_m / N_UNITS
    P[P_D1H] = v.set_spacing_m / 2.0
    P[P_D2H] = v.track_gauge_m / 2.0
    P[P_SIGMA] = m.orientation_sign
    P[P_KMAG] = MU0 * m.turns**2 / 4.0
    P[P_A2] = m.pole_length_m
    P[P_B2] = m.pole_width_m
    P[P_DELTA0] = m.nominal_gap_m
    P[P_IMAX] = m.max_current_A
    P[P_CLEAR] = m.clearance_m
    gd = params.guidance
    P[P_GCLEAR] = gd.clearance_m
    P[P_TAU] = m.coil_time_constant_s
    P[P_SPAN] = g.span_m
    P[P_MODALMASS] = g.mass_per_length_kg_per_m * g.span_m
    P[P_ZETA] = g.damping_ratio
    P[P_OMEGA1Y] = 2 * math.pi * g.natural_frequency_hz(1)
    P[P_OMEGA1Z] = 2 * math.pi * g.natural_frequency_hz(1, lateral=True)
    P[P_NMODES] = g.n_modes
    P[P_SPEED] = c.speed_m_s
    P[P_KAPPA] = c.curvature_per_m
    P[P_CANT] = math.radians(c.cant_deg)
    P[P_TRANS] = c.transition_length_m
    P[P_CURVE0] = c.curve_start_m
    P[P_G] = grav
    P[P_DT] = sim.control_dt_s
    P[P_NSUB] = sim.substeps
    P[P_IRRDX] = params.irregularity.grid_step_m
    P[P_RIGID] = 1.0 if g.rigid else 0.0
    P[P_I0] = nominal_current_A(m, f0)
    if P[P_I0] > m.max_current_A:
        raise ValueError(
            f"MagnetParams.max_current_A ({m.max_current_A!r}) is below the equilibrium "
            f"current {P[P_I0]:.1f} A needed to carry the vehicle"
        )
    P[P_XSTART] = sim.start_position_m
    P[P_F0] = f0
    P[P_FPRE] = v.loaded_capsule_mass_kg * grav / N_UNITS
    P[P_XCG] = v.cg_offset_x_m
    P[P_ZCG] = v.cg_offset_z_m
    for a in range(N_UNITS):
        xo, zo = unit_offsets(a, 1.0, 1.0)  # signs of the corner
        P[P_FPREU + a] = P[P_FPRE] * (
            1.0
            + xo * v.cg_offset_x_m / (0.5 * v.set_spacing_m)
            + zo * v.cg_offset_z_m / (0.5 * v.track_gauge_m)
        )
    P[P_ACCEL] = c.acceleration_m_s2
    fl = params.fault
    P[P_FAULT_UNIT] = fl.unit
    P[P_FAULT_T] = fl.time_s
    P[P_FAULT_LO] = P[P_I0] * (1.0 - fl.range_fraction)
    P[P_FAULT_HI] = P[P_I0] + fl.range_fraction * (m.max_current_A - P[P_I0])
    P[P_FAULT_FREEZE] = 1.0 if fl.freeze else 0.0
    ig0 = guidance_bias_current_A(gd, m, grav, N_UNITS)
    P[P_KMAGG] = MU0 * gd.turns**2 / 4.0
    P[P_AG] = m.pole_length_m * gd.pole_height_m
    P[P_DELTAG0] = gd.nominal_gap_m
    P[P_IG0] = ig0
    if ig0 >= gd.max_current_A:
        raise ValueError(
            f"GuidanceParams.max_current_A ({gd.max_current_A!r}) must exceed the guidance bias "
            f"current {ig0:.1f} A of the design rule"
        )
    P[P_DIGMAX] = min(ig0, gd.max_current_A - ig0)
    return pack_kinds(P)


def pack_kinds(P: np.ndarray) -> np.ndarray:
    """Fill the actuator-kind blocks of ``P`` (``layout.kind_param``) from each registered
    kind's data and the scalar parameters already in ``P``; returns ``P``."""
    if P.shape != (param_size(len(ACTUATOR_KINDS)),):
        raise ValueError(
            f"P must have length {param_size(len(ACTUATOR_KINDS))} for the "
            f"{len(ACTUATOR_KINDS)} registered actuator kinds, got shape {P.shape}"
        )
    for k, kind in enumerate(ACTUATOR_KINDS.values()):
        lo, hi = kind.limits_A(P)
        P[kind_param(k, K_REF)] = kind.reference_A(P)
        P[kind_param(k, K_NEUTRAL)] = kind.neutral
        P[kind_param(k, K_LO)] = lo
        P[kind_param(k, K_HI)] = hi
        P[kind_param(k, K_RECORD)] = record_slot(kind.name)
        P[kind_param(k, K_LAW)] = FORCE_LAWS[kind.force_law]
    return P


# ---------------------------------------------------------------------------------------
# compiled kernels
# ---------------------------------------------------------------------------------------
# The kernels (here and in vehicle, guideway, magnets, track, irregularity) compile with
# error_model="numpy": no zero-division checks in the hot loops (every divisor is a
# validated positive parameter or a floored gap, so no result changes), and the ones that
# allocate nothing with _nrt=False: no reference counting of their arrays (every array they
# see is owned by the Python caller for the whole call). Numba's reference counting is an
# atomic update per array per function call or view; in this integrator those cost ~15 %
# of the time. Stage loads blocks are therefore addressed as (tl, row), not as row views.


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def _update_ring(P: np.ndarray, y: np.ndarray, spans: np.ndarray, t_end: float) -> bool:
    """Give the span the front footprint reaches by ``t_end`` a slot, starting at rest;
    True if a slot changed.

    The slot it takes held the span two behind, which the rear footprint has left
    (guaranteed by ModelParams: footprint + one substep of travel < span)."""
    nm = int(P[P_NMODES])
    span = P[P_SPAN]
    xf = (
        P[P_XSTART]
        + P[P_SPEED] * t_end
        + 0.5 * P[P_ACCEL] * t_end * t_end
        + P[P_D1H]
        + 0.5 * P[P_A2]
    )
    jf = int(math.floor(xf / span))
    slot = jf % 2
    if spans[slot] != jf:
        spans[slot] = jf
        base = BEAM0 + slot * SLOT_STRIDE * nm
        for i in range(base, base + SLOT_STRIDE * nm):
            y[i] = 0.0
        return True
    return False


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def _measure(
    P: np.ndarray,
    y: np.ndarray,
    aux: np.ndarray,
    irr: np.ndarray,
    meas: np.ndarray,
    dydt: np.ndarray,
    tl: np.ndarray,
    row: int,
    uo: np.ndarray,
    spans: np.ndarray,
    positions_ready: bool,
) -> None:
    """Write the measurement record of the state at ``aux[A_T]``. ``tl[row]`` is a stage
    loads block; ``positions_ready``: its position part already holds that time with these
    spans."""
    t = aux[A_T]
    nk = (P.shape[0] - P_KINDS) // KIND_STRIDE
    cur = aux[A_I : A_I + nk * N_UNITS]
    if not positions_ready:
        stage_positions(t, P, irr, spans, tl, row)
    stage_currents(t, t, cur, cur, P, tl, row)
    rhs_loaded(y, P, tl, row, dydt, uo)
    contact = False
    for a in range(N_UNITS):
        meas[M_GAP + a] = uo[U_GAP, a]
        meas[M_LAT + a] = uo[U_LAT, a]
        meas[M_W + a] = uo[U_W, a]
        meas[M_WZ + a] = uo[U_WZ, a]
        meas[M_FY + a] = uo[U_FY, a]
        meas[M_FZ + a] = uo[U_FZ, a]
        meas[M_FG + a] = uo[U_FG, a]
        if abs(uo[U_GAP, a]) >= P[P_CLEAR] or abs(uo[U_LAT, a]) >= P[P_GCLEAR]:
            contact = True
    tc = stage_currents_start(P)
    for k in range(nk):  # applied currents of every kind, in its record slot
        rs = int(P[P_KINDS + k * KIND_STRIDE + K_RECORD])
        for a in range(N_UNITS):
            meas[rs + a] = tl[row, tc + k * N_UNITS + a]
    meas[M_ACC_HEAVE] = dydt[NQ + Q_HEAVE]
    meas[M_ACC_LAT] = dydt[NQ + Q_LAT]
    meas[M_ACC_PITCH] = dydt[NQ + Q_PITCH]
    meas[M_ACC_ROLL] = dydt[NQ + Q_ROLL]
    meas[M_ACC_YAW] = dydt[NQ + Q_YAW]
    xc = P[P_XSTART] + P[P_SPEED] * t + 0.5 * P[P_ACCEL] * t * t
    speed = P[P_SPEED] + P[P_ACCEL] * t
    kap, alat, _ = curve_loads(xc, speed, P[P_KAPPA], P[P_CANT], P[P_CURVE0], P[P_TRANS], P[P_G])
    meas[M_SPEED] = speed
    meas[M_X] = xc
    meas[M_T] = t
    meas[M_KAPPA] = kap
    meas[M_ALAT] = alat
    finite = True
    for i in range(y.shape[0]):
        if not math.isfinite(y[i]):
            finite = False
            break
    meas[M_FINITE] = 1.0 if finite else 0.0
    meas[M_CONTACT] = 1.0 if (contact or not finite) else 0.0


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def control_step(
    P: np.ndarray,
    y: np.ndarray,
    aux: np.ndarray,
    irr: np.ndarray,
    i_cmd_in: np.ndarray,
    meas: np.ndarray,
    work: np.ndarray,
    tl: np.ndarray,
    uo: np.ndarray,
    spans: np.ndarray,
) -> None:
    """Advance one control interval with ``P[P_NSUB]`` RK4 substeps (in place).

    ``work`` is float64[WORK_ROWS, n_state] scratch, ``tl`` float64[TL_ROWS,
    stage_loads_size(n_modes, n_commands)] scratch for the stage loads; ``i_cmd_in`` the
    full command vector [A] (finite; each kind's channels clipped here to its clamp
    ``[P[kind_param(k, K_LO)], P[kind_param(k, K_HI)]]``).

    The right-hand side is :func:`~hyperloop_env.physics.vehicle.rhs` at every RK4 stage,
    with its time-only part (footprint weights, profile, curve loads, coil currents)
    computed once per distinct stage time: the two midpoint stages share theirs, and a
    substep's end serves as the next one's start when the two times are the same float and
    no span slot changed in between. Bit-identical to evaluating rhs at every stage.

    Deliberately one long function: it is the numba-compiled kernel of every control
    interval, and splitting it into helpers would add calls and state passing in the hot
    loop and could change the floating-point evaluation order (bit-identity)."""
    nk = (P.shape[0] - P_KINDS) // KIND_STRIDE
    ncmd = nk * N_UNITS
    a_icmd = A_I + ncmd
    for kk in range(nk):
        lo = P[P_KINDS + kk * KIND_STRIDE + K_LO]
        hi = P[P_KINDS + kk * KIND_STRIDE + K_HI]
        for a in range(kk * N_UNITS, (kk + 1) * N_UNITS):
            c = i_cmd_in[a]
            aux[a_icmd + a] = lo if c < lo else (hi if c > hi else c)
    fu = int(P[P_FAULT_UNIT])
    if fu >= 0 and aux[A_STEPS] * P[P_DT] >= P[P_FAULT_T]:
        k = a_icmd + CMD_LEV + fu
        if aux[A_FAULTED] < 0.5:  # onset: remember the coil's current
            aux[A_FAULTED] = 1.0
            aux[A_FROZEN] = aux[A_I + CMD_LEV + fu]
        if P[P_FAULT_FREEZE] > 0.5:
            aux[k] = aux[A_FROZEN]
        else:
            lo = P[P_FAULT_LO]
            hi = P[P_FAULT_HI]
            aux[k] = lo if aux[k] < lo else (hi if aux[k] > hi else aux[k])
    i_start = aux[A_I:a_icmd]
    i_cmd = aux[a_icmd : a_icmd + ncmd]
    dt = P[P_DT]
    nsub = int(P[P_NSUB])
    h = dt / nsub
    hh = 0.5 * h
    h6 = h / 6.0
    steps = aux[A_STEPS]
    t0 = steps * dt
    spans[0] = int(aux[A_SPAN0])
    spans[1] = int(aux[A_SPAN1])
    k1 = work[0]
    k2 = work[1]
    k3 = work[2]
    k4 = work[3]
    yt = work[4]  # WORK_ROWS = 5 scratch rows
    n = y.shape[0]
    # stage loads rows: start, midpoint and end of the substep (rotated, TL_ROWS = 3)
    r_start = 0
    r_mid = 1
    r_end = 2
    t_prev_end = 0.0
    have_end = False
    for j in range(nsub):
        t = t0 + j * h
        changed = _update_ring(P, y, spans, t + h)
        if have_end and not changed and t == t_prev_end:
            r_start, r_end = r_end, r_start  # the previous end is this start
        else:
            stage_positions(t, P, irr, spans, tl, r_start)
            stage_currents(t, t0, i_start, i_cmd, P, tl, r_start)
        rhs_loaded(y, P, tl, r_start, k1, uo)
        for i in range(n):
            yt[i] = y[i] + hh * k1[i]
        tm = t + 0.5 * h
        stage_positions(tm, P, irr, spans, tl, r_mid)
        stage_currents(tm, t0, i_start, i_cmd, P, tl, r_mid)
        rhs_loaded(yt, P, tl, r_mid, k2, uo)
        for i in range(n):
            yt[i] = y[i] + hh * k2[i]
        rhs_loaded(yt, P, tl, r_mid, k3, uo)
        for i in range(n):
            yt[i] = y[i] + h * k3[i]
        te = t + h
        stage_positions(te, P, irr, spans, tl, r_end)
        stage_currents(te, t0, i_start, i_cmd, P, tl, r_end)
        rhs_loaded(yt, P, tl, r_end, k4, uo)
        for i in range(n):
            y[i] += h6 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        t_prev_end = te
        have_end = True
    t_end = (steps + 1.0) * dt
    for a in range(ncmd):
        aux[A_I + a] = coil_current(t_end, t0, i_start[a], i_cmd[a], P[P_TAU])
    aux[A_T] = t_end
    aux[A_STEPS] = steps + 1.0
    aux[A_SPAN0] = spans[0]
    aux[A_SPAN1] = spans[1]
    _measure(P, y, aux, irr, meas, k1, tl, r_end, uo, spans, have_end and t_end == t_prev_end)


@nb.njit(cache=True, parallel=True, _nrt=False)
def control_step_batch(
    P: np.ndarray,
    Y: np.ndarray,
    AUX: np.ndarray,
    IRR: np.ndarray,
    ICMD: np.ndarray,
    MEAS: np.ndarray,
    WORK: np.ndarray,
    TL: np.ndarray,
    UO: np.ndarray,
    SPANS: np.ndarray,
) -> None:
    """control_step for N vehicles (row i of every array), in parallel over vehicles."""
    for i in nb.prange(Y.shape[0]):
        control_step(P[i], Y[i], AUX[i], IRR[i], ICMD[i], MEAS[i], WORK[i], TL[i], UO[i], SPANS[i])


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def control_step_serial(
    P: np.ndarray,
    Y: np.ndarray,
    AUX: np.ndarray,
    IRR: np.ndarray,
    ICMD: np.ndarray,
    MEAS: np.ndarray,
    WORK: np.ndarray,
    TL: np.ndarray,
    UO: np.ndarray,
    SPANS: np.ndarray,
) -> None:
    """control_step_batch on one thread (bit-identical; cheaper for small batches)."""
    for i in range(Y.shape[0]):
        control_step(P[i], Y[i], AUX[i], IRR[i], ICMD[i], MEAS[i], WORK[i], TL[i], UO[i], SPANS[i])


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def control_step_rows(
    P: np.ndarray,
    Y: np.ndarray,
    AUX: np.ndarray,
    IRR: np.ndarray,
    ICMD: np.ndarray,
    MEAS: np.ndarray,
    WORK: np.ndarray,
    TL: np.ndarray,
    UO: np.ndarray,
    SPANS: np.ndarray,
    rows: np.ndarray,
) -> None:
    """control_step_serial for the vehicles ``rows`` (int64 indices) only; the others keep
    their state and records (bit-identical for the rows it advances: rows never interact)."""
    for k in range(rows.shape[0]):
        i = rows[k]
        control_step(P[i], Y[i], AUX[i], IRR[i], ICMD[i], MEAS[i], WORK[i], TL[i], UO[i], SPANS[i])


@nb.njit(cache=True, error_model="numpy", _nrt=False)
def run_constant(
    P: np.ndarray,
    y: np.ndarray,
    aux: np.ndarray,
    irr: np.ndarray,
    currents: np.ndarray,
    n_steps: int,
    out: np.ndarray,
    work: np.ndarray,
    tl: np.ndarray,
    uo: np.ndarray,
    spans: np.ndarray,
) -> int:
    """Advance n_steps with fixed commanded currents, recording every measurement in
    out[n_steps, NM]; stops early (returning the number of steps taken) if the state
    stops being finite."""
    for k in range(n_steps):
        control_step(P, y, aux, irr, currents, out[k], work, tl, uo, spans)
        if out[k, M_FINITE] < 0.5:
            return k + 1
    return n_steps


# ---------------------------------------------------------------------------------------
# initial state
# ---------------------------------------------------------------------------------------


WORK_ROWS = 5
"""Scratch rows of the RK4 step (k1..k4 and the trial state)."""
TL_ROWS = 3
"""Stage loads blocks of the RK4 step (substep start, midpoint, end)."""


def _n_kinds(P: np.ndarray) -> int:
    return (P.shape[-1] - P_KINDS) // KIND_STRIDE


def neutral_commands(P: np.ndarray) -> np.ndarray:
    """The full command vector at rest [A]: every actuator kind at its neutral command
    ``reference·neutral`` (levitation coils at I0, guidance pairs at ΔI = 0)."""
    nk = _n_kinds(P)
    out = np.empty(nk * N_UNITS)
    for k in range(nk):
        out[k * N_UNITS : (k + 1) * N_UNITS] = P[kind_param(k, K_REF)] * P[kind_param(k, K_NEUTRAL)]
    return out


def command_reference(P: np.ndarray, actuators: ActuatorSet) -> np.ndarray:
    """Reference current of each channel of ``actuators`` [A] (I0 for levitation coils)."""
    order = list(ACTUATOR_KINDS)
    return np.array(
        [P[kind_param(order.index(k), K_REF)] for k in actuators.kinds for _ in range(N_UNITS)]
    )


def initial_state(P: np.ndarray, irr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Static equilibrium at the start position: the guideway under its static modal deflection
    from the nominal forces, the units at the nominal gap over the deflected, irregular
    guideway, and the capsule fitted to the unit heights (least squares for heave, pitch,
    roll; lateral and yaw likewise). Returns (y, aux)."""
    nm = int(P[P_NMODES])
    y = np.zeros(state_size(nm))
    ncmd = _n_kinds(P) * N_UNITS
    aux = np.zeros(aux_size(ncmd))
    span = P[P_SPAN]
    half = 0.5 * P[P_A2]
    jf = math.floor((P[P_XSTART] + P[P_D1H] + half) / span)
    spans = np.zeros(2, dtype=np.int64)
    spans[jf % 2] = jf
    spans[(jf + 1) % 2] = jf - 1
    aux[A_SPAN0], aux[A_SPAN1] = spans
    aux[A_I : A_I + ncmd] = neutral_commands(P)
    aux[A_I + ncmd : A_I + 2 * ncmd] = aux[A_I : A_I + ncmd]
    rigid = P[P_RIGID] > 0.5
    k = np.arange(1, nm + 1)
    wts = np.zeros((N_UNITS, N_SLOTS, nm))
    xs = np.zeros(N_UNITS)
    zos = np.zeros(N_UNITS)
    for a in range(N_UNITS):
        xo, zo = unit_offsets(a, P[P_D1H], P[P_D2H])
        xs[a], zos[a] = xo, zo
        for sl in range(2):
            footprint_weights(P[P_XSTART] + xo, half, spans[sl] * span, span, wts[a, sl])
    if not rigid:
        omega = P[P_OMEGA1Y] * k**2
        for sl in range(2):
            load = -P[P_F0] * wts[:, sl, :].sum(axis=0)
            b0 = beam_index(sl, 0, 0, 0, nm)
            y[b0 : b0 + nm] = load / (P[P_MODALMASS] * omega**2)
    ys = np.zeros(N_UNITS)
    zs = np.zeros(N_UNITS)
    for a in range(N_UNITS):
        w = 0.0
        if not rigid:
            for sl in range(2):
                b0 = beam_index(sl, 0, 0, 0, nm)
                w += float(y[b0 : b0 + nm] @ wts[a, sl])
        x_a = P[P_XSTART] + xs[a]
        ys[a] = w + irr_mod.sample(irr, a % 2, x_a, P[P_IRRDX])
        zs[a] = irr_mod.sample(irr, irr_mod.ROW_LATERAL, x_a, P[P_IRRDX])
    y[Q_UY : Q_UY + N_UNITS] = ys
    y[Q_UZ : Q_UZ + N_UNITS] = zs
    A = np.column_stack([np.ones(N_UNITS), xs, -zos])
    heave, pitch, roll = np.linalg.lstsq(A, ys, rcond=None)[0]
    B = np.column_stack([np.ones(N_UNITS), xs])
    lat, yaw = np.linalg.lstsq(B, zs, rcond=None)[0]
    y[Q_HEAVE], y[Q_PITCH], y[Q_ROLL], y[Q_LAT], y[Q_YAW] = heave, pitch, roll, lat, yaw
    return y, aux


# ---------------------------------------------------------------------------------------
# Python API
# ---------------------------------------------------------------------------------------


def _check_currents(currents: Any, shape: tuple[int, ...], names: Sequence[str]) -> np.ndarray:
    try:
        arr = np.asarray(currents, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"currents must be numbers of shape {shape} ({', '.join(names)}) [A], got {currents!r}"
        ) from exc
    if arr.shape != shape:
        raise ValueError(
            f"currents must have shape {shape} ({', '.join(names)}) [A], got {arr.shape}"
        )
    if not np.isfinite(arr).all():
        raise ValueError(f"currents must be finite, got {arr!r}")
    return arr


def _unit_field(m: np.ndarray, name: str) -> np.ndarray:
    return m[RECORD_FIELDS[name]].copy()


@dataclass(frozen=True)
class Measurement:
    """Named view of one measurement record (all SI units; per-unit arrays in the order of
    :data:`~hyperloop_env.physics.units.UNIT_NAMES`)."""

    gap_excursion_m: np.ndarray  # (N_UNITS,) s_a, positive = gap opens
    lateral_offset_m: np.ndarray  # (N_UNITS,) z_rel,a
    guideway_deflection_m: np.ndarray  # (N_UNITS,) vertical w under each unit
    lateral_deflection_m: np.ndarray  # (N_UNITS,)
    current_A: np.ndarray  # (N_UNITS,) applied levitation coil currents
    magnet_force_N: np.ndarray  # (N_UNITS,)
    acceleration: np.ndarray  # (5,) heave, lateral [m/s²], pitch, roll, yaw [rad/s²]
    position_m: float
    time_s: float
    curvature_per_m: float
    lateral_load_m_s2: float
    contact: bool

    @staticmethod
    def from_record(m: np.ndarray) -> Measurement:
        return Measurement(
            gap_excursion_m=_unit_field(m, "gap_excursion_m"),
            lateral_offset_m=_unit_field(m, "lateral_offset_m"),
            guideway_deflection_m=_unit_field(m, "guideway_deflection_m"),
            lateral_deflection_m=_unit_field(m, "lateral_deflection_m"),
            current_A=_unit_field(m, "current_A"),
            magnet_force_N=_unit_field(m, "magnet_force_N"),
            acceleration=_unit_field(m, "acceleration"),
            position_m=float(m[M_X]),
            time_s=float(m[M_T]),
            curvature_per_m=float(m[M_KAPPA]),
            lateral_load_m_s2=float(m[M_ALAT]),
            contact=bool(m[M_CONTACT] > 0.5),
        )


def equilibrium_current_A(params: ModelParams) -> float:
    """I0: the levitation current that carries the vehicle at the nominal gap [A]."""
    return float(pack(params)[P_I0])


def guidance_bias_A(params: ModelParams) -> float:
    """I_g0: the guidance magnets' bias current [A] (GuidanceParams design rule)."""
    return float(pack(params)[P_IG0])


def track_length_needed_m(params: ModelParams) -> float:
    """Length of guideway profile a run needs [m]: the section, the start position, the
    vehicle's set spacing and a margin."""
    return (
        params.simulation.track_length_m
        + params.simulation.start_position_m
        + params.vehicle.set_spacing_m
        + 10.0
    )


def profile_grid(params: ModelParams) -> tuple[int, float]:
    """(number of points, step [m]) of the guideway profile grid of a run."""
    return (
        irr_mod.grid_size(params.irregularity, track_length_needed_m(params)),
        float(params.irregularity.grid_step_m),
    )


def episode_steps(params: ModelParams) -> int:
    """Control steps to cover the track section: ceil(track_length / (v·dt)), or with an
    acceleration a the time t of L = v0·t + a·t²/2, t = (√(v0² + 2aL) − v0)/a, over dt."""
    sim = params.simulation
    v0 = params.condition.speed_m_s
    acc = params.condition.acceleration_m_s2
    if acc == 0.0:
        dx = v0 * sim.control_dt_s
        return max(1, math.ceil(sim.track_length_m / dx - 1e-9))
    t = (math.sqrt(v0 * v0 + 2.0 * acc * sim.track_length_m) - v0) / acc
    return max(1, math.ceil(t / sim.control_dt_s - 1e-9))
