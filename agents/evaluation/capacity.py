"""Per-seed capacities by incremental dynamic analysis (IDA).

Seismic engineering scales one ground-motion record until the structure collapses; the
scale at collapse is that record's capacity and the fragility is the distribution of the
capacities (Vamvatsikos & Cornell 2002, "Incremental dynamic analysis", Earthquake Eng.
Struct. Dyn. 31:491–514). Here a **seed** fixes one realisation of the guideway (the
roughness phases, the pier offsets, the camber pattern, the joint offsets) and the
family's **severity** scales it (each disturbance declares it:
:attr:`~hyperloop_env.disturbances.base.Disturbance.scales_with_severity`, proved in
``tests/agents/evaluation/test_capacity.py``: the realisation at 2s is twice the one at
s). The capacity of a seed is the smallest severity at which a run of the given distance
touches (any gap or guidance gap reaches its clearance).

Search for one (controller, condition, family, seed), all severities in the family's unit:

1. **hunt** — fly the family's ``start``; while the run flies, multiply the severity by
   ``step`` (until ``upper``: a seed that flies at ``upper`` is *right-censored*,
   capacity > upper, kept and marked); while it touches, divide by ``step`` (until
   ``lower``: *left-censored*, capacity <= lower).
2. **fill** — bisect the bracket (largest flying severity ``lo``, smallest touching
   ``hi``) in log-severity until ``hi / lo <= ratio`` (default 1.02). The capacity is
   ``hi``: the smallest severity seen to touch — the first touch along the hunt, as in
   IDA (the search never flies a severity above one that touched, except on the check
   grid).
3. **check** — fly the ``check`` severities (the family's fitting grid by default) above
   ``hi``, at most ``check_above`` of them: a run there that flies makes the seed
   **non-monotone** (a higher severity flies after a lower one touched). Such seeds are
   counted and reported; their capacity stays the first touch.

Every run is kept (severity, contact, time and kind of first contact, phase).

Engine: the rollout engine (:mod:`agents.evaluation.engine`) with one row per search
slot, per task (one controller on one condition; any number of families × seeds): every
row works through a queue of searches, and when its run ends it is reset at once with the
next severity of its search or with the next search — so rows never idle while searches
remain, and a run that touches early frees its row early. The controller is built once
per task from the nominal model; a row's result depends only on its (seed, severity),
never on the other rows, the batch size or the queue order (tested). A controller without
``act_batch`` flies its runs one at a time on one row (slower, same results).

**The paper's STS from the same runs.** With the suite's ``levels`` (the benchmark passes
them; ``start`` is the middle one), the hunt steps to the neighbouring level when it lies
within one ``step`` (else by ``step``), the check never flies a severity twice, and a last
phase (**levels**) flies the levels the search has not flown yet — so every seed flies
every level exactly once (a run there that touches below a flying severity, or flies above
a touching one, makes the seed non-monotone; level runs do not move the bracket). Their
levitation- and guidance-gap signals (every ``sts_stride``-th step) are kept, and per
family and level the paper's P(unsteady) (fitted law, KS test at α = 0.05,
:func:`hyperloop_env.sts.analyse_episodes`; a run that touched counts with P = 1) is
computed from these runs of all seeds — the same runs the capacities come from, so the
paper's metric and the fragility are one data set seen two ways. Without ``levels`` the
STS is that of each search's first run (at ``start``).

Families whose realisation does not scale with the severity (sensor dropout's schedule,
the actuator fault's onset, payload position, speed profile) keep the grid design of
:mod:`agents.evaluation.fragility`.
"""

from __future__ import annotations

import math
import time
from collections import Counter, deque
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from agents.evaluation import engine
from agents.evaluation.batch_rollout import (
    contact_kind,
    max_steps,
)
from hyperloop_env.config import EnvConfig
from hyperloop_env.disturbances import DISTURBANCES
from hyperloop_env.physics import RECORD_FIELDS

DEFAULT_RATIO = 1.02
DEFAULT_STEP = 1.5
DEFAULT_CHECK_ABOVE = 2
DEFAULT_ROWS = 32
DEFAULT_STS_STRIDE = 4

