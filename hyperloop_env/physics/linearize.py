"""Linearisation of the vehicle at equilibrium (for eigenvalue checks and LQR design).

The vehicle (26 states: 13 coordinates and their rates, see
:mod:`hyperloop_env.physics.layout`) over a rigid, straight, smooth guideway at its
equilibrium (nominal gap, I0) is linearised by central differences of the same compiled
right-hand side the simulator integrates::

    dx/dt = A x + B u,   s = C x     (u: current deviation from I0 [A], s: gap excursion [m])
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from hyperloop_env.physics.layout import N_SLOTS, NQ, P_I0, P_TAU, Q_UY, Q_UZ, state_size
from hyperloop_env.physics.model import neutral_commands, pack
from hyperloop_env.physics.params import ModelParams
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES
from hyperloop_env.physics.vehicle import NU, rhs

N_VEHICLE_STATES = 2 * NQ
_COORDS: tuple[str, ...] = (
    "heave",
    "lateral",
    "pitch",
    "roll",
    "yaw",
    *(f"y_{u}" for u in UNIT_NAMES),
    *(f"z_{u}" for u in UNIT_NAMES),
)
STATE_NAMES: tuple[str, ...] = _COORDS + tuple(f"d{n}" for n in _COORDS)
"""Names of the vehicle states (coordinates, then rates ``d<name>``), layout order."""


@dataclass(frozen=True)
class LinearModel:
    A: np.ndarray  # (26, 26)
    B: np.ndarray  # (26, n_channels) per ampere of command deviation (ModelParams.actuators)
    C_gap: np.ndarray  # (N_UNITS, 26): gap excursions s_a [m]
    C_lat: np.ndarray  # (N_UNITS, 26): lateral offsets [m]
    nominal_current_A: float
    state_names: tuple[str, ...] = STATE_NAMES

    def eigenvalues(self) -> np.ndarray:
        return np.linalg.eigvals(self.A)

    def index(self, *names: str) -> list[int]:
        """Positions of the named states (see :data:`STATE_NAMES`)."""
        return [self.state_names.index(n) for n in names]


def rigid_straight(params: ModelParams) -> ModelParams:
    """Same vehicle and magnets on a rigid, smooth, straight guideway."""
    return replace(
        params,
        guideway=replace(params.guideway, rigid=True),
        irregularity=replace(params.irregularity, spectrum="none"),
        condition=replace(params.condition, curve_radius_m=math.inf, cant_deg=0.0),
    )


def linearize(params: ModelParams | None = None, rel_step: float = 1e-6) -> LinearModel:
    """Jacobians of the vehicle right-hand side at equilibrium (rigid straight guideway)."""
    p = rigid_straight(params if params is not None else ModelParams())
    P = pack(p)
    P[P_TAU] = 0.0
    nm = p.guideway.n_modes
    n = state_size(nm)
    irr = np.zeros((3, 16))
    spans = np.zeros(N_SLOTS, dtype=np.int64)
    wts = np.zeros((N_UNITS, N_SLOTS, nm))
    uo = np.zeros((NU, N_UNITS))
    i0 = float(P[P_I0])
    cmd0 = neutral_commands(P)
    idx = p.actuators.command_index()
    n_u = len(idx)

    def f(x: np.ndarray, u: np.ndarray) -> np.ndarray:
        y = np.zeros(n)
        y[:N_VEHICLE_STATES] = x
        cur = cmd0.copy()
        cur[idx] += u
        out = np.zeros(n)
        rhs(0.0, y, P, irr, 0.0, cur, cur, spans, out, wts, uo)
        return out[:N_VEHICLE_STATES]

    x0 = np.zeros(N_VEHICLE_STATES)
    u0 = np.zeros(n_u)
    A = np.zeros((N_VEHICLE_STATES, N_VEHICLE_STATES))
    B = np.zeros((N_VEHICLE_STATES, n_u))
    hx = rel_step * 1e-2  # state scale ~ 1 cm / 1 cm/s / 10 mrad
    for j in range(N_VEHICLE_STATES):
        e = np.zeros(N_VEHICLE_STATES)
        e[j] = hx
        A[:, j] = (f(x0 + e, u0) - f(x0 - e, u0)) / (2 * hx)
    hu = rel_step * i0
    for j in range(n_u):
        e = np.zeros(n_u)
        e[j] = hu
        B[:, j] = (f(x0, u0 + e) - f(x0, u0 - e)) / (2 * hu)
    sigma = p.magnet.orientation_sign
    C_gap = np.zeros((N_UNITS, N_VEHICLE_STATES))
    C_lat = np.zeros((N_UNITS, N_VEHICLE_STATES))
    for a in range(N_UNITS):
        C_gap[a, Q_UY + a] = sigma
        C_lat[a, Q_UZ + a] = 1.0
    return LinearModel(A=A, B=B, C_gap=C_gap, C_lat=C_lat, nominal_current_A=i0)
