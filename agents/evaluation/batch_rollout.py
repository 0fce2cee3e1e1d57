"""Long closed-loop runs of a block of seeds with streaming statistics.

:func:`run_block` runs the seeds of one case (controller × condition × severity level ×
seed block) over the configured track section and returns a :class:`BlockResult`: one
:class:`RunResult` per seed with exact counts, running moments, the streamed ISO 2631-1
comfort and thinned levitation- and guidance-gap signals (every ``thin_stride``-th step)
for the STS fits — never the full signals (:mod:`agents.evaluation.streaming`).

The runs fly on the rollout engine (:mod:`agents.evaluation.engine`: its controller
protocol, its nominal-model rule): a controller with ``act_batch`` flies all seeds of the
block at once, one row each; one without flies them one after the other on one row.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from agents.evaluation import engine
from agents.evaluation.streaming import Exceedances, Moments, Thinned, WeightedRMS
from hyperloop_env.comfort import HORIZONTAL_FACTOR
from hyperloop_env.config import EnvConfig
from hyperloop_env.physics import RECORD_FIELDS
from hyperloop_env.physics.layout import NM
from hyperloop_env.physics.model import episode_steps
from hyperloop_env.physics.units import N_UNITS
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

_GAP = RECORD_FIELDS["gap_excursion_m"]
_LAT = RECORD_FIELDS["lateral_offset_m"]
_CUR = RECORD_FIELDS["current_A"]
_ACC_H = RECORD_FIELDS["acceleration_heave_lateral"].start
_X = RECORD_FIELDS["position_m"].start
_T = RECORD_FIELDS["time_s"].start

DEFAULT_EXCEED_FRACTIONS = (0.5, 0.75, 1.0)
"""Exceedance levels counted exactly, as fractions of the clearance Ω."""


@dataclass(frozen=True)
class BlockSpec:
    """One unit of work: a controller on one configuration for a block of seeds."""

    controller: str
    config: EnvConfig
    seeds: tuple[int, ...]
    settle_s: float = 1.0
    thin_stride: int = 1
    controller_kwargs: dict[str, Any] = field(default_factory=dict)
    exceed_fractions: tuple[float, ...] = DEFAULT_EXCEED_FRACTIONS
    chunk_steps: int = 1024
    batched: bool | None = None  # None: batched when the controller has act_batch
    key: tuple[Any, ...] = ()


@dataclass
class RunResult:
    """Streamed statistics of one run (seed)."""

    seed: int
    n_steps: int
    terminated: bool
    truncated: bool
    contact_kind: str | None
    contact_time_s: float | None
    contact_position_m: float | None
    distance_m: float
    a_wz_m_s2: float
    a_wy_m_s2: float
    a_v_m_s2: float
    gap: dict[str, np.ndarray]  # moments after settling, per unit
    lateral: dict[str, np.ndarray]
    current_dev: dict[str, np.ndarray]
    exceed: np.ndarray  # (n_levels, n_units) samples with |s| >= level after settling
    exceed_any: np.ndarray  # (n_levels,) samples where any unit exceeds
    n_post: int  # samples after settling
    thinned_gap: np.ndarray  # (J, n_units), steps 1, 1 + k, …
    thinned_lateral: np.ndarray  # (J, n_units) guidance gap (lateral offset), same steps


@dataclass
class BlockResult:
    key: tuple[Any, ...]
    controller: str
    runs: list[RunResult]
    batched: bool
    steps: int
    wall_s: float
    dt_s: float
    clearance_m: float
    lateral_clearance_m: float
    thin_stride: int
    exceed_levels_m: tuple[float, ...]
    thinned_bytes: int


contact_kind = engine.contact_kind


def max_steps(config: EnvConfig) -> int:
    """An episode's control steps at the base speed, or at the slowest speed a randomising
    scenario may draw (the thinned storage grows if an episode takes longer, e.g. when a
    speed profile brakes)."""
    res = config.resolve()
    p = res.base
    if res.draw_speed and res.scenario.random is not None:
        lo = res.scenario.random.speed_range_kmh[0]
        p = p.with_(condition=replace(p.condition, speed_kmh=lo))
    return episode_steps(p)


class _Recorder:
    """Chunked streaming of N rows' measurement records into the accumulators."""

    def __init__(self, n: int, spec: BlockSpec, dt: float, clearance: float, n_meas: int) -> None:
        self.n = n
        self.dt = dt
        self.n0 = int(math.ceil(spec.settle_s / dt - 1e-9)) if spec.settle_s > 0 else 0
        c = max(1, int(spec.chunk_steps))
        self.buf = np.zeros((c, n, n_meas))
        self.mask = np.zeros((c, n), dtype=np.bool_)
        self.pos = 0
        self.first = 1  # global step of buf[0]
        self.gap = Moments(n, N_UNITS)
        self.lat = Moments(n, N_UNITS)
        self.cur = Moments(n, N_UNITS)
        self.levels = tuple(f * clearance for f in spec.exceed_fractions)
        self.exc = Exceedances(n, N_UNITS, np.array(self.levels))
        self.wz = WeightedRMS(n, dt, "k", spec.settle_s)
        self.wy = WeightedRMS(n, dt, "d", spec.settle_s)
        self.thin = Thinned(n, N_UNITS, max_steps(spec.config), spec.thin_stride)
        self.thin_lat = Thinned(n, N_UNITS, max_steps(spec.config), spec.thin_stride)
        self.i0 = np.zeros(n)

    def add(self, meas: np.ndarray, active: np.ndarray) -> None:
        self.buf[self.pos] = meas
        self.mask[self.pos] = active
        self.pos += 1
        if self.pos == self.buf.shape[0]:
            self.flush()

    def flush(self) -> None:
        k = self.pos
        if k == 0:
            return
        x = self.buf[:k]
        m = self.mask[:k]
        t = self.first + np.arange(k)
        post = m & (t >= self.n0 + 1)[:, None]
        gap = x[:, :, _GAP]
        self.gap.update(gap, post)
        self.lat.update(x[:, :, _LAT], post)
        self.cur.update(x[:, :, _CUR] - self.i0[None, :, None], post)
        self.exc.update(gap, post)
        self.wz.update(x[:, :, _ACC_H], m)
        self.wy.update(x[:, :, _ACC_H + 1], m)
        self.thin.update(gap, m, self.first)
        self.thin_lat.update(x[:, :, _LAT], m, self.first)
        self.first += k
        self.pos = 0

    def results(
        self,
        seeds: list[int],
        end: np.ndarray,
        term: np.ndarray,
        x0: np.ndarray,
        last: np.ndarray,
        lat_clear: float,
        clear: float,
    ) -> list[RunResult]:
        self.flush()
        az, ay = self.wz.result(), self.wy.result()
        out = []
        for i, seed in enumerate(seeds):
            n_steps = int(end[i])
            ok = n_steps > self.n0 + 10  # as agents.evaluation.metrics.summarise
            a_z = float(az[i]) if ok else math.nan
            a_y = float(ay[i]) if ok else math.nan
            a_v = math.sqrt((HORIZONTAL_FACTOR * a_y) ** 2 + a_z**2) if ok else math.nan
            kind = ct = cp = None
            if term[i]:
                r = last[i]
                kind = contact_kind(r, clear, lat_clear)
                ct, cp = float(r[_T]), float(r[_X])
            out.append(
                RunResult(
                    seed=int(seed),
                    n_steps=n_steps,
                    terminated=bool(term[i]),
                    truncated=not bool(term[i]),
                    contact_kind=kind,
                    contact_time_s=ct,
                    contact_position_m=cp,
                    distance_m=float(last[i, _X] - x0[i]),
                    a_wz_m_s2=a_z,
                    a_wy_m_s2=a_y,
                    a_v_m_s2=a_v,
                    gap=self.gap.row(i),
                    lateral=self.lat.row(i),
                    current_dev=self.cur.row(i),
                    exceed=self.exc.count[i].copy(),
                    exceed_any=self.exc.count_any[i].copy(),
                    n_post=int(self.gap.n[i, 0]),
                    thinned_gap=self.thin.row(i),
                    thinned_lateral=self.thin_lat.row(i),
                )
            )
        return out


