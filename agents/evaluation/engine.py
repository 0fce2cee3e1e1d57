"""The closed-loop rollout engine: the one loop behind every evaluation.

:func:`run` flies a controller on ``rows`` rows of the native vector env
(:class:`hyperloop_env.vector_env.HyperloopSuspensionVectorEnv` with
``autoreset_mode=DISABLED``, physics on the calling thread, no info dicts: bit for bit the
single env's values) and lets a *schedule* decide what every row flies:

* ``schedule.next(row) -> Job | None`` — the next run of a row (a seed and, optionally, the
  episode's disturbances), or ``None``: the row has nothing left to fly (it idles: the
  vector env holds its physics, :meth:`~hyperloop_env.vector_env.HyperloopSuspensionVectorEnv.hold`,
  its zero actions and values are ignored, and it asks again when its held run ends);
* ``schedule.ended(row, job, end)`` — a run ended (:class:`End`: terminated or truncated,
  its steps, its first and last measurement records). ``next`` is called right after, so a
  schedule may choose a row's next run from the runs it has seen (the capacity search).

When a run ends, its row is reset at once with its next job (``reset(seed=…, options=
{"reset_mask": …, "disturbances": …})``) and the controller's rows with
``reset_batch(mask)``: rows never idle while work remains, and a run that ends early frees
its row early. A row's result depends only on its job, never on the other rows, the batch
size or the order of the jobs (tested in ``tests/agents/evaluation/test_engine.py``).

An optional *recorder* sees the measurements (``hyperloop_env.physics.RECORD_FIELDS``)::

    recorder.attach(venv)                      # optional: once, after the first reset
    recorder.started(row, job, meas_row)       # after the row's reset (the step-0 record)
    recorder.step(meas, active, row_steps)     # after every step: (rows, n_meas) records,
                                               # rows that flew a job, steps of each row's run
    recorder.ended(row, job, end)              # before schedule.ended (once if the
                                               # recorder is the schedule)

Controllers. A batched controller has ``act_batch(obs (rows, n_obs)) -> (rows, n_act)``
and, if it keeps state, ``reset_batch(mask)``; row i's action must depend only on row i's
observations since its reset. A controller may also have ``idle_batch(mask)``: the engine
calls it whenever the set of idle rows changes (``mask``: the rows whose actions it ignores
until their next ``reset_batch``), so that it can skip costly work on them (the MPC skips
their QPs); their actions must still be finite. A controller with only ``act(obs)`` /
``reset(seed)`` runs on one row (:class:`OneRow`), one job after the other. Actions are
cast to the action space's float32 (the shipped controllers return float32 already).
Controllers are built from the *nominal* model (:func:`build_controller`: the
configuration's base parameters), never from an episode's disturbed parameters: a
controller does not know the realisation it flies.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from agents.controllers import make_controller
from agents.controllers.base import checked_controller, control_context
from hyperloop_env.config import EnvConfig
from hyperloop_env.physics import RECORD_FIELDS
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

_GAP = RECORD_FIELDS["gap_excursion_m"]
_LAT = RECORD_FIELDS["lateral_offset_m"]


def contact_kind(record: np.ndarray, clearance_m: float, lateral_clearance_m: float) -> str:
    """What a run's last record touched: "gap", "lateral" or "gap+lateral"."""
    gap_hit = bool(np.any(np.abs(record[_GAP]) >= clearance_m))
    lat_hit = bool(np.any(np.abs(record[_LAT]) >= lateral_clearance_m))
    return "gap+lateral" if gap_hit and lat_hit else ("lateral" if lat_hit else "gap")


@dataclass(frozen=True)
class Job:
    """One run: the episode's seed and its disturbances (``None``: the configuration's)."""

    seed: int
    disturbances: Any = None


@dataclass(frozen=True)
class End:
    """How a run ended: ``terminated`` (contact) or truncated (end of the section) after
    ``n_steps`` control steps; ``first`` and ``last`` are its step-0 and final records."""

    terminated: bool
    n_steps: int
    first: np.ndarray
    last: np.ndarray


class Schedule(Protocol):
    def next(self, row: int) -> Job | None: ...

    def ended(self, row: int, job: Job, end: End) -> None: ...


@dataclass
class EngineRun:
    """Work done by :func:`run`: control steps of the batch (all rows, the idle ones that the
    vector env holds included), steps of the runs themselves, wall time, and the parameters
    of row 0's last episode."""

    steps: int
    run_steps: int
    wall_s: float
    params: Any


