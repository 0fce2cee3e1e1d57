"""Observation layout and action map shared by the environments and the controllers.

Observation (float32, what a real vehicle measures; every entry scaled to O(1)):

====================  ==========  ===========================================  ===============
slice                 name        meaning                                      scaling
====================  ==========  ===========================================  ===============
``OBS_GAP``  0–3      gap         gap excursion s_a of FL, FR, RL, RR [m]      / clearance Ω
``OBS_GAP_RATE`` 4–7  gap rate    ds_a/dt (backward difference of the gap      / 1 m/s
                                  sensor over one control interval) [m/s]
``OBS_LAT``  8–11     lateral     lateral offset of each unit from its rail    / lateral clearance
``OBS_ACC``  12–13    accel.      capsule heave and lateral acceleration       / g
                                  (track frame) [m/s²]
``OBS_CURRENT`` 14–17 current     applied coil current I_a [A]                 I_a/I0 − 1
``OBS_SPEED`` 18      speed       v [m/s]                                      / (2000 km/h)
``OBS_CURV``  19–22   curvature   κ at the capsule and 250, 500, 1000 m ahead  × 1e5 m
====================  ==========  ===========================================  ===============

Action: ``Box(-1, 1, (4,), float32)``, one entry per unit, mapped affinely to the commanded
coil current ``I_a = I0·(1 + action_scale·a)`` [A] (default ``action_scale = 1``: 0 … 2·I0),
then limited to the physical range [0, I_max] by the simulator.
"""

from __future__ import annotations

import numpy as np

OBS_GAP = slice(0, 4)
OBS_GAP_RATE = slice(4, 8)
OBS_LAT = slice(8, 12)
OBS_ACC = slice(12, 14)
OBS_CURRENT = slice(14, 18)
OBS_SPEED = 18
PREVIEW_DISTANCES_M: tuple[float, ...] = (0.0, 250.0, 500.0, 1000.0)
OBS_CURV = slice(19, 19 + len(PREVIEW_DISTANCES_M))
OBS_SIZE = 19 + len(PREVIEW_DISTANCES_M)

GAP_RATE_SCALE_M_S = 1.0
SPEED_SCALE_M_S = 2000.0 / 3.6
CURVATURE_SCALE_M = 1e5


def action_to_current(
    action: np.ndarray, i0: float | np.ndarray, action_scale: float = 1.0
) -> np.ndarray:
    """Commanded currents [A] for normalised actions in [-1, 1]: I0·(1 + scale·a).

    ``i0`` is a scalar, or shape (N,) for a batch of actions of shape (N, 4)."""
    i0 = np.asarray(i0, dtype=np.float64)
    if i0.ndim:
        i0 = i0[..., None]
    return i0 * (1.0 + action_scale * np.asarray(action, dtype=np.float64))


def current_to_action(current: np.ndarray, i0: float, action_scale: float = 1.0) -> np.ndarray:
    """Inverse of :func:`action_to_current` (not clipped)."""
    return (np.asarray(current) / i0 - 1.0) / action_scale