def build_controller(spec: BlockSpec) -> Any:
    """The controller of a block, designed on the nominal model (the base parameters)."""
    return engine.build_controller(spec.controller, spec.config, spec.controller_kwargs)


def uses_batch(controller: Any, batched: bool | None) -> bool:
    has = engine.is_batched(controller)
    if batched and not has:
        raise ValueError(
            f"controller {getattr(controller, 'name', controller)!r} has no act_batch()"
        )
    return has if batched is None else bool(batched)


def batch_env(config: EnvConfig, n: int) -> HyperloopSuspensionVectorEnv:
    """The vector env of a batched block of ``n`` seeds (:func:`engine.vector_env`)."""
    return engine.vector_env(config, n)


def run_block(spec: BlockSpec, progress: Callable[[int], None] | None = None) -> BlockResult:
    """Run the block (see the module docstring); ``progress(n)`` gets the control steps
    done since its previous call."""
    if not spec.seeds:
        raise ValueError("a block needs at least one seed")
    ctrl = build_controller(spec)
    batched = uses_batch(ctrl, spec.batched)
    t0 = time.perf_counter()
    if batched:
        runs, info = _run_batched(ctrl, spec, progress)
    else:
        runs, info = [], {}
        for s in spec.seeds:
            r, info = _run_single(ctrl, spec, int(s), progress)
            runs.extend(r)
    wall = time.perf_counter() - t0
    return BlockResult(
        key=spec.key,
        controller=spec.controller,
        runs=runs,
        batched=batched,
        steps=sum(r.n_steps for r in runs),
        wall_s=wall,
        thin_stride=spec.thin_stride,
        **info,
    )


