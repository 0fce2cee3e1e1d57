"""Index constants of the packed arrays the compiled kernels work on.

The compiled code (numba) sees a run as four flat float64 arrays:

``P`` (parameters, length ``param_size(n_kinds)``), the state ``y`` (length
``state_size(n_modes)``), ``aux`` (time, span ring, coil currents; length
``aux_size(n_commands)``) and the measurement record ``m`` (length ``record_size(n_kinds)``)
written after every control step. The names below are the only place those positions are
defined.

Actuator kinds (:mod:`hyperloop_env.physics.actuators`) are data the kernels read at run
time, never compile-time constants (a cached kernel would not see a kind registered
later): every kind ``k`` (its position in ``actuators.physics_kinds()``) has a block of
:data:`KIND_STRIDE` entries at the end of ``P`` (``kind_param(k, K_*)``: reference current,
neutral command, clamp, record slot, force law), ``N_UNITS`` channels in the full command
vector, the ``aux`` blocks of applied and commanded currents at its end, and a record slot
of ``N_UNITS`` applied currents (the built-in kinds at ``M_I`` and ``M_IG``, registered ones
after ``M_SPEED``). :data:`NP`, :data:`NA` and :data:`NM` are the sizes with the built-in
kinds only.
"""

from __future__ import annotations

from hyperloop_env.physics.units import N_UNITS

# ---- P: packed parameters -----------------------------------------------------------
P_MC = 0  # capsule mass with payload [kg]
P_IPITCH = 1  # capsule pitch inertia [kg m^2]
P_IROLL = 2  # capsule roll inertia [kg m^2]
P_IYAW = 3  # capsule yaw inertia [kg m^2]
P_MU = 4  # mass of one magnet unit (frame share) [kg]
P_KP = 5  # primary stiffness per corner [N/m]
P_CP = 6  # primary damping per corner [N s/m]
P_KS = 7  # secondary (lateral) stiffness per corner [N/m]
P_CS = 8  # secondary damping per corner [N s/m]
P_D1H = 9  # half the front-rear set spacing d1/2 [m]
P_D2H = 10  # half the left-right magnet distance d2/2 [m]
P_SIGMA = 11  # +1 repelling, -1 attracting
P_KMAG = 12  # mu0 N^2 / 4 [H m^-1 ... ] so that F = KMAG I^2 A / delta^2
P_A2 = 13  # pole length a2 (along x), also the load length La [m]
P_B2 = 14  # pole width b2 (across z) [m]
P_DELTA0 = 15  # nominal gap [m]
P_IMAX = 16  # current limit [A]
P_CLEAR = 17  # gap clearance Omega [m]
P_GCLEAR = 18  # guidance clearance Ω_g: contact when |z_rel| >= Ω_g [m]
P_TAU = 19  # coil time constant [s] (0: ideal current source)
P_SPAN = 20  # span length L [m]
P_MODALMASS = 21  # rho A L [kg] (modal mass for phi_k = sqrt2 sin)
P_ZETA = 22  # modal damping ratio
P_OMEGA1Y = 23  # first vertical bending circular frequency [rad/s]
P_OMEGA1Z = 24  # first lateral bending circular frequency [rad/s]
P_NMODES = 25  # number of modes per span and plane
P_SPEED = 26  # speed [m/s]
P_KAPPA = 27  # full curvature 1/R [1/m]
P_CANT = 28  # full cant [rad]
P_TRANS = 29  # transition length [m]
P_CURVE0 = 30  # start of the transition [m]
P_G = 31  # gravity [m/s^2]
P_DT = 32  # control interval [s]
P_NSUB = 33  # RK4 substeps per control interval
P_IRRDX = 34  # irregularity grid step [m]
P_RIGID = 35  # 1.0: rigid guideway
P_I0 = 36  # nominal (equilibrium) current [A]
P_XSTART = 37  # initial position of the capsule centre [m]
P_F0 = 38  # nominal magnet force per unit [N]
P_FPRE = 39  # mean static primary preload per corner = m_c g / 4 [N] (see P_FPREU)
P_KMAGG = 40  # guidance magnets: mu0 N_g^2 / 4
P_AG = 41  # guidance pole area A_g = a2 h_g [m^2]
P_DELTAG0 = 42  # guidance nominal gap [m]
P_IG0 = 43  # guidance bias current [A]
P_DIGMAX = 44  # largest |differential guidance current| [A] (both coils in [0, I_g,max])
P_ACCEL = 45  # longitudinal acceleration a [m/s^2]: x_c = x0 + v0 t + a t^2/2
P_XCG = 46  # capsule centre of gravity ahead of the geometric centre [m]
P_ZCG = 47  # capsule centre of gravity right of the geometric centre [m]
P_FPREU = 48  # static primary preload of each corner [N] (N_UNITS entries)
P_FAULT_UNIT = P_FPREU + N_UNITS  # faulty levitation coil (-1: none)
P_FAULT_T = P_FAULT_UNIT + 1  # fault onset [s]
P_FAULT_LO = P_FAULT_T + 1  # command limits of the faulty coil after the onset [A]
P_FAULT_HI = P_FAULT_LO + 1
P_FAULT_FREEZE = P_FAULT_HI + 1  # 1.0: the faulty coil's current freezes at the onset
# one block per actuator kind, in the physics order (kind_param(k, field))
P_KINDS = P_FAULT_FREEZE + 1  # first kind block
K_REF = 0  # reference current [A]: the base of the action map and of the scaling
K_NEUTRAL = 1  # neutral command in units of the reference (1: absolute, 0: differential)
K_LO = 2  # clamp of the commanded current: lower limit [A]
K_HI = 3  # upper limit [A]
K_RECORD = 4  # first record slot of its N_UNITS applied currents
K_LAW = 5  # force law id (FORCE_LAWS)
KIND_STRIDE = 6
N_BUILTIN_KINDS = 2  # levitation, guidance: always the first two kinds
LAW_LEVITATION = 0  # a levitation magnet of the unit's geometry (vehicle.kind_force)
LAW_GUIDANCE = 1  # a guidance pair of the unit's geometry biased at the kind's reference
FORCE_LAWS: dict[str, int] = {"levitation": LAW_LEVITATION, "guidance": LAW_GUIDANCE}
"""Force laws an actuator kind can name (``ActuatorKind.force_law``) → its ``K_LAW`` id;
each has a branch in :func:`hyperloop_env.physics.vehicle.kind_force`."""