class Jobs:
    """The schedule of a fixed list of jobs, given to rows in order (each row takes the next
    job when its run ends); ``ends[j]`` is the :class:`End` of job ``j``."""

    def __init__(self, jobs: Sequence[Job]) -> None:
        self.jobs = list(jobs)
        self.ends: list[End | None] = [None] * len(self.jobs)
        self.index: dict[int, int] = {}  # row -> job index it flies
        self._next = 0

    def next(self, row: int) -> Job | None:
        if self._next >= len(self.jobs):
            self.index.pop(row, None)
            return None
        self.index[row] = self._next
        self._next += 1
        return self.jobs[self.index[row]]

    def ended(self, row: int, job: Job, end: End) -> None:
        self.ends[self.index[row]] = end


class OneRow:
    """A controller with only ``act(obs)`` and ``reset(seed=…)`` as a one-row batched
    controller (the engine then flies its jobs one after the other on one row)."""

    def __init__(self, controller: Any) -> None:
        self.controller = controller
        self.name = getattr(controller, "name", type(controller).__name__)
        self.seed: int | None = None

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        return np.asarray(self.controller.act(obs[0]), dtype=np.float32)[None]

    def reset_batch(self, mask: np.ndarray) -> None:
        if mask[0]:
            self.controller.reset(seed=self.seed)


def build_controller(
    name: str, config: EnvConfig, controller_kwargs: dict[str, Any] | None = None
) -> Any:
    """A controller designed on the nominal model (the configuration's base parameters),
    its actions checked (:func:`~agents.controllers.base.checked_controller`: shape and
    finite values; an error names the controller and the control step)."""
    res = config.resolve()
    ctx = control_context(res.base, action_scale=res.action_scale)
    ctrl = make_controller(name, ctx, **(controller_kwargs or {}))
    return checked_controller(ctrl, name, ctx.n_actions)


def is_batched(controller: Any) -> bool:
    """Whether ``controller`` has ``act_batch`` (else it runs on one row: :class:`OneRow`)."""
    return callable(getattr(controller, "act_batch", None))


def vector_env(config: EnvConfig, rows: int) -> HyperloopSuspensionVectorEnv:
    """The engine's vector env: physics on the calling thread (``parallel=False``: the
    runners parallelise over processes, and numba's threads stall a process whenever another
    one holds a core), no info dicts (the engine reads the simulator's records), no
    autoreset (the engine resets rows itself); the same values as the default env."""
    return HyperloopSuspensionVectorEnv(
        rows, config=config, autoreset_mode="Disabled", parallel=False, info=False
    )


def _idle_hook(ctrl: Any, active: np.ndarray) -> Callable[[np.ndarray], None] | None:
    """The controller's ``idle_batch`` (None without one), told at once of rows that start
    idle."""
    idle_batch = getattr(ctrl, "idle_batch", None)
    if not callable(idle_batch):
        return None
    if not active.all():
        idle_batch(~active)
    return idle_batch


def _attach_recorder(
    recorder: Any,
    venv: HyperloopSuspensionVectorEnv,
    jobs: list[Job | None],
    active: np.ndarray,
    first: np.ndarray,
) -> None:
    """Attach the recorder (if it wants the env) and tell it the first runs started."""
    if callable(getattr(recorder, "attach", None)):
        recorder.attach(venv)
    for i in np.flatnonzero(active):
        recorder.started(int(i), jobs[i], first[i])


def _end_runs(
    fin: np.ndarray,
    te: np.ndarray,
    jobs: list[Job | None],
    seeds: list[int],
    dists: list[Any],
    row_t: np.ndarray,
    first: np.ndarray,
    meas: np.ndarray,
    active: np.ndarray,
    schedule: Schedule,
    recorder: Any,
) -> None:
    """The runs of the rows ``fin`` ended: report each (recorder, then schedule) and give its
    row the schedule's next job, or None (the row idles); ``jobs``, ``seeds``, ``dists`` and
    ``row_t`` are updated in place."""
    for i in np.flatnonzero(fin):
        job = jobs[i]
        if job is not None and active[i]:
            end = End(bool(te[i]), int(row_t[i]), first[i].copy(), meas[i].copy())
            if recorder is not None and recorder is not schedule:
                recorder.ended(int(i), job, end)
            schedule.ended(int(i), job, end)
        nxt = schedule.next(int(i))
        if nxt is not None:
            jobs[i] = nxt
            seeds[i], dists[i] = int(nxt.seed), nxt.disturbances
        else:
            jobs[i] = None  # idles: flies its last job again, ignored
        row_t[i] = 0


