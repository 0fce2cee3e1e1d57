"""The evaluation's summed safety cost per episode (``safety_cost_episodes``): the env's
``info["cost"]`` rule (indicator, 2 mm margin) over the recorded steps, by hand."""

from __future__ import annotations

import numpy as np

from agents.evaluation.metrics import episode_safety_cost
from agents.evaluation.rollout import Episode

MM = 1e-3


def episode(gap_mm: list[list[float]], lat_mm: list[list[float]], terminated: bool) -> Episode:
    t = len(gap_mm)
    z = np.zeros((t, 4))
    return Episode(
        controller="hand", scenario="paper-1000-straight", seed=0, magnet="repelling",
        dt_s=1e-3, speed_kmh=1000.0, curve_radius_m=np.inf, nominal_current_A=100.0,
        clearance_m=8 * MM, lateral_clearance_m=8 * MM, time_s=np.arange(t) * 1e-3,
        position_m=np.zeros(t), gap_m=np.asarray(gap_mm) * MM, lateral_m=np.asarray(lat_mm) * MM,
        current_A=z, guidance_current_A=z, acc_m_s2=np.zeros((t, 2)), terminated=terminated,
        contact_time_s=None, contact_position_m=None, contact_kind=None, wall_s=0.0,
    )  # fmt: skip


def test_summed_cost_by_hand() -> None:
    q = [0.0, 0.0, 0.0, 0.0]
    gaps = [[9.0, 0, 0, 0], q, q, [0, -7.0, 0, 0], q]  # row 0: the reset state, not a step
    lats = [q, q, [0, 0, 6.2, 0], q, [0, 0, 0, 5.0]]
    assert episode_safety_cost(episode(gaps, lats, False)) == 2.0  # steps 2 and 3
    assert episode_safety_cost(episode(gaps, lats, True)) == 3.0  # the last step touched
    assert episode_safety_cost(episode(gaps, lats, False), margin_mm=1.5) == 1.0  # 7 > 6.5 mm