def kind_param(k: int, field: int) -> int:
    """Index in ``P`` of ``field`` (``K_*``) of actuator kind ``k``."""
    return P_KINDS + k * KIND_STRIDE + field


def param_size(n_kinds: int) -> int:
    """Length of ``P`` with ``n_kinds`` actuator kinds."""
    return P_KINDS + n_kinds * KIND_STRIDE


NP = param_size(N_BUILTIN_KINDS)

# ---- y: state ------------------------------------------------------------------------
# generalised coordinates q (13) then their rates (13), then the guideway modal states.
Q_HEAVE = 0  # capsule heave y_c [m]
Q_LAT = 1  # capsule lateral z_c [m]
Q_PITCH = 2  # [rad]
Q_ROLL = 3  # [rad]
Q_YAW = 4  # [rad]
N_CAPSULE_DOF = 5  # heave, lateral, pitch, roll, yaw
Q_UY = N_CAPSULE_DOF  # unit vertical y_a [m], one per unit in the order of UNIT_NAMES
Q_UZ = Q_UY + N_UNITS  # unit lateral z_a [m]
NQ = Q_UZ + N_UNITS  # generalised coordinates (13)
BEAM0 = 2 * NQ  # first guideway state
N_SLOTS = 2  # span slots: the spans under the vehicle
N_PLANES = 2  # vertical (0) and lateral (1) bending
SLOT_STRIDE = N_PLANES * 2  # per mode: (displacement, velocity) per plane


def state_size(n_modes: int) -> int:
    """Length of the state vector: 2·NQ vehicle states + 2 span slots x 2 planes x
    (displacement, velocity) x n_modes."""
    return BEAM0 + N_SLOTS * SLOT_STRIDE * n_modes


def beam_index(slot: int, plane: int, rate: int, k: int, n_modes: int) -> int:
    """Index of modal coordinate k (0-based) of span ``slot`` (0/1), ``plane`` (0 vertical,
    1 lateral), ``rate`` (0 displacement [m], 1 velocity [m/s])."""
    return BEAM0 + ((slot * N_PLANES + plane) * 2 + rate) * n_modes + k


# ---- aux -----------------------------------------------------------------------------
A_T = 0  # time since reset [s]
A_SPAN0 = 1  # span index held by slot 0
A_SPAN1 = 2  # span index held by slot 1
A_STEPS = 3  # control steps taken
A_FROZEN = 4  # current held by a frozen faulty coil [A]
A_FAULTED = 5  # 1.0 once the fault has set in
A_I = 6  # full command vector (n commands): applied currents at the start of the step [A]
# then the commanded (clipped) currents of the step [A] at A_I + n (a_icmd(n))


