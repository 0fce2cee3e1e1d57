"""The rollout engine (agents.evaluation.engine): one loop for every evaluation.

A row's run depends only on its job (seed, disturbances), never on the number of rows, the
other rows or the order of the jobs; a run equals the single environment's episode bit for
bit; controllers without ``act_batch`` fly on one row with ``reset(seed)`` per run."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from agents.controllers import make_controller
from agents.evaluation import engine
from agents.evaluation.rollout import episode_config, make_env, run_episode, run_episodes
from hyperloop_env.physics import RECORD_FIELDS

COND = "paper-1000-straight"
_T = RECORD_FIELDS["time_s"].start


def _cfg(km: float = 0.15, **kw: Any) -> Any:
    return episode_config(COND, km, None, kw)


def _ends(ctrl_name: str, jobs: list[engine.Job], rows: int, cfg: Any) -> list[engine.End]:
    ctrl = engine.build_controller(ctrl_name, cfg)
    sched = engine.Jobs(jobs)
    engine.run(ctrl, cfg, rows, sched)
    return sched.ends  # type: ignore[return-value]


def _same(a: engine.End, b: engine.End) -> None:
    assert (a.terminated, a.n_steps) == (b.terminated, b.n_steps)
    np.testing.assert_array_equal(a.first, b.first)
    np.testing.assert_array_equal(a.last, b.last)


def test_a_run_depends_only_on_its_job() -> None:
    """Rows refilled in any order and number give every job the same run, bit for bit;
    a touching severity ends its run early (the row is refilled at once)."""
    cfg = _cfg()
    jobs = [
        engine.Job(3, {"roughness": 0.3}),
        engine.Job(4, None),
        engine.Job(5, {"joint_steps": 0.02}),  # touches: 2 cm steps
        engine.Job(3, None),
    ]
    ref = _ends("pid", jobs, 4, cfg)
    assert ref[2].terminated and ref[2].n_steps < ref[0].n_steps
    assert not ref[0].terminated and not ref[1].terminated
    for rows in (1, 2, 3):
        for e_ref, e in zip(ref, _ends("pid", jobs, rows, cfg), strict=True):
            _same(e_ref, e)
    rev = _ends("pid", jobs[::-1], 2, cfg)[::-1]
    for e_ref, e in zip(ref, rev, strict=True):
        _same(e_ref, e)
    # the same seed without and with roughness differ (the disturbance reached the row)
    assert not np.array_equal(ref[0].last, ref[3].last)


def test_a_run_equals_the_single_environment_episode() -> None:
    """run_episode (the engine) records exactly what a gym.make env loop records with the
    controller's batched law on one row (its ``act`` may round differently: LQR's differs
    by ~1e-10 relative; the engine flies ``act_batch`` wherever a controller has it)."""
    cfg = _cfg(0.1, disturbances={"roughness": 0.3})
    for name in ("lqr", "pid"):
        ep = run_episode(name, cfg, 7, 0.1, None)
        env = make_env(cfg)
        try:
            obs, _ = env.reset(seed=7)
            res = cfg.resolve()
            from agents.controllers.base import control_context

            ctrl = make_controller(name, control_context(res.base, action_scale=res.action_scale))
            ctrl.reset_batch(np.ones(1, dtype=bool))
            sim = env.unwrapped.sim
            recs = [sim.meas.copy()]
            while True:
                obs, _, te, tr, _ = env.step(ctrl.act_batch(obs[None])[0])
                recs.append(sim.meas.copy())
                if te or tr:
                    break
        finally:
            env.close()
        rec = np.array(recs)
        assert ep.n_steps == len(rec) - 1
        np.testing.assert_array_equal(ep.time_s, rec[:, _T])
        np.testing.assert_array_equal(ep.gap_m, rec[:, RECORD_FIELDS["gap_excursion_m"]])
        np.testing.assert_array_equal(ep.current_A, rec[:, RECORD_FIELDS["current_A"]])


class _SingleOnly:
    """A controller without act_batch: records its resets."""

    name = "single-only"

    def __init__(self) -> None:
        self.resets: list[int | None] = []

    def reset(self, seed: int | None = None) -> None:
        self.resets.append(seed)

    def act(self, obs: np.ndarray) -> np.ndarray:
        return np.zeros(4)


def test_a_controller_without_act_batch_flies_its_runs_one_after_the_other() -> None:
    cfg = _cfg(0.05)
    c = _SingleOnly()
    eps = run_episodes(lambda ctx: c, cfg, [11, 12, 13], 0.05, None)
    assert c.resets == [11, 12, 13]
    passive = run_episodes("passive", cfg, [11, 12, 13], 0.05, None)
    for a, b in zip(eps, passive, strict=True):  # zero action == passive (I0)
        np.testing.assert_array_equal(a.gap_m, b.gap_m)
    with pytest.raises(ValueError, match="rows=1"):
        engine.run(c, cfg, 2, engine.Jobs([engine.Job(1)]))


class _Refill:
    """A schedule that decides the next run from the last: the next seed after a run."""

    def __init__(self) -> None:
        self.seen: list[tuple[int, bool]] = []
        self.todo = [21, 22]

    def next(self, row: int) -> engine.Job | None:
        return engine.Job(self.todo.pop(0)) if self.todo else None

    def ended(self, row: int, job: engine.Job, end: engine.End) -> None:
        self.seen.append((job.seed, end.terminated))
        if job.seed == 21:
            self.todo.append(23)


def test_a_schedule_may_choose_the_next_run_from_the_runs_it_saw() -> None:
    cfg = _cfg(0.05)
    s = _Refill()
    run = engine.run(engine.build_controller("passive", cfg), cfg, 1, s)
    assert [x[0] for x in s.seen] == [21, 22, 23]
    assert run.run_steps == run.steps  # one row, never idle
    s2 = _Refill()
    run2 = engine.run(engine.build_controller("passive", cfg), cfg, 2, s2)
    assert sorted(x[0] for x in s2.seen) == [21, 22, 23]
    assert run2.run_steps == run.run_steps and run2.steps > run2.run_steps  # an idle row


class _IdleSpy:
    """PID that records the engine's ``idle_batch`` masks (and the step it got each)."""

    def __init__(self, cfg: Any) -> None:
        self.pid = engine.build_controller("pid", cfg)
        self.steps = 0
        self.masks: list[tuple[int, list[bool]]] = []

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        self.steps += 1
        return self.pid.act_batch(obs)

    def reset_batch(self, mask: np.ndarray) -> None:
        self.pid.reset_batch(mask)

    def idle_batch(self, mask: np.ndarray) -> None:
        self.masks.append((self.steps, np.asarray(mask).tolist()))