def _restart_rows(
    venv: HyperloopSuspensionVectorEnv,
    sim: Any,
    ctrl: Any,
    fin: np.ndarray,
    jobs: list[Job | None],
    seeds: list[int],
    dists: list[Any],
    first: np.ndarray,
    reset_batch: Any,
    recorder: Any,
) -> np.ndarray:
    """Reset the rows ``fin`` with their next jobs (env, then the controller's rows that fly
    one), record their step-0 records in ``first`` and tell the recorder; the new
    observations."""
    n = len(jobs)
    obs, _ = venv.reset(
        seed=[seeds[i] if fin[i] else None for i in range(n)],
        options={"reset_mask": fin.copy(), "disturbances": list(dists)},
    )
    if isinstance(ctrl, OneRow):
        ctrl.seed = seeds[0]
    new = fin & np.array([j is not None for j in jobs])
    if callable(reset_batch) and new.any():  # idle rows' controller state: ignored
        reset_batch(new)
    meas = sim.MEAS
    for i in np.flatnonzero(fin):
        first[i] = meas[i]
        if jobs[i] is not None and recorder is not None:
            recorder.started(int(i), jobs[i], first[i])
    return obs


def run(
    controller: Any,
    config: EnvConfig,
    rows: int,
    schedule: Schedule,
    recorder: Any = None,
    progress: Callable[[int], None] | None = None,
    progress_every: int = 4096,
) -> EngineRun:
    """Fly ``schedule``'s jobs with ``controller`` on ``rows`` rows (module docstring);
    ``progress(n)`` gets the control steps of the runs done since its previous call."""
    if isinstance(rows, bool) or not isinstance(rows, int | np.integer) or rows < 1:
        raise ValueError(f"rows must be an int >= 1, got {rows!r}")
    ctrl = controller if is_batched(controller) else OneRow(controller)
    if not is_batched(controller) and rows != 1:
        raise ValueError("a controller without act_batch runs on rows=1")
    n = int(rows)
    jobs: list[Job | None] = [schedule.next(i) for i in range(n)]
    if jobs[0] is None:
        raise ValueError("the schedule has no job")
    t0 = time.perf_counter()
    venv = vector_env(config, n)
    try:
        seeds = [int((j or jobs[0]).seed) for j in jobs]  # type: ignore[union-attr]
        dists = [(j or jobs[0]).disturbances for j in jobs]  # type: ignore[union-attr]
        obs, _ = venv.reset(seed=seeds, options={"disturbances": list(dists)})
        if isinstance(ctrl, OneRow):
            ctrl.seed = seeds[0]
        reset_batch = getattr(ctrl, "reset_batch", None)
        if callable(reset_batch):
            reset_batch(np.ones(n, dtype=np.bool_))
        sim = venv.sim
        active = np.array([j is not None for j in jobs])
        idle_batch = _idle_hook(ctrl, active)
        venv.hold(None if active.all() else ~active)
        first = sim.MEAS.copy()
        if recorder is not None:
            _attach_recorder(recorder, venv, jobs, active, first)
        row_t = np.zeros(n, dtype=np.int64)
        steps = run_steps = pending = 0
        act, step = ctrl.act_batch, venv.step
        while active.any():
            a = np.asarray(act(obs), dtype=np.float32)
            if not active.all():
                a = np.where(active[:, None], a, np.float32(0.0))
            obs, _, te, tr, _ = step(a)
            row_t += 1
            k = int(active.sum())
            steps += n
            run_steps += k
            pending += k
            meas = sim.MEAS
            if recorder is not None:
                recorder.step(meas, active, row_t)
            fin = te | tr
            if fin.any():
                _end_runs(
                    fin, te, jobs, seeds, dists, row_t, first, meas, active, schedule, recorder
                )
                obs = _restart_rows(
                    venv, sim, ctrl, fin, jobs, seeds, dists, first, reset_batch, recorder
                )
                was = active
                active = np.array([j is not None for j in jobs])
                if not np.array_equal(active, was):
                    venv.hold(None if active.all() else ~active)
                    if idle_batch is not None and active.any():
                        idle_batch(~active)
            if progress is not None and pending >= progress_every:
                progress(pending)
                pending = 0
        if progress is not None and pending:
            progress(pending)
        return EngineRun(steps, run_steps, time.perf_counter() - t0, venv.params[0])
    finally:
        venv.close()
