"""Index constants of the packed arrays the compiled kernels work on.

The compiled code (numba) sees a run as four flat float64 arrays:

``P`` (parameters, length :data:`NP`), the state ``y`` (length ``state_size(n_modes)``),
``aux`` (time, span ring, coil currents; length :data:`NA`) and the measurement record
``m`` (length :data:`NM`) written after every control step. The names below are the only
place those positions are defined.
"""

from __future__ import annotations

# ---- P: packed parameters -----------------------------------------------------------
P_MC = 0  # capsule mass [kg]
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
P_LATCLEAR = 18  # lateral clearance [m]
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
P_FPRE = 39  # static primary preload per corner = m_c g / 4 [N]
NP = 40

# ---- y: state ------------------------------------------------------------------------
# generalised coordinates q (13) then their rates (13), then the guideway modal states.
Q_HEAVE = 0  # capsule heave y_c [m]
Q_LAT = 1  # capsule lateral z_c [m]
Q_PITCH = 2  # [rad]
Q_ROLL = 3  # [rad]
Q_YAW = 4  # [rad]
Q_UY = 5  # 5..8: unit vertical y_a [m], order FL, FR, RL, RR
Q_UZ = 9  # 9..12: unit lateral z_a [m]
NQ = 13
BEAM0 = 2 * NQ  # first guideway state


def state_size(n_modes: int) -> int:
    """Length of the state vector: 26 vehicle states + 2 span slots x 2 planes x
    (displacement, velocity) x n_modes."""
    return BEAM0 + 8 * n_modes


def beam_index(slot: int, plane: int, rate: int, k: int, n_modes: int) -> int:
    """Index of modal coordinate k (0-based) of span ``slot`` (0/1), ``plane`` (0 vertical,
    1 lateral), ``rate`` (0 displacement [m], 1 velocity [m/s])."""
    return BEAM0 + ((slot * 2 + plane) * 2 + rate) * n_modes + k


# ---- aux -----------------------------------------------------------------------------
A_T = 0  # time since reset [s]
A_SPAN0 = 1  # span index held by slot 0
A_SPAN1 = 2  # span index held by slot 1
A_I = 3  # 3..6: coil currents at the start of the step [A]
A_ICMD = 7  # 7..10: commanded (clipped) currents of the step [A]
A_STEPS = 11  # control steps taken
NA = 12

# ---- m: measurements after a control step -------------------------------------------
M_GAP = 0  # 0..3: gap excursion s_a [m] (positive: gap opens)
M_LAT = 4  # 4..7: lateral offset of unit from its rail z_rel [m]
M_W = 8  # 8..11: vertical guideway deflection under each unit (footprint mean) [m]
M_I = 12  # 12..15: coil currents at the end of the step [A]
M_ACC_HEAVE = 16  # capsule vertical acceleration [m/s^2]
M_ACC_LAT = 17  # capsule lateral acceleration in the track frame [m/s^2]
M_ACC_PITCH = 18  # [rad/s^2]
M_ACC_ROLL = 19  # [rad/s^2]
M_ACC_YAW = 20  # [rad/s^2]
M_X = 21  # capsule-centre position [m]
M_T = 22  # time [s]
M_KAPPA = 23  # track curvature at the capsule centre [1/m]
M_CONTACT = 24  # 1.0 if any |s_a| >= Omega or |z_rel| >= lateral clearance
M_FY = 25  # 25..28: magnet force along the gap [N]
M_ALAT = 29  # quasi-static lateral load v^2 kappa cos(theta) - g sin(theta) [m/s^2]
M_WZ = 30  # 30..33: lateral guideway deflection under each unit [m]
M_FINITE = 34  # 1.0 if the state is finite
NM = 35
