"""Linear design models shared by the PID and LQR controllers (levitation channels).

Source: :func:`hyperloop_env.physics.linearize.linearize` (the 26-state vehicle on a rigid,
straight guideway at equilibrium, ``dx/dt = A x + B u`` with ``u`` the current deviation
from I0 [A]). At equilibrium the lateral plane (lateral, yaw, unit lateral offsets) is
decoupled from the vertical plane and not controllable by the currents (∂F_z/∂I = 0 at
z = 0), so the designs use the 14-state vertical subsystem (heave, pitch, roll, 4 unit
heights and their rates). The coil lag (first order, τ = ``coil_time_constant_s``:
``dI/dt = (I_cmd − I)/τ``, exactly what the simulator integrates) is appended as 4 states
when τ > 0. Discretisation: zero-order hold at the control interval (the simulator holds
the command over the interval).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.linalg import expm

from hyperloop_env.physics.linearize import STATE_NAMES, linearize
from hyperloop_env.physics.params import ModelParams
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES

_VERT = ["heave", "pitch", "roll", *(f"y_{u}" for u in UNIT_NAMES)]
VERTICAL_STATES: tuple[str, ...] = (*_VERT, *(f"d{n}" for n in _VERT))
"""The 14 vertical-plane states (heave, pitch, roll, unit heights and their rates)."""
VERTICAL_INDEX: tuple[int, ...] = tuple(STATE_NAMES.index(n) for n in VERTICAL_STATES)
"""Their positions in the state vector of ``linearize``."""
HEAVE_RATE_ROW = VERTICAL_STATES.index("dheave")

_LAT = ["lateral", "yaw", *(f"z_{u}" for u in UNIT_NAMES)]
LATERAL_STATES: tuple[str, ...] = (*_LAT, *(f"d{n}" for n in _LAT))
"""The 12 lateral-plane states (capsule lateral and yaw, unit lateral offsets, rates)."""
LATERAL_INDEX: tuple[int, ...] = tuple(STATE_NAMES.index(n) for n in LATERAL_STATES)
LATERAL_RATE_ROW = LATERAL_STATES.index("dlateral")


@dataclass(frozen=True)
class VerticalModel:
    """Continuous vertical-plane model ``dx/dt = A x + B u`` (u: commanded current
    deviation [A]); with τ > 0 the last 4 states are the coil currents (deviation, [A]).

    ``C_gap`` (4, n): gap excursions [m]; ``c_acc`` (n,): capsule heave acceleration
    [m/s²]; ``C_cur`` (4, n): applied current deviation [A] (rows of zeros if τ = 0, where
    the applied current is the command itself)."""

    A: np.ndarray
    B: np.ndarray
    C_gap: np.ndarray
    c_acc: np.ndarray
    C_cur: np.ndarray
    sigma: float
    tau_s: float
    nominal_current_A: float

    @property
    def n(self) -> int:
        return self.A.shape[0]

    @property
    def n_vehicle(self) -> int:
        return len(VERTICAL_INDEX)


@lru_cache(maxsize=32)
def _vertical_model_cached(params: ModelParams) -> VerticalModel:
    lm = linearize(params.with_(actuators="levitation"))
    idx = np.array(VERTICAL_INDEX)
    A = lm.A[np.ix_(idx, idx)]
    B = lm.B[idx]
    C_gap = lm.C_gap[:, idx]
    c_acc = A[HEAVE_RATE_ROW]  # d(heave rate)/dt = capsule heave acceleration
    tau = params.magnet.coil_time_constant_s
    nv = len(idx)
    nu = N_UNITS
    if tau > 0:
        n = nv + nu
        Aa = np.zeros((n, n))
        Aa[:nv, :nv] = A
        Aa[:nv, nv:] = B
        Aa[nv:, nv:] = -np.eye(nu) / tau
        Ba = np.zeros((n, nu))
        Ba[nv:] = np.eye(nu) / tau
        Cg = np.hstack([C_gap, np.zeros((nu, nu))])
        ca = np.concatenate([c_acc, np.zeros(nu)])
        Cc = np.hstack([np.zeros((nu, nv)), np.eye(nu)])
        return VerticalModel(
            Aa, Ba, Cg, ca, Cc, params.magnet.orientation_sign, tau, lm.nominal_current_A
        )
    return VerticalModel(
        A,
        B,
        C_gap,
        c_acc,
        np.zeros((nu, nv)),
        params.magnet.orientation_sign,
        0.0,
        lm.nominal_current_A,
    )


def vertical_model(params: ModelParams) -> VerticalModel:
    """The vertical design model for ``params`` (cached per parameter set)."""
    return _vertical_model_cached(params)


@lru_cache(maxsize=32)
def _lateral_model_cached(params: ModelParams) -> VerticalModel:
    lm = linearize(params.with_(actuators="levitation+guidance"))
    idx = np.array(LATERAL_INDEX)
    A = lm.A[np.ix_(idx, idx)]
    B = lm.B[idx][:, N_UNITS : 2 * N_UNITS]  # the guidance pairs' differential currents
    C_lat = lm.C_lat[:, idx]
    c_acc = A[LATERAL_RATE_ROW]  # capsule lateral acceleration (track frame)
    tau = params.magnet.coil_time_constant_s
    nv = len(idx)
    nu = N_UNITS
    if tau > 0:
        n = nv + nu
        Aa = np.zeros((n, n))
        Aa[:nv, :nv] = A
        Aa[:nv, nv:] = B
        Aa[nv:, nv:] = -np.eye(nu) / tau
        Ba = np.zeros((n, nu))
        Ba[nv:] = np.eye(nu) / tau
        Cl = np.hstack([C_lat, np.zeros((nu, nu))])
        ca = np.concatenate([c_acc, np.zeros(nu)])
        Cc = np.hstack([np.zeros((nu, nv)), np.eye(nu)])
        return VerticalModel(Aa, Ba, Cl, ca, Cc, 1.0, tau, lm.nominal_current_A)
    return VerticalModel(A, B, C_lat, c_acc, np.zeros((nu, nv)), 1.0, 0.0, lm.nominal_current_A)


def lateral_model(params: ModelParams) -> VerticalModel:
    """The lateral design model (12 states + the guidance coils' lag; inputs: the guidance
    pairs' differential currents [A]; ``C_gap`` rows: the guidance gap excursions z_a,
    ``c_acc``: the capsule's lateral acceleration), cached per parameter set. Same record
    type as :func:`vertical_model` (``sigma`` is 1: z_rel = z on a rigid track)."""
    return _lateral_model_cached(params)


def c2d(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation (matrix exponential of the block matrix)."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A * dt
    M[:n, n:] = B * dt
    E = expm(M)
    return E[:n, :n], E[:n, n:]
