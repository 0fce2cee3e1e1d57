"""Linear design models of the vertical and lateral planes (:class:`PlaneModel`), shared by
the PID and LQR controllers.

Source: :func:`hyperloop_env.physics.linearize.linearize` (the 26-state vehicle on a rigid,
straight guideway at equilibrium, ``dx/dt = A x + B u`` with ``u`` the current deviation
from I0 [A]). At equilibrium the lateral plane (lateral, yaw, unit lateral offsets) is
decoupled from the vertical plane and not controllable by the levitation currents
(∂F_z/∂I = 0 at z = 0), so the levitation designs use the 14-state vertical subsystem
(heave, pitch, roll, 4 unit heights and their rates, :func:`vertical_model`); the guidance
pairs' differential currents act on the 12-state lateral subsystem (:func:`lateral_model`).
The coil lag (first order, τ = ``coil_time_constant_s``:
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
class PlaneModel:
    """Continuous design model of one plane, ``dx/dt = A x + B u`` (u: commanded current
    deviation [A] of the plane's 4 input channels); with τ > 0 the last 4 states are the
    coil currents (deviation, [A]).

    ``C_gap`` (4, n): the plane's gap excursions [m] (vertical: the levitation gaps,
    lateral: the guidance gaps z_a); ``c_acc`` (n,): the capsule's acceleration in the plane
    [m/s²] (heave, lateral); ``C_cur`` (4, n): applied current deviation [A] (rows of zeros
    if τ = 0, where the applied current is the command itself); ``sigma``: the gap's sign
    per unit of unit displacement (the magnet orientation; 1 for the lateral plane);
    ``states``: the names of the vehicle states (the first ``n_vehicle`` of ``A``)."""

    A: np.ndarray
    B: np.ndarray
    C_gap: np.ndarray
    c_acc: np.ndarray
    C_cur: np.ndarray
    sigma: float
    tau_s: float
    nominal_current_A: float
    states: tuple[str, ...]

    @property
    def n(self) -> int:
        return self.A.shape[0]

    @property
    def n_vehicle(self) -> int:
        return len(self.states)


def _plane_model(
    A: np.ndarray,
    B: np.ndarray,
    C_gap: np.ndarray,
    c_acc: np.ndarray,
    sigma: float,
    tau: float,
    nominal_current_A: float,
    states: tuple[str, ...],
) -> PlaneModel:
    """The plane's model, with the first-order coil lag (time constant ``tau`` [s])
    appended as 4 states when ``tau > 0``."""
    nv = len(states)
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
        return PlaneModel(Aa, Ba, Cg, ca, Cc, sigma, tau, nominal_current_A, states)
    return PlaneModel(A, B, C_gap, c_acc, np.zeros((nu, nv)), sigma, 0.0, nominal_current_A, states)


@lru_cache(maxsize=32)
def _vertical_model_cached(params: ModelParams) -> PlaneModel:
    lm = linearize(params.with_(actuators="levitation"))
    idx = np.array(VERTICAL_INDEX)
    A = lm.A[np.ix_(idx, idx)]
    return _plane_model(
        A,
        lm.B[idx],
        lm.C_gap[:, idx],
        A[HEAVE_RATE_ROW],  # d(heave rate)/dt = capsule heave acceleration
        params.magnet.orientation_sign,
        params.magnet.coil_time_constant_s,
        lm.nominal_current_A,
        VERTICAL_STATES,
    )


def vertical_model(params: ModelParams) -> PlaneModel:
    """The vertical design model (14 states + the levitation coils' lag; inputs: the
    levitation currents' deviation from I0 [A]), cached per parameter set."""
    return _vertical_model_cached(params)


@lru_cache(maxsize=32)
def _lateral_model_cached(params: ModelParams) -> PlaneModel:
    lm = linearize(params.with_(actuators="levitation+guidance"))
    idx = np.array(LATERAL_INDEX)
    A = lm.A[np.ix_(idx, idx)]
    return _plane_model(
        A,
        lm.B[idx][:, N_UNITS : 2 * N_UNITS],  # the guidance pairs' differential currents
        lm.C_lat[:, idx],
        A[LATERAL_RATE_ROW],  # capsule lateral acceleration (track frame)
        1.0,  # z_rel = z on a rigid track
        params.magnet.coil_time_constant_s,
        lm.nominal_current_A,
        LATERAL_STATES,
    )


def lateral_model(params: ModelParams) -> PlaneModel:
    """The lateral design model (12 states + the guidance coils' lag; inputs: the guidance
    pairs' differential currents [A]; ``C_gap`` rows: the guidance gap excursions z_a,
    ``c_acc``: the capsule's lateral acceleration), cached per parameter set."""
    return _lateral_model_cached(params)


def c2d(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation (matrix exponential of the block matrix)."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A * dt
    M[:n, n:] = B * dt
    E = expm(M)
    return E[:n, :n], E[:n, n:]