def _info(p: Any, rec: _Recorder) -> dict[str, Any]:
    return {
        "dt_s": p.simulation.control_dt_s,
        "clearance_m": p.magnet.clearance_m,
        "lateral_clearance_m": p.guidance.clearance_m,
        "exceed_levels_m": rec.levels,
        "thinned_bytes": rec.thin.nbytes + rec.thin_lat.nbytes,
    }


class _Streams:
    """The engine's recorder for a block: every step's records into a :class:`_Recorder`
    whose row i is the block's seed i (rows are not refilled)."""

    def __init__(self, rec: _Recorder) -> None:
        self.rec = rec

    def attach(self, venv: HyperloopSuspensionVectorEnv) -> None:
        self.rec.i0 = np.asarray(venv.nominal_current_A, dtype=float).copy()

    def started(self, row: int, job: engine.Job, meas_row: np.ndarray) -> None:
        pass

    def step(self, meas: np.ndarray, active: np.ndarray, row_steps: np.ndarray) -> None:
        self.rec.add(meas, active)

    def ended(self, row: int, job: engine.Job, end: engine.End) -> None:
        pass


def _run_on_engine(
    ctrl: Any, spec: BlockSpec, seeds: list[int], progress: Callable[[int], None] | None
) -> tuple[list[RunResult], dict]:
    """Fly ``seeds`` on one row each (all at once) with the engine, streamed."""
    n = len(seeds)
    res = spec.config.resolve()
    p = res.base
    n_meas = NM  # the record's length
    rec = _Recorder(n, spec, p.simulation.control_dt_s, p.magnet.clearance_m, n_meas)
    jobs = engine.Jobs([engine.Job(s) for s in seeds])
    run = engine.run(ctrl, spec.config, n, jobs, _Streams(rec), progress)
    p = run.params
    ends = [e for e in jobs.ends if e is not None]
    end = np.array([e.n_steps for e in ends], dtype=np.int64)
    term = np.array([e.terminated for e in ends], dtype=np.bool_)
    x0 = np.array([e.first[_X] for e in ends])
    last = np.stack([e.last for e in ends])
    runs = rec.results(seeds, end, term, x0, last, p.guidance.clearance_m, p.magnet.clearance_m)
    return runs, _info(p, rec)


def _run_batched(
    ctrl: Any, spec: BlockSpec, progress: Callable[[int], None] | None
) -> tuple[list[RunResult], dict]:
    return _run_on_engine(ctrl, spec, [int(s) for s in spec.seeds], progress)


def _run_single(
    ctrl: Any, spec: BlockSpec, seed: int, progress: Callable[[int], None] | None
) -> tuple[list[RunResult], dict]:
    return _run_on_engine(engine.OneRow(ctrl), spec, [seed], progress)
