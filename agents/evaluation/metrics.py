"""Scalar metrics and the STS report of the episodes of one controller × scenario."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from agents.evaluation.rollout import Episode
from hyperloop_env.comfort import comfort_label, ride_comfort
from hyperloop_env.physics.units import N_UNITS
from hyperloop_env.safety import DEFAULT_SAFETY_MARGIN_MM, safety_cost
from hyperloop_env.sts import STSReport, analyse_episodes


def settle_steps(settle_s: float, dt_s: float) -> int:
    """Samples discarded as settling: ceil(settle_s / dt)."""
    return int(math.ceil(settle_s / dt_s - 1e-9)) if settle_s > 0 else 0


def episode_safety_cost(e: Episode, margin_mm: float = DEFAULT_SAFETY_MARGIN_MM) -> float:
    """The episode's summed safety cost (``info["cost"]`` of every step, the indicator with
    ``margin_mm``: :func:`hyperloop_env.safety.safety_cost`; the contact step costs 1)."""
    contact = np.zeros(e.n_steps, dtype=bool)
    if e.terminated and e.n_steps:
        contact[-1] = True
    step = safety_cost(
        e.gap_m[1:], e.lateral_m[1:], e.clearance_m, e.lateral_clearance_m, margin_mm * 1e-3,
        "indicator", contact,
    )  # fmt: skip
    return float(step.sum())


def summarise(
    episodes: list[Episode], settle_s: float, n_boot: int = 200
) -> tuple[STSReport, dict[str, Any], STSReport]:
    """STS reports of both signals and the scalar metrics of the episodes of one
    controller × scenario: (levitation-gap report, metrics, guidance-gap report).

    The two signals: the levitation gap excursion s_a against Ω, and the guidance gap
    excursion z_a (the unit's lateral offset from the guideway) against Ω_g."""
    ep0 = episodes[0]
    dt = ep0.dt_s
    n0 = int(math.ceil(settle_s / dt - 1e-9)) if settle_s > 0 else 0
    report = analyse_episodes(
        [(e.gap_m[1:], bool(e.terminated)) for e in episodes],  # row 0 is the reset state
        dt,
        settle_s=settle_s,
        n_boot=n_boot,
        clearance_m=ep0.clearance_m,
    )
    guidance = analyse_episodes(
        [(e.lateral_m[1:], bool(e.terminated)) for e in episodes],
        dt,
        settle_s=settle_s,
        n_boot=n_boot,
        clearance_m=ep0.lateral_clearance_m,
    )
    post = [e.gap_m[1 + n0 :] for e in episodes]
    post = [g for g in post if len(g)]
    allg = np.concatenate(post) if post else np.empty((0, 4))
    rms_units = np.sqrt(np.mean(allg**2, axis=0)) if len(allg) else np.full(N_UNITS, np.nan)
    lat = np.concatenate([e.lateral_m[1 + n0 :] for e in episodes])
    cur = np.concatenate([e.current_A[1 + n0 :] - e.nominal_current_A for e in episodes])
    gcur = np.concatenate([e.guidance_current_A[1 + n0 :] for e in episodes])
    comfort = [
        ride_comfort(e.acc_m_s2[1:, 0], e.acc_m_s2[1:, 1], dt, settle_s)
        for e in episodes
        if len(e.acc_m_s2) - 1 > n0 + 10
    ]
    costs = [episode_safety_cost(e) for e in episodes]
    contacts = [e for e in episodes if e.terminated]
    first = min(contacts, key=lambda e: e.contact_time_s) if contacts else None

    def _mean(vals: list[float]) -> float:
        v = [x for x in vals if math.isfinite(x)]
        return float(np.mean(v)) if v else math.nan

    a_wz = _mean([c.a_wz_m_s2 for c in comfort])
    a_wy = _mean([c.a_wy_m_s2 for c in comfort])
    a_v = _mean([c.a_v_m_s2 for c in comfort])
    metrics = {
        "controller": ep0.controller,
        "condition": ep0.scenario,
        "magnet": ep0.magnet,
        "speed_kmh": ep0.speed_kmh,
        "curve_radius_m": ep0.curve_radius_m,
        "n_episodes": len(episodes),
        "seeds": [e.seed for e in episodes],
        "distance_km_mean": float(np.mean([e.distance_m for e in episodes])) / 1e3,
        "steps_total": int(sum(e.n_steps for e in episodes)),
        "wall_s": float(sum(e.wall_s for e in episodes)),
        "rms_gap_mm": float(np.sqrt(np.mean(allg**2))) * 1e3 if len(allg) else math.nan,
        "rms_gap_units_mm": (rms_units * 1e3).tolist(),
        "max_abs_gap_mm": float(np.max(np.abs(allg))) * 1e3 if len(allg) else math.nan,
        "mean_lateral_mm": float(np.mean(lat)) * 1e3 if len(lat) else math.nan,
        "max_abs_lateral_mm": float(np.max(np.abs(lat))) * 1e3 if len(lat) else math.nan,
        "rms_lateral_mm": float(np.sqrt(np.mean(lat**2))) * 1e3 if len(lat) else math.nan,
        "rms_current_dev_A": float(np.sqrt(np.mean(cur**2))) if len(cur) else math.nan,
        "rms_guidance_current_A": float(np.sqrt(np.mean(gcur**2))) if len(gcur) else math.nan,
        "safety_cost_episodes": costs,
        "safety_cost_mean": float(np.mean(costs)),
        "n_contact_episodes": len(contacts),
        "time_to_first_contact_s": first.contact_time_s if first else None,
        "position_of_first_contact_m": first.contact_position_m if first else None,
        "contact_kind": first.contact_kind if first else None,
        "contact_times_s": [e.contact_time_s for e in contacts],
        "a_wz_m_s2": a_wz,
        "a_wy_m_s2": a_wy,
        "a_v_m_s2": a_v,
        "comfort": comfort_label(a_v),
        "p_unsteady": report.worst_p_unsteady,
        "unit": report.worst_unit,
        "p_unsteady_units": [u.p_unsteady for u in report.units],
        "p_unsteady_guidance": guidance.worst_p_unsteady,
        "unit_guidance": guidance.worst_unit,
        "p_unsteady_units_guidance": [u.p_unsteady for u in guidance.units],
        "n_samples_after_settle": int(len(allg)),
    }
    return report, metrics, guidance
