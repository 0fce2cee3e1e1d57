"""Closed-loop episodes of a controller in the Gymnasium environment.

:func:`run_episode` builds ``HyperloopSuspension-v0`` for one configuration, runs a
controller until contact (termination) or the end of the track section (truncation) and
returns an :class:`Episode` with the recorded signals. The runner (not the controller)
copies the simulator's measurement record after every step (``env.unwrapped.sim.meas``,
named fields in ``hyperloop_env.physics.RECORD_FIELDS``): the same values the env
reports in ``info``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

from hyperloop_env import ENV_ID
from hyperloop_env.config import EnvConfig
from hyperloop_env.physics import RECORD_FIELDS

_T = RECORD_FIELDS["time_s"].start
_X = RECORD_FIELDS["position_m"].start
_GAP = RECORD_FIELDS["gap_excursion_m"]
_LAT = RECORD_FIELDS["lateral_offset_m"]
_CUR = RECORD_FIELDS["current_A"]
_ACC = RECORD_FIELDS["acceleration_heave_lateral"]
_IG = RECORD_FIELDS["guidance_current_A"]


def make_env(config: EnvConfig | str, **kwargs: Any) -> gym.Env:
    """``gymnasium.make`` of the environment for a config (or a scenario name and keyword
    arguments), without the passive environment checker."""
    cfg = config if isinstance(config, EnvConfig) else EnvConfig.from_kwargs(scenario=config)
    if kwargs:
        cfg = cfg.replace(**kwargs)
    return gym.make(ENV_ID, config=cfg, disable_env_checker=True)


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
    clearance_m: float
    lateral_clearance_m: float
    time_s: np.ndarray
    position_m: np.ndarray
    gap_m: np.ndarray  # (T, 4)
    lateral_m: np.ndarray  # (T, 4) guidance gap excursion (lateral offset from the guideway)
    current_A: np.ndarray  # (T, 4) levitation coil currents
    guidance_current_A: np.ndarray  # (T, 4) guidance pairs' differential currents
    acc_m_s2: np.ndarray  # (T, 2) heave, lateral
    terminated: bool
    contact_time_s: float | None
    contact_position_m: float | None
    contact_kind: str | None  # "gap", "lateral", "gap+lateral" or None
    wall_s: float
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def n_steps(self) -> int:
        return len(self.time_s) - 1

    @property
    def distance_m(self) -> float:
        return float(self.position_m[-1] - self.position_m[0])


def _episode_from_records(
    rec: np.ndarray, n: int, terminated: bool, meta: dict[str, Any]
) -> Episode:
    r = rec[:n]
    ct = cp = ck = None
    if terminated:
        last = r[-1]
        ct, cp = float(last[_T]), float(last[_X])
        gap_hit = np.abs(last[_GAP]) >= meta["clearance_m"]
        lat_hit = np.abs(last[_LAT]) >= meta["lateral_clearance_m"]
        ck = "gap" if gap_hit.any() or not lat_hit.any() else "lateral"
        if gap_hit.any() and lat_hit.any():
            ck = "gap+lateral"
    r = np.where(np.isfinite(r), r, np.nan)
    return Episode(
        time_s=r[:, _T].copy(),
        position_m=r[:, _X].copy(),
        gap_m=r[:, _GAP].copy(),
        lateral_m=r[:, _LAT].copy(),
        current_A=r[:, _CUR].copy(),
        guidance_current_A=r[:, _IG].copy(),
        acc_m_s2=r[:, _ACC].copy(),
        terminated=terminated,
        contact_time_s=ct,
        contact_position_m=cp,
        contact_kind=ck,
        **meta,
    )


def episode_config(
    scenario: str | EnvConfig,
    distance_km: float,
    magnet: str | None = None,
    env_kwargs: dict[str, Any] | None = None,
) -> EnvConfig:
    """The environment configuration of an evaluation episode: the scenario (or config)
    with its track section set to ``distance_km`` and the given overrides."""
    cfg = scenario if isinstance(scenario, EnvConfig) else EnvConfig(scenario=scenario)
    kw: dict[str, Any] = {"track_length_m": float(distance_km) * 1000.0}
    if magnet is not None:
        kw["magnet"] = magnet
    kw.update(env_kwargs or {})
    return cfg.replace(**kw)


def run_episode(
    controller_factory: Callable[[gym.Env], Any],
    scenario: str | EnvConfig,
    seed: int,
    distance_km: float,
    magnet: str | None = "repelling",
    env_kwargs: dict[str, Any] | None = None,
    step_callback: Callable[[int], None] | None = None,
) -> Episode:
    """Run one episode; ``controller_factory(env)`` builds the controller after the reset
    (so it sees the episode's parameters). ``step_callback(n)`` is called every 1000 steps
    with the number of steps done since the previous call (progress bars)."""
    cfg = episode_config(scenario, distance_km, magnet, env_kwargs)
    env = make_env(cfg)
    try:
        obs, _ = env.reset(seed=int(seed))
        u = env.unwrapped
        ctrl = controller_factory(env)
        ctrl.reset(seed=int(seed))
        sim = u.sim
        p = sim.params
        n_max = int(u.max_episode_steps)
        rec = np.empty((n_max + 1, sim.meas.shape[0]))
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
            scenario=cfg.scenario,
            seed=int(seed),
            magnet=p.magnet.orientation,
            dt_s=p.simulation.control_dt_s,
            speed_kmh=p.condition.speed_kmh,
            curve_radius_m=p.condition.curve_radius_m,
            nominal_current_A=sim.nominal_current_A,
            clearance_m=p.magnet.clearance_m,
            lateral_clearance_m=p.guidance.clearance_m,
            wall_s=wall,
        )
        return _episode_from_records(rec, k + 1, bool(terminated), meta)
    finally:
        env.close()