def a_icmd(n_commands: int) -> int:
    """Index in ``aux`` of the commanded (clipped) currents of the step [A]."""
    return A_I + n_commands


def aux_size(n_commands: int) -> int:
    """Length of ``aux`` for a full command vector of ``n_commands`` channels."""
    return A_I + 2 * n_commands


NA = aux_size(N_BUILTIN_KINDS * N_UNITS)

# ---- m: measurements after a control step -------------------------------------------
# per-unit blocks have N_UNITS entries in the order of UNIT_NAMES
M_GAP = 0  # gap excursion s_a [m] (positive: gap opens)
M_LAT = M_GAP + N_UNITS  # lateral offset of unit from its rail z_rel [m]
M_W = M_LAT + N_UNITS  # vertical guideway deflection under each unit (footprint mean) [m]
M_I = M_W + N_UNITS  # levitation coil currents at the end of the step [A]
M_ACC_HEAVE = M_I + N_UNITS  # capsule vertical acceleration [m/s^2]
M_ACC_LAT = M_ACC_HEAVE + 1  # capsule lateral acceleration in the track frame [m/s^2]
M_ACC_PITCH = M_ACC_HEAVE + 2  # [rad/s^2]
M_ACC_ROLL = M_ACC_HEAVE + 3  # [rad/s^2]
M_ACC_YAW = M_ACC_HEAVE + 4  # [rad/s^2]
M_X = M_ACC_YAW + 1  # capsule-centre position [m]
M_T = M_X + 1  # time [s]
M_KAPPA = M_T + 1  # track curvature at the capsule centre [1/m]
M_CONTACT = M_KAPPA + 1  # 1.0 if any |s_a| >= Omega or |z_rel| >= Omega_g
M_FY = M_CONTACT + 1  # magnet force along the gap [N] (per unit)
M_ALAT = M_FY + N_UNITS  # quasi-static lateral load v^2 kappa cos(theta) - g sin(theta) [m/s^2]
M_WZ = M_ALAT + 1  # lateral guideway deflection under each unit [m] (per unit)
M_FINITE = M_WZ + N_UNITS  # 1.0 if the state is finite
M_IG = M_FINITE + 1  # applied differential guidance current ΔI per unit [A]
M_FZ = M_IG + N_UNITS  # lateral (edge) force of the levitation magnet per unit [N]
M_FG = M_FZ + N_UNITS  # net lateral force of the guidance pair per unit [N]
M_SPEED = M_FG + N_UNITS  # speed v(t) = v0 + a t [m/s]
M_KINDS = M_SPEED + 1  # applied currents of the registered (not built-in) kinds [A]


def record_size(n_kinds: int) -> int:
    """Length of the record with ``n_kinds`` actuator kinds."""
    return M_KINDS + (n_kinds - N_BUILTIN_KINDS) * N_UNITS


NM = record_size(N_BUILTIN_KINDS)


def _unit_block(start: int) -> slice:
    return slice(start, start + N_UNITS)


RECORD_FIELDS: dict[str, slice] = {
    "gap_excursion_m": _unit_block(M_GAP),
    "lateral_offset_m": _unit_block(M_LAT),  # = the guidance gap excursion (δ_L − δg0)
    "guideway_deflection_m": _unit_block(M_W),
    "lateral_deflection_m": _unit_block(M_WZ),
    "current_A": _unit_block(M_I),
    "magnet_force_N": _unit_block(M_FY),
    "guidance_current_A": _unit_block(M_IG),  # differential ΔI
    "edge_force_N": _unit_block(M_FZ),
    "guidance_force_N": _unit_block(M_FG),
    "acceleration": slice(M_ACC_HEAVE, M_ACC_YAW + 1),
    "acceleration_heave_lateral": slice(M_ACC_HEAVE, M_ACC_LAT + 1),
    "position_m": slice(M_X, M_X + 1),
    "speed_m_s": slice(M_SPEED, M_SPEED + 1),
    "time_s": slice(M_T, M_T + 1),
    "curvature_per_m": slice(M_KAPPA, M_KAPPA + 1),
    "lateral_load_m_s2": slice(M_ALAT, M_ALAT + 1),
    "contact": slice(M_CONTACT, M_CONTACT + 1),
    "finite": slice(M_FINITE, M_FINITE + 1),
}
"""Named slices of the measurement record (what the simulator's users read); a registered
actuator kind adds its ``record_field``."""

CMD_LEV = 0  # first levitation coil current in the full command vector (kind 0)
CMD_GUID = N_UNITS  # first guidance differential current (kind 1)
