"""Closed-loop episodes of a controller in the Gymnasium environment.

:func:`run_episodes` runs a controller on one configuration for a list of seeds, each
until contact (termination) or the end of the track section (truncation), on the rollout
engine (:mod:`agents.evaluation.engine`), and returns one :class:`Episode` per seed with
every measurement record (``hyperloop_env.physics.RECORD_FIELDS``: the values the env
reports in ``info``). :func:`run_episode` is the one-seed case. The controller's actions
are checked (:func:`~agents.controllers.base.checked_controller`): one of the wrong shape,
NaN or infinite is a :class:`~agents.controllers.base.ControllerError` naming the
controller and the control step.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

from agents.controllers.base import checked_controller, control_context
from agents.evaluation import engine
from hyperloop_env import ENV_ID
from hyperloop_env.config import EnvConfig
from hyperloop_env.physics import RECORD_FIELDS
from hyperloop_env.physics.model import episode_steps

_T = RECORD_FIELDS["time_s"].start
_X = RECORD_FIELDS["position_m"].start
_GAP = RECORD_FIELDS["gap_excursion_m"]
_LAT = RECORD_FIELDS["lateral_offset_m"]
_CUR = RECORD_FIELDS["current_A"]
_ACC = RECORD_FIELDS["acceleration_heave_lateral"]
_IG = RECORD_FIELDS["guidance_current_A"]

_FIELDS = {  # Episode field -> record slice
    "time_s": slice(_T, _T + 1),
    "position_m": slice(_X, _X + 1),
    "gap_m": _GAP,
    "lateral_m": _LAT,
    "current_A": _CUR,
    "guidance_current_A": _IG,
    "acc_m_s2": _ACC,
}
_KEPT = np.concatenate([np.arange(sl.start, sl.stop) for sl in _FIELDS.values()])
"""Record columns an :class:`Episode` keeps (the runner stores only these)."""


def _episode_columns() -> dict[str, Any]:
    """Episode field -> its column (a scalar field) or columns in the :data:`_KEPT` record."""
    out: dict[str, Any] = {}
    k = 0
    for name, sl in _FIELDS.items():
        w = sl.stop - sl.start
        out[name] = k if w == 1 else slice(k, k + w)
        k += w
    return out


_EPISODE_COLUMNS = _episode_columns()


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
    rec: np.ndarray, last: np.ndarray, terminated: bool, meta: dict[str, Any]
) -> Episode:
    """An :class:`Episode` from a run's records in the :data:`_KEPT` columns (``rec``) and
    its last full record (``last``)."""
    ct = cp = ck = None
    if terminated:
        ct, cp = float(last[_T]), float(last[_X])
        ck = engine.contact_kind(last, meta["clearance_m"], meta["lateral_clearance_m"])
    r = np.where(np.isfinite(rec), rec, np.nan)
    return Episode(
        **{name: r[:, sl].copy() for name, sl in _EPISODE_COLUMNS.items()},
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


class _Signals:
    """The engine's recorder of whole runs: every record of each job (row 0 = the reset
    state), kept per job index of a :class:`engine.Jobs` schedule."""

    def __init__(self, jobs: engine.Jobs, rows: int, n_steps: int) -> None:
        self.jobs = jobs
        self.buf = np.empty((rows, n_steps + 1, _KEPT.size))
        self.records: list[np.ndarray | None] = [None] * len(jobs.jobs)
        self.i0 = np.zeros(rows)  # each row's nominal current I0 of its episode [A]
        self.nominal_current_A = [0.0] * len(jobs.jobs)
        self.venv: Any = None

    def attach(self, venv: Any) -> None:
        self.venv = venv

    def started(self, row: int, job: engine.Job, meas_row: np.ndarray) -> None:
        self.buf[row, 0] = meas_row[_KEPT]
        self.i0[row] = float(np.asarray(self.venv.nominal_current_A)[row])

    def step(self, meas: np.ndarray, active: np.ndarray, row_steps: np.ndarray) -> None:
        ix = np.flatnonzero(active)
        k = row_steps[ix]
        if k.max() >= self.buf.shape[1]:  # a run longer than planned (a braking profile)
            grow = np.empty((self.buf.shape[0], 2 * self.buf.shape[1], _KEPT.size))
            grow[:, : self.buf.shape[1]] = self.buf
            self.buf = grow
        self.buf[ix, k] = meas[ix][:, _KEPT]

    def ended(self, row: int, job: engine.Job, end: engine.End) -> None:
        j = self.jobs.index[row]
        self.records[j] = self.buf[row, : end.n_steps + 1].copy()
        self.nominal_current_A[j] = float(self.i0[row])


MAX_ROWS = 32
"""Most seeds :func:`run_episodes` flies at once (more wait for a free row)."""


def run_episodes(
    controller: str | Callable[[Any], Any],
    scenario: str | EnvConfig,
    seeds: Sequence[int],
    distance_km: float,
    magnet: str | None = "repelling",
    env_kwargs: dict[str, Any] | None = None,
    step_callback: Callable[[int], None] | None = None,
    controller_kwargs: dict[str, Any] | None = None,
) -> list[Episode]:
    """One episode per seed on the rollout engine (:mod:`agents.evaluation.engine`): the
    seeds at once (at most :data:`MAX_ROWS` at a time), one row each, when the controller
    has ``act_batch``, else one after the other. ``controller``: a registered name (or
    entry point / model path), or a factory ``f(ctx)`` given the nominal
    :class:`~agents.controllers.base.ControlContext` (the configuration's base parameters;
    a controller never sees an episode's disturbed parameters). ``step_callback(n)`` gets
    the control steps done since its previous call (progress bars)."""
    cfg = episode_config(scenario, distance_km, magnet, env_kwargs)
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("seeds must not be empty")
    res = cfg.resolve()
    if isinstance(controller, str):
        ctrl = engine.build_controller(controller, cfg, controller_kwargs)
        label = controller
    else:
        ctrl = controller(control_context(res.base, action_scale=res.action_scale))
        label = getattr(ctrl, "name", type(ctrl).__name__)
    ctrl = checked_controller(ctrl, label, res.base.actuators.size)
    # up to MAX_ROWS runs at once (the rows' record buffers live until each run ends)
    rows = min(len(seeds), MAX_ROWS) if engine.is_batched(ctrl) else 1
    jobs = engine.Jobs([engine.Job(s) for s in seeds])
    sig = _Signals(jobs, rows, episode_steps(cfg.resolve().base))
    run = engine.run(ctrl, cfg, rows, jobs, sig, step_callback, progress_every=1000)
    p = run.params
    name = getattr(ctrl, "name", type(ctrl).__name__)
    out = []
    for j, seed in enumerate(seeds):
        rec, end = sig.records[j], jobs.ends[j]
        assert rec is not None and end is not None
        meta = dict(
            controller=name,
            scenario=cfg.scenario,
            seed=seed,
            magnet=p.magnet.orientation,
            dt_s=p.simulation.control_dt_s,
            speed_kmh=p.condition.speed_kmh,
            curve_radius_m=p.condition.curve_radius_m,
            nominal_current_A=sig.nominal_current_A[j],
            clearance_m=p.magnet.clearance_m,
            lateral_clearance_m=p.guidance.clearance_m,
            wall_s=run.wall_s / len(seeds),
        )
        out.append(_episode_from_records(rec, end.last, end.terminated, meta))
    return out


def run_episode(
    controller: str | Callable[[Any], Any],
    scenario: str | EnvConfig,
    seed: int,
    distance_km: float,
    magnet: str | None = "repelling",
    env_kwargs: dict[str, Any] | None = None,
    step_callback: Callable[[int], None] | None = None,
) -> Episode:
    """One episode (:func:`run_episodes` with one seed)."""
    return run_episodes(
        controller, scenario, [seed], distance_km, magnet, env_kwargs, step_callback
    )[0]
