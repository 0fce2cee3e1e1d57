"""The safety cost: a constraint signal beside the reward, for the benchmark's one hard
constraint, the clearance (Safety-Gymnasium's convention: ``info["cost"]`` every step, as
TorchRL and OmniSafe read it).

With the levitation gap excursions s_a [m] (a = FL, FR, RL, RR) against the clearance Ω
[m], the guidance gap excursions z_a [m] against the guidance clearance Ω_g [m], and the
safety margin m [m] (``safety_margin_mm`` / 1000; 0 ≤ m < min(Ω, Ω_g)):

* ``"indicator"`` (the default): c = 1 if any |s_a| > Ω − m or any |z_a| > Ω_g − m, else 0;
* ``"continuous"``: c = max(0, max_a (|s_a| − (Ω − m)) / m, max_a (|z_a| − (Ω_g − m)) / m):
  0 inside the margin, 1 at the clearance, growing beyond it (with m = 0: the indicator).

A step that ends in contact (the simulator's contact flag, also set when the state diverges)
costs at least 1, so every episode that ends in contact has a cost > 0. The cost does not
enter the reward.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

COST_KINDS: tuple[str, ...] = ("indicator", "continuous")
DEFAULT_SAFETY_MARGIN_MM = 2.0


def check_margin(margin_m: float, clearance_m: float, lateral_clearance_m: float) -> None:
    """``ValueError`` naming ``safety_margin_mm`` unless 0 ≤ m < min(Ω, Ω_g)."""
    top = min(clearance_m, lateral_clearance_m)
    if not (math.isfinite(margin_m) and 0.0 <= margin_m < top):
        raise ValueError(
            f"safety_margin_mm must be in [0, {top * 1e3:g}) mm (below the smaller clearance), "
            f"got {margin_m * 1e3!r}"
        )


def safety_cost(
    gap_m: Any,
    lateral_m: Any,
    clearance_m: float,
    lateral_clearance_m: float,
    margin_m: float,
    kind: str = "indicator",
    contact: Any = False,
) -> np.ndarray:
    """The safety cost of each step (module docstring).

    Args:
        gap_m: levitation gap excursions s_a [m], shape (..., 4).
        lateral_m: guidance gap excursions z_a [m], shape (..., 4).
        clearance_m, lateral_clearance_m: Ω and Ω_g [m].
        margin_m: the safety margin m [m].
        kind: ``"indicator"`` or ``"continuous"``.
        contact: the contact flag of each step, shape (...) (or a bool).

    Returns:
        float64 array of shape (...), ≥ 0.
    """
    if kind not in COST_KINDS:
        raise ValueError(f"cost kind must be one of {COST_KINDS}, got {kind!r}")
    over_gap = np.abs(np.asarray(gap_m, dtype=np.float64)) - (clearance_m - margin_m)
    over_lat = np.abs(np.asarray(lateral_m, dtype=np.float64)) - (lateral_clearance_m - margin_m)
    worst = np.maximum(over_gap.max(axis=-1), over_lat.max(axis=-1))
    if kind == "indicator" or margin_m == 0.0:
        cost = (worst > 0.0).astype(np.float64)
    else:
        cost = np.maximum(worst, 0.0) / margin_m
    return np.where(np.asarray(contact, dtype=bool), np.fmax(cost, 1.0), cost)
