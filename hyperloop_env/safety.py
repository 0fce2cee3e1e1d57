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
costs at least 1, so every episode that ends in contact has a cost above 0; so does a step
with a non-finite excursion. The cost does not enter the reward. One compiled loop
(:func:`costs_into`) computes it for the environments' every step and for recorded runs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numba as nb
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


@dataclass(frozen=True)
class CostLimits:
    """What the cost of a step needs besides its excursions: the thresholds Ω − m and
    Ω_g − m [m], the margin m [m] and whether the cost is graded (``"continuous"``)."""

    gap_m: float
    lateral_m: float
    margin_m: float
    graded: bool

    @classmethod
    def of(
        cls, clearance_m: float, lateral_clearance_m: float, margin_m: float, kind: str
    ) -> CostLimits:
        if kind not in COST_KINDS:
            raise ValueError(f"cost kind must be one of {COST_KINDS}, got {kind!r}")
        m = float(margin_m)
        return cls(clearance_m - m, lateral_clearance_m - m, m, kind == "continuous" and m > 0)


@nb.njit(cache=True)
def _costs(gap, lat, lim_gap, lim_lat, margin, graded, contact, out):  # pragma: no cover
    for i in range(gap.shape[0]):
        worst = -np.inf
        bad = False
        for a in range(gap.shape[1]):
            e = abs(gap[i, a]) - lim_gap
            bad = bad or not math.isfinite(e)
            worst = max(worst, e)
        for a in range(lat.shape[1]):
            e = abs(lat[i, a]) - lim_lat
            bad = bad or not math.isfinite(e)
            worst = max(worst, e)
        c = max(worst, 0.0) / margin if graded else (1.0 if worst > 0.0 else 0.0)
        out[i] = max(c, 1.0) if (bad or contact[i]) else c


def costs_into(
    gap_m: np.ndarray, lateral_m: np.ndarray, limits: CostLimits, contact: np.ndarray,
    out: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """The cost of each row (step or vehicle) into ``out`` (n,): ``gap_m``, ``lateral_m``
    (n, 4) [m], ``contact`` (n,) bool; the environments' per-step path (no checks)."""
    _costs(gap_m, lateral_m, limits.gap_m, limits.lateral_m, limits.margin_m, limits.graded,
           contact, out)  # fmt: skip
    return out


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
    limits = CostLimits.of(clearance_m, lateral_clearance_m, margin_m, kind)
    g = np.asarray(gap_m, dtype=np.float64)
    z = np.asarray(lateral_m, dtype=np.float64)
    shape = g.shape[:-1]
    c = np.broadcast_to(np.asarray(contact, dtype=np.bool_), shape).reshape(-1)
    out = np.empty(c.size)
    costs_into(g.reshape(-1, g.shape[-1]), z.reshape(-1, z.shape[-1]), limits, c, out)
    return out.reshape(shape)
