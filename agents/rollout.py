"""Closed-loop episodes of a controller in the Gymnasium environment.

:func:`run_episode` builds ``HyperloopSuspension-v0`` for one scenario, runs a controller
until contact (termination) or the end of the track section (truncation) and returns an
:class:`Episode` with the recorded signals. The runner (not the controller) copies the
simulator's measurement record after every step (``env.unwrapped.sim.meas``, layout in
:mod:`hyperloop_env.physics.layout`): the same values the env reports in ``info``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

from hyperloop_env.physics.layout import (
    M_ACC_HEAVE,
    M_ACC_LAT,
    M_GAP,
    M_I,
    M_LAT,
    M_T,
    M_X,
    NM,
)

ENV_ID = "HyperloopSuspension-v0"


def make_env(scenario: str, **kwargs: Any) -> gym.Env:
    """The environment (``gymnasium.make`` if registered, else the class directly)."""
    import hyperloop_env  # noqa: F401  (registers the env when the package does)

    if ENV_ID in gym.registry:
        return gym.make(ENV_ID, scenario=scenario, disable_env_checker=True, **kwargs)
    from hyperloop_env.env import HyperloopSuspensionEnv

    return HyperloopSuspensionEnv(scenario, **kwargs)


@dataclass
class Episode:
    """Signals of one closed-loop run (row 0 is the reset state, then one row per step)."""

    controller: str
    scenario: str
    seed: int
    magnet: str
    dt_s: float
    speed_kmh: float
    curve_radius_m: float
    nominal_current_A: float
    time_s: np.ndarray
    position_m: np.ndarray
    gap_m: np.ndarray  # (T, 4)
    lateral_m: np.ndarray  # (T, 4)
    current_A: np.ndarray  # (T, 4)
    acc_m_s2: np.ndarray  # (T, 2) heave, lateral
    terminated: bool
    contact_time_s: float | None
    contact_position_m: float | None
    contact_kind: str | None  # "gap", "lateral" or None
    wall_s: float
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def n_steps(self) -> int:
        return len(self.time_s) - 1

    @property
    def distance_m(self) -> float:
        return float(self.position_m[-1] - self.position_m[0])


def _episode_from_records(
    rec: np.ndarray, n: int, terminated: bool, meta: dict[str, Any], clear: float, latc: float
) -> Episode:
    r = rec[:n]
    ct = cp = ck = None
    if terminated:
        last = r[-1]
        ct, cp = float(last[M_T]), float(last[M_X])
        gap_hit = np.abs(last[M_GAP : M_GAP + 4]) >= clear
        lat_hit = np.abs(last[M_LAT : M_LAT + 4]) >= latc
        ck = "gap" if gap_hit.any() or not lat_hit.any() else "lateral"
        if gap_hit.any() and lat_hit.any():
            ck = "gap+lateral"
    r = np.where(np.isfinite(r), r, np.nan)
    return Episode(
        time_s=r[:, M_T].copy(),
        position_m=r[:, M_X].copy(),
        gap_m=r[:, M_GAP : M_GAP + 4].copy(),
        lateral_m=r[:, M_LAT : M_LAT + 4].copy(),
        current_A=r[:, M_I : M_I + 4].copy(),
        acc_m_s2=r[:, M_ACC_HEAVE : M_ACC_LAT + 1].copy(),
        terminated=terminated,
        contact_time_s=ct,
        contact_position_m=cp,
        contact_kind=ck,
        **meta,
    )


def run_episode(
    controller_factory: Callable[[gym.Env], Any],
    scenario: str,
    seed: int,
    distance_km: float,
    magnet: str = "repelling",
    env_kwargs: dict[str, Any] | None = None,
    step_callback: Callable[[int], None] | None = None,
) -> Episode:
    """Run one episode; ``controller_factory(env)`` builds the controller after the reset
    (so it sees the episode's parameters). ``step_callback(n)`` is called every 1000 steps
    with the number of steps done since the previous call (progress bars)."""
    env = make_env(
        scenario, track_length_m=float(distance_km) * 1000.0, magnet=magnet, **(env_kwargs or {})
    )
    try:
        obs, _ = env.reset(seed=int(seed))
        u = env.unwrapped
        ctrl = controller_factory(env)
        ctrl.reset(seed=int(seed))
        sim = u.sim
        p = sim.params
        n_max = int(u.max_episode_steps)
        rec = np.empty((n_max + 1, NM))
        rec[0] = sim.meas
        t0 = time.perf_counter()
        step = env.step
        act = ctrl.act
        k = 0
        terminated = False
        last_cb = 0
        while True:
            obs, _, terminated, truncated, _ = step(act(obs))
            k += 1
            rec[k] = sim.meas
            if step_callback is not None and k - last_cb >= 1000:
                step_callback(k - last_cb)
                last_cb = k
            if terminated or truncated:
                break
        if step_callback is not None and k > last_cb:
            step_callback(k - last_cb)
        wall = time.perf_counter() - t0
        meta = dict(
            controller=getattr(ctrl, "name", type(ctrl).__name__),
            scenario=scenario,
            seed=int(seed),
            magnet=magnet,
            dt_s=p.simulation.control_dt_s,
            speed_kmh=p.condition.speed_kmh,
            curve_radius_m=p.condition.curve_radius_m,
            nominal_current_A=sim.nominal_current_A,
            wall_s=wall,
        )
        return _episode_from_records(
            rec, k + 1, bool(terminated), meta, p.magnet.clearance_m, p.magnet.lateral_clearance_m
        )
    finally:
        env.close()


def expected_steps(speed_kmh: float, distance_km: float, dt_s: float = 1e-3) -> int:
    """Control steps to cover ``distance_km`` at ``speed_kmh`` (as the env truncates)."""
    return max(1, math.ceil(distance_km * 1000.0 / (speed_kmh / 3.6 * dt_s) - 1e-9))