def test_the_engine_tells_the_controller_its_idle_rows() -> None:
    """A row whose work is done is announced idle once, when it goes idle (and a schedule
    that starts with fewer jobs than rows announces the empty rows before the first step);
    the runs are those of a controller without the hook, bit for bit."""
    cfg = _cfg()
    jobs = [engine.Job(5, {"joint_steps": 0.02}), engine.Job(3, None)]  # the first touches
    spy = _IdleSpy(cfg)
    sched = engine.Jobs(jobs)
    engine.run(spy, cfg, 2, sched)
    ref = _ends("pid", jobs, 2, cfg)
    for e_ref, e in zip(ref, sched.ends, strict=True):
        _same(e_ref, e)
    assert spy.masks == [(ref[0].n_steps, [True, False])]
    spy3 = _IdleSpy(cfg)
    engine.run(spy3, cfg, 3, engine.Jobs(jobs))
    assert spy3.masks == [(0, [False, False, True]), (ref[0].n_steps, [True, False, True])]


@pytest.mark.parametrize("rows", [0, -1, 1.5, True, "2"])
def test_rows_must_be_a_positive_int(rows: Any) -> None:
    cfg = _cfg(0.05)
    with pytest.raises(ValueError, match="rows must be an int >= 1"):
        engine.run(engine.build_controller("passive", cfg), cfg, rows, engine.Jobs([]))


def test_an_empty_schedule_is_refused() -> None:
    cfg = _cfg(0.05)
    with pytest.raises(ValueError, match="no job"):
        engine.run(engine.build_controller("passive", cfg), cfg, 1, engine.Jobs([]))


def test_run_episodes_gives_the_same_episodes_with_fewer_rows(monkeypatch) -> None:  # noqa: ANN001
    """More seeds than MAX_ROWS wait for a free row: the same episodes, in seed order."""
    import agents.evaluation.rollout as rollout

    cfg = _cfg(0.05)
    seeds = [1, 2, 3, 4, 5]
    a = run_episodes("pid", cfg, seeds, 0.05, None)
    monkeypatch.setattr(rollout, "MAX_ROWS", 2)
    b = run_episodes("pid", cfg, seeds, 0.05, None)
    assert [e.seed for e in b] == seeds
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x.gap_m, y.gap_m)
        np.testing.assert_array_equal(x.current_A, y.current_A)


class _IdleWatch:
    """A recorder that sees the vector env and keeps the state of row 0 while it idles."""

    def attach(self, venv: Any) -> None:
        self.venv = venv
        self.states: list[np.ndarray] = []

    def started(self, row: int, job: engine.Job, meas: np.ndarray) -> None:
        pass

    def step(self, meas: np.ndarray, active: np.ndarray, row_t: np.ndarray) -> None:
        if not active[0] and active[1]:
            self.states.append(self.venv.sim.Y[0].copy())

    def ended(self, row: int, job: engine.Job, end: engine.End) -> None:
        pass


def test_idle_rows_are_held_not_flown() -> None:
    """A row whose run ended with no job left keeps its reset state while the other row
    flies (the vector env holds its physics); the runs are those each flies alone."""
    cfg = _cfg()
    jobs = [engine.Job(5, {"joint_steps": 0.02}), engine.Job(3, {"roughness": 0.3})]
    watch = _IdleWatch()
    ctrl = engine.build_controller("pid", cfg)
    sched = engine.Jobs(jobs)
    engine.run(ctrl, cfg, 2, sched, recorder=watch)
    assert sched.ends[0].terminated  # row 0's run touched early: it idled after
    assert len(watch.states) > 100
    for y in watch.states[1:]:
        np.testing.assert_array_equal(y, watch.states[0])
    for job, end in zip(jobs, sched.ends, strict=True):
        _same(end, _ends("pid", [job], 1, cfg)[0])