_GAP = RECORD_FIELDS["gap_excursion_m"]
_LAT = RECORD_FIELDS["lateral_offset_m"]
_T = RECORD_FIELDS["time_s"].start
_X = RECORD_FIELDS["position_m"].start


@dataclass(frozen=True)
class FamilySearch:
    """How to search one family's capacities (severities in the family's unit)."""

    family: str
    start: float
    lower: float
    upper: float
    step: float = DEFAULT_STEP
    ratio: float = DEFAULT_RATIO
    check: tuple[float, ...] = ()
    check_above: int = DEFAULT_CHECK_ABOVE
    fixed: tuple[tuple[str, float], ...] = ()
    levels: tuple[float, ...] = ()  # the suite's levels: every seed flies each once (STS)

    def __post_init__(self) -> None:
        cls = DISTURBANCES.get(self.family)
        if cls is None:
            raise ValueError(f"family must be one of {list(DISTURBANCES)}, got {self.family!r}")
        if not cls.scales_with_severity:
            raise ValueError(
                f"family {self.family!r}: its realisation does not scale with the severity "
                f"({cls.scaling_note}); use the grid design (python -m agents.fragility)"
            )
        for name in ("start", "lower", "upper", "step", "ratio"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise ValueError(f"FamilySearch.{name} must be a finite number, got {v!r}")
        if not 0.0 < self.lower <= self.start <= self.upper:
            raise ValueError(
                f"FamilySearch ({self.family}): need 0 < lower <= start <= upper, got "
                f"lower={self.lower!r}, start={self.start!r}, upper={self.upper!r}"
            )
        if not self.step > 1.0:
            raise ValueError(f"FamilySearch.step must be > 1, got {self.step!r}")
        if not 1.0 < self.ratio <= self.step:
            raise ValueError(
                f"FamilySearch.ratio must be in (1, step={self.step}], got {self.ratio!r}"
            )
        if (
            isinstance(self.check_above, bool)
            or not isinstance(self.check_above, int)
            or (self.check_above < 0)
        ):
            raise ValueError(
                f"FamilySearch.check_above must be an int >= 0, got {self.check_above!r}"
            )
        for name in ("check", "levels"):
            for v in getattr(self, name):
                if isinstance(v, bool) or not (
                    isinstance(v, int | float) and math.isfinite(v) and v > 0
                ):
                    raise ValueError(
                        f"FamilySearch.{name} must hold positive severities, got {v!r}"
                    )
        if self.levels and (
            list(self.levels) != sorted(set(self.levels)) or self.start not in self.levels
        ):
            raise ValueError(
                "FamilySearch.levels must be increasing and hold start "
                f"({self.start!r}), got {self.levels!r}"
            )

    def up(self, lo: float) -> float:
        """The hunt's next severity above a flying ``lo``: the next level if it lies within
        one ``step``, else ``lo · step`` (capped at ``upper``)."""
        nxt = [v for v in self.levels if lo < v <= lo * self.step]
        return min(nxt[0] if nxt else lo * self.step, self.upper)

    def down(self, hi: float) -> float:
        """The hunt's next severity below a touching ``hi``: the previous level if it lies
        within one ``step``, else ``hi / step`` (floored at ``lower``)."""
        prev = [v for v in self.levels if hi / self.step <= v < hi]
        return max(prev[-1] if prev else hi / self.step, self.lower)

    def disturbances(self, severity: float) -> dict[str, float]:
        d = dict(self.fixed)
        d[self.family] = float(severity)
        return d


@dataclass
class Run:
    severity: float
    contact: bool
    time_s: float  # time of the first contact, or the end of the run [s]
    kind: str | None  # "gap", "lateral", "gap+lateral" or None
    phase: str  # hunt, fill, check


@dataclass
class Search:
    """The state and the result of one seed's capacity search (module docstring)."""

    family: str
    seed: int
    runs: list[Run] = field(default_factory=list)
    lo: float | None = None  # largest flying severity of the hunt and fill
    hi: float | None = None  # smallest touching severity of the hunt and fill
    phase: str = "hunt"
    censored: str | None = None  # "right" (flies at upper) or "left" (touches at lower)
    pending_check: list[float] = field(default_factory=list)
    pending_levels: list[float] = field(default_factory=list)
    levels: tuple[float, ...] = ()
    non_monotone: bool = False

    def next_severity(self, fs: FamilySearch) -> float | None:
        """The severity of the next run, or None when the search is finished."""
        if self.phase == "hunt":
            if self.hi is None and self.lo is None:
                return fs.start
            if self.hi is None:
                assert self.lo is not None
                if self.lo >= fs.upper:
                    self.censored = "right"
                    return self._start_check(fs)
                return fs.up(self.lo)
            if self.lo is None:
                if self.hi <= fs.lower:
                    self.censored = "left"
                    return self._start_check(fs)
                return fs.down(self.hi)
            self.phase = "fill"
        if self.phase == "fill":
            assert self.lo is not None and self.hi is not None
            if self.hi / self.lo > fs.ratio * (1 + 1e-12):
                return math.sqrt(self.lo * self.hi)
            return self._start_check(fs)
        return self._next_check()

    def _start_check(self, fs: FamilySearch) -> float | None:
        self.phase = "check"
        if self.hi is not None:
            flown = {r.severity for r in self.runs}  # deterministic: never fly one twice
            above = sorted(v for v in fs.check if self.hi < v <= fs.upper and v not in flown)
            self.pending_check = above[: fs.check_above]
        return self._next_check()

    def _next_check(self) -> float | None:
        if self.pending_check:
            return self.pending_check.pop(0)
        return self._next_level()

    def _next_level(self) -> float | None:
        """The suite's levels this search has not flown yet (phase "levels"), then done."""
        if self.phase != "levels":
            self.phase = "levels"
            flown = {r.severity for r in self.runs}
            self.pending_levels = [v for v in self.levels if v not in flown]
        if self.pending_levels:
            return self.pending_levels.pop(0)
        self.phase = "done"
        return None

    def record(self, run: Run) -> None:
        self.runs.append(run)
        if run.phase == "check":
            if not run.contact:
                self.non_monotone = True
            return
        if run.phase == "levels":  # kept for the STS; the capacity is the hunt's and fill's
            if (run.contact and self.lo is not None and run.severity < self.lo) or (
                not run.contact and self.hi is not None and run.severity > self.hi
            ):
                self.non_monotone = True
            return
        if run.contact:
            self.hi = run.severity if self.hi is None else min(self.hi, run.severity)
        else:
            self.lo = run.severity if self.lo is None else max(self.lo, run.severity)

    @property
    def capacity(self) -> float:
        """The capacity (module docstring); for a right-censored seed the upper bound it
        flew, for a left-censored one the lower bound it touched."""
        if self.censored == "right":
            assert self.lo is not None
            return self.lo
        assert self.hi is not None
        return self.hi

    def to_dict(self) -> dict[str, Any]:
        return {
            "family": self.family,
            "seed": self.seed,
            "capacity": self.capacity,
            "bracket": [self.lo, self.hi],
            "censored": self.censored,
            "non_monotone": self.non_monotone,
            "runs": [asdict(r) for r in self.runs],
        }


@dataclass(frozen=True)
class CapacityTask:
    """One unit of work: a controller on one condition, searches for families × seeds."""

    controller: str
    config: EnvConfig  # the condition, the distance (track section) and the actuators
    families: tuple[FamilySearch, ...]
    seeds: tuple[int, ...]
    rows: int = DEFAULT_ROWS
    controller_kwargs: dict[str, Any] = field(default_factory=dict)
    key: tuple[Any, ...] = ()
    sts_stride: int = DEFAULT_STS_STRIDE  # 0: no STS
    settle_s: float = 1.0
    n_boot: int = 200


@dataclass
class TaskResult:
    key: tuple[Any, ...]
    controller: str
    searches: list[Search]
    steps: int  # control steps of the batch (all rows, the held idle tail included)
    run_steps: int  # control steps of the runs themselves
    wall_s: float  # the flights (engine.run)
    sts: dict[str, dict[str, Any]] = field(default_factory=dict)  # family -> at the start
    sts_s: float = 0.0  # the paper's STS of the levels' runs (fits, KS tests, bootstrap)

    def by_family(self, family: str) -> list[Search]:
        return [s for s in self.searches if s.family == family]


def run_task(task: CapacityTask, progress: Callable[[int], None] | None = None) -> TaskResult:
    """Run every search of ``task`` (module docstring); ``progress(n)`` gets control steps."""
    if not task.seeds:
        raise ValueError("a capacity task needs at least one seed")
    if isinstance(task.rows, bool) or not isinstance(task.rows, int) or task.rows < 1:
        raise ValueError(f"CapacityTask.rows must be an int >= 1, got {task.rows!r}")
    fams = {fs.family: fs for fs in task.families}
    if len(fams) != len(task.families):
        raise ValueError("CapacityTask.families: each family at most once")
    ctrl = engine.build_controller(task.controller, task.config, dict(task.controller_kwargs))
    searches = [
        Search(fs.family, int(sd), levels=fs.levels) for fs in task.families for sd in task.seeds
    ]
    # a controller without act_batch flies one run at a time (engine.OneRow)
    n = min(task.rows, len(searches)) if engine.is_batched(ctrl) else 1
    res = task.config.resolve().base
    clear, lat_clear = res.magnet.clearance_m, res.guidance.clearance_m
    work = _Searches(
        searches, fams, n, int(task.sts_stride), max_steps(task.config), clear, lat_clear
    )
    run = engine.run(ctrl, task.config, n, work, work, progress, progress_every=8192)
    sts: dict[str, dict[str, Any]] = {}
    t_sts = time.perf_counter()
    if task.sts_stride > 0:
        dt = run.params.simulation.control_dt_s * task.sts_stride
        for fs in task.families:
            per_level = {}
            for level in fs.levels or (fs.start,):
                sig = [
                    work.signals[(j, level)]
                    for j, s in enumerate(searches)
                    if s.family == fs.family and (j, level) in work.signals
                ]
                per_level[level] = level_sts(
                    sig, dt, level, clear, lat_clear, settle_s=task.settle_s, n_boot=task.n_boot
                )
            sts[fs.family] = {
                "start": per_level[fs.start],
                "levels": [per_level[v] for v in sorted(per_level)],
            }
    return TaskResult(
        task.key,
        task.controller,
        searches,
        run.steps,
        run.run_steps,
        run.wall_s,
        sts,
        time.perf_counter() - t_sts,
    )


class _Searches:
    """The capacity searches as the engine's schedule and recorder: a row works through a
    queue of searches (the next severity of its search, else the next search); the first
    run of every search (at the family's start level) keeps its gap signals every
    ``stride``-th step for the paper's STS."""

    def __init__(
        self,
        searches: list[Search],
        fams: dict[str, FamilySearch],
        rows: int,
        stride: int,
        max_steps: int,
        clearance_m: float,
        lateral_clearance_m: float,
    ) -> None:
        self.searches, self.fams = searches, fams
        self.queue = deque(range(len(searches)))
        self.row_search: list[int | None] = [None] * rows
        self.row_sev = np.zeros(rows)
        self.row_phase = [""] * rows
        self.clear, self.lat_clear = clearance_m, lateral_clearance_m
        self.stride = stride
        cap = (max_steps // stride + 2) if stride > 0 else 0
        self.buf_gap = np.zeros((rows, cap, _GAP.stop - _GAP.start))
        self.buf_lat = np.zeros((rows, cap, _LAT.stop - _LAT.start))
        self.fill = np.zeros(rows, dtype=np.int64)
        self.rec = np.zeros(rows, dtype=np.bool_)
        self.signals: dict[tuple[int, float], tuple[np.ndarray, np.ndarray, bool]] = {}

    def next(self, row: int) -> engine.Job | None:
        cur = self.row_search[row]
        while True:
            if cur is not None:
                s = self.searches[cur]
                fam = self.fams[s.family]
                sev = s.next_severity(fam)
                if sev is not None:
                    self.row_search[row], self.row_sev[row] = cur, sev
                    self.row_phase[row] = s.phase
                    return engine.Job(s.seed, fam.disturbances(sev))
            if not self.queue:
                self.row_search[row] = None
                return None
            cur = self.queue.popleft()

    def started(self, row: int, job: engine.Job, meas_row: np.ndarray) -> None:
        j = self.row_search[row]
        if self.stride <= 0 or j is None:
            self.rec[row] = False
        else:  # the suite's levels (or, without them, the search's first run: the start)
            s = self.searches[j]
            levels = self.fams[s.family].levels
            sev = float(self.row_sev[row])
            self.rec[row] = (sev in levels) if levels else not s.runs
        self.fill[row] = 0

    def step(self, meas: np.ndarray, active: np.ndarray, row_steps: np.ndarray) -> None:
        if self.stride > 0:
            m = self.rec & (row_steps % self.stride == 1 % self.stride)
            if m.any():
                ix = np.flatnonzero(m)
                self.buf_gap[ix, self.fill[ix]] = meas[ix, _GAP]
                self.buf_lat[ix, self.fill[ix]] = meas[ix, _LAT]
                self.fill[ix] += 1

    def ended(self, row: int, job: engine.Job, end: engine.End) -> None:
        j = self.row_search[row]
        if j is None:
            return
        if self.rec[row]:  # a run at a level: its signals for the STS
            f = int(self.fill[row])
            self.signals[(j, float(self.row_sev[row]))] = (
                self.buf_gap[row, :f].copy(),
                self.buf_lat[row, :f].copy(),
                end.terminated,
            )
            self.rec[row] = False
        kind = contact_kind(end.last, self.clear, self.lat_clear) if end.terminated else None
        t = float(end.last[_T])
        self.searches[j].record(
            Run(float(self.row_sev[row]), end.terminated, t, kind, self.row_phase[row])
        )


def level_sts(
    signals: Sequence[tuple[np.ndarray, np.ndarray, bool]],
    dt_s: float,
    severity: float,
    clearance_m: float,
    lateral_clearance_m: float,
    *,
    settle_s: float = 1.0,
    n_boot: int = 200,
) -> dict[str, Any]:
    """The paper's P(unsteady) (worst unit, fitted law with its block-bootstrap interval)
    of the levitation and guidance gaps from the runs at ``severity`` (one per seed)."""
    from hyperloop_env.sts import analyse_episodes, worst_index

    out: dict[str, Any] = {
        "severity": severity,
        "n_runs": len(signals),
        "n_contacts": int(sum(t for _, _, t in signals)),
    }
    for name, col, om in (("gap", 0, clearance_m), ("guidance", 1, lateral_clearance_m)):
        rep = analyse_episodes(
            [(sig[col], sig[2]) for sig in signals],
            dt_s,
            settle_s=settle_s,
            n_boot=n_boot,
            clearance_m=om,
            intervals="worst",  # only the worst unit is reported
        )
        worst = rep.units[worst_index([u.p_unsteady for u in rep.units])]
        out[name] = {
            "p_unsteady": rep.worst_p_unsteady,
            "unit": rep.worst_unit,
            "p_unsteady_ci": list(worst.p_unsteady_ci),
            "distribution": worst.distribution,
            "p_unsteady_fit": worst.p_unsteady_fit,
            "empirical_exceedance": worst.empirical_exceedance,
        }
    return out


def capacities(searches: Sequence[Search]) -> tuple[np.ndarray, np.ndarray]:
    """(capacities, right-censored flags) of searches, in their order."""
    c = np.array([s.capacity for s in searches], dtype=float)
    cens = np.array([s.censored == "right" for s in searches], dtype=bool)
    return c, cens


def contact_kinds(searches: Sequence[dict[str, Any]]) -> dict[str, int]:
    """Per kind of first contact (``gap``, ``lateral``, ``gap+lateral``), the seeds whose
    capacity run touched that way (a right-censored seed: ``none``)."""
    out: Counter[str] = Counter()
    for s in searches:
        if s["censored"] == "right":
            out["none"] += 1
            continue
        run = next((r for r in s["runs"] if r["contact"] and r["severity"] == s["capacity"]), None)
        out[(run or {}).get("kind") or "unknown"] += 1
    return dict(sorted(out.items()))
