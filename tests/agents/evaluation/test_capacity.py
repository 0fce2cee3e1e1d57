"""Per-seed capacities (incremental dynamic analysis): scaling, the search, the engine."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agents.controllers import make_controller
from agents.controllers.base import control_context
from agents.evaluation.capacity import (
    CapacityTask,
    FamilySearch,
    Run,
    Search,
    run_task,
)
from agents.evaluation.rollout import episode_config, make_env
from hyperloop_env.disturbances import DISTURBANCES

SCALING = [f for f, cls in DISTURBANCES.items() if cls.scales_with_severity]
SEVERITY = {
    "roughness": 0.3,
    "pier_settlement": 0.001,
    "thermal_camber": 0.003,
    "joint_steps": 0.0004,
}


@pytest.mark.parametrize("family", SCALING)
def test_realisation_scales_with_severity(family):
    """The profile a seed flies over at severity 2s is twice the one at s (the premise of
    incremental dynamic analysis), for every family that declares it scales
    (``scales_with_severity``)."""
    s = SEVERITY[family]
    profiles = []
    for sev in (s, 2 * s):
        dist = {"roughness": 0.0, family: sev} if family != "roughness" else {family: sev}
        env = make_env(episode_config("paper-1000-straight", 0.3, None, {"disturbances": dist}))
        env.reset(seed=1_000_003)
        profiles.append(env.unwrapped.sim.irr.copy())
        env.close()
    base = make_env(
        episode_config("paper-1000-straight", 0.3, None, {"disturbances": {"roughness": 0.0}})
    )
    base.reset(seed=1_000_003)
    flat = base.unwrapped.sim.irr
    d1, d2 = profiles[0] - flat, profiles[1] - flat
    assert np.abs(d1).max() > 1e-5  # the disturbance is there
    np.testing.assert_allclose(d2, 2 * d1, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("family", [f for f in DISTURBANCES if f not in SCALING])
def test_non_scaling_families_keep_the_grid_design(family):
    with pytest.raises(ValueError, match="does not scale"):
        FamilySearch(family, start=0.1, lower=0.01, upper=1.0)


def _drive(search: Search, fs: FamilySearch, touches) -> None:
    while (s := search.next_severity(fs)) is not None:
        search.record(Run(s, bool(touches(s)), 0.0, None, search.phase))


def test_search_finds_the_first_touch_to_the_stated_precision():
    fs = FamilySearch("roughness", start=0.3, lower=0.01, upper=3.0, check=(0.5, 0.7, 1.0))
    s = Search("roughness", 1)
    _drive(s, fs, lambda x: x >= 0.4123)
    assert s.censored is None and not s.non_monotone
    assert s.lo < 0.4123 <= s.hi and s.hi / s.lo <= 1.02
    assert s.capacity == s.hi
    phases = [r.phase for r in s.runs]
    assert phases[:2] == ["hunt", "hunt"] and phases[-2:] == ["check", "check"]


def test_non_monotone_seed_is_detected_and_keeps_the_first_touch():
    # touches in [0.35, 0.45], flies again above (a "resurrection"), touches above 0.8
    fs = FamilySearch("roughness", start=0.3, lower=0.01, upper=3.0, check=(0.5, 0.9))
    s = Search("roughness", 1)
    _drive(s, fs, lambda x: 0.35 <= x <= 0.45 or x >= 0.8)
    assert s.non_monotone
    assert 0.35 <= s.capacity <= 0.35 * 1.02


def test_censoring_both_ends():
    fs = FamilySearch("roughness", start=0.3, lower=0.1, upper=0.5)
    right = Search("roughness", 1)
    _drive(right, fs, lambda x: False)
    assert right.censored == "right" and right.capacity == 0.5
    left = Search("roughness", 2)
    _drive(left, fs, lambda x: True)
    assert left.censored == "left" and left.capacity == 0.1
    assert [r.severity for r in left.runs] == pytest.approx([0.3, 0.2, 0.1333333, 0.1])


def test_every_search_flies_each_suite_level_once():
    """With the suite's levels, the hunt steps through the neighbouring level (within one
    step), the check never flies a severity twice, and a last phase flies the levels not
    flown yet: every seed flies every level exactly once (the paper's STS at each level);
    the capacity is still the first touch of hunt and fill."""
    levels = (0.21, 0.3, 0.43)
    fs = FamilySearch(
        "roughness",
        start=0.3,
        lower=0.05,
        upper=3.0,
        check=(0.21, 0.3, 0.43, 0.58, 0.77),
        levels=levels,
    )
    for cap in (0.1, 0.25, 0.35, 0.5, 5.0):
        s = Search("roughness", 1, levels=levels)
        _drive(s, fs, lambda x, c=cap: x >= c)
        sev = [r.severity for r in s.runs]
        for v in levels:
            assert sev.count(v) == 1, (cap, sev)
        assert len(sev) == len(set(sev)), (cap, sev)
        assert not s.non_monotone
        if cap < 3.0:
            assert s.lo < cap <= s.hi and s.hi / s.lo <= 1.02
        else:
            assert s.censored == "right"
    up = Search("roughness", 1, levels=levels)
    _drive(up, fs, lambda x: x >= 0.5)
    assert [r.severity for r in up.runs][:2] == [0.3, 0.43]  # the next level, not 0.3 x 1.5
    assert up.runs[-1].phase == "levels" and up.runs[-1].severity == 0.21
    with pytest.raises(ValueError, match="levels must be increasing and hold start"):
        FamilySearch("roughness", start=0.3, lower=0.1, upper=1.0, levels=(0.2, 0.4))
    with pytest.raises(ValueError, match="levels must hold positive"):
        FamilySearch("roughness", start=0.3, lower=0.1, upper=1.0, levels=(-0.1, 0.3))


def test_task_sts_at_every_level_from_one_run_per_seed():
    cfg = episode_config("paper-2000-straight", 0.25, None, {})
    levels = (0.35, 0.5, 0.7)
    fs = FamilySearch("roughness", start=0.5, lower=0.1, upper=4.0, ratio=1.1, levels=levels)
    seeds = (1_000_000, 1_000_001, 1_000_002)
    res = run_task(CapacityTask("passive", cfg, (fs,), seeds, rows=3, n_boot=20, settle_s=0.1))
    st = res.sts["roughness"]
    assert [x["severity"] for x in st["levels"]] == list(levels)
    assert st["start"] is st["levels"][1]
    for x, v in zip(st["levels"], levels, strict=True):
        assert x["n_runs"] == len(seeds)
        touched = sum(r.contact for s in res.searches for r in s.runs if r.severity == v)
        assert x["n_contacts"] == touched
        assert 0.0 <= x["gap"]["p_unsteady"] <= 1.0


def test_family_search_validation():
    with pytest.raises(ValueError, match="lower <= start <= upper"):
        FamilySearch("roughness", start=0.3, lower=0.5, upper=1.0)
    with pytest.raises(ValueError, match="ratio"):
        FamilySearch("roughness", start=0.3, lower=0.1, upper=1.0, ratio=1.0)
    with pytest.raises(ValueError, match="start must be a finite"):
        FamilySearch("roughness", start=math.nan, lower=0.1, upper=1.0)


def _task(rows: int) -> CapacityTask:
    cfg = episode_config("paper-2000-straight", 0.25, None, {})
    fams = (
        FamilySearch("roughness", start=0.5, lower=0.1, upper=4.0, ratio=1.1, check=(1.0, 2.0)),
        FamilySearch("pier_settlement", start=0.002, lower=0.0005, upper=0.02, ratio=1.1),
    )
    return CapacityTask("passive", cfg, fams, (1_000_000, 1_000_001, 1_000_002), rows=rows)


def test_engine_result_does_not_depend_on_the_batch():
    """A search's runs depend only on its seed and severities: the same with 2 rows (rows
    refilled from the queue) as with 6 (every search in its own row)."""
    a = run_task(_task(2))
    b = run_task(_task(6))
    assert [x.to_dict() for x in a.searches] == [x.to_dict() for x in b.searches]
    assert a.run_steps <= a.steps


def test_engine_capacities_match_single_env_runs():
    """Independent check of two brackets: a single env with the passive controller
    touches at the capacity and flies at the largest flying severity below it."""
    res = run_task(_task(4))
    cfg0 = episode_config("paper-2000-straight", 0.25, None, {})
    ctrl = make_controller("passive", control_context(cfg0.resolve().base))
    for s in res.searches[:2]:
        assert s.censored is None
        for sev, touch in ((s.hi, True), (s.lo, False)):
            cfg = episode_config(
                "paper-2000-straight", 0.25, None, {"disturbances": {s.family: sev}}
            )
            env = make_env(cfg)
            obs, _ = env.reset(seed=s.seed)
            ctrl.reset(seed=s.seed)
            te = tr = False
            while not (te or tr):
                obs, _, te, tr, _ = env.step(ctrl.act(obs))
            env.close()
            assert te == touch, (s.family, s.seed, sev)


def test_capacity_fit_agrees_with_the_binary_outcome_fit_on_a_real_sweep():
    """On a real search (passive, 16 seeds), the lognormal fit of the per-seed capacities
    and the binary-outcome MLE of the same seeds at a grid agree on the median."""
    from agents.evaluation import capacity_stats as cs
    from agents.evaluation.capacity import capacities

    cfg = episode_config("paper-2000-straight", 0.25, None, {})
    fs = FamilySearch("roughness", start=0.5, lower=0.1, upper=4.0, ratio=1.05)
    res = run_task(
        CapacityTask(
            "passive", cfg, (fs,), tuple(range(1_000_000, 1_000_016)), rows=16, sts_stride=0
        )
    )
    c, cens = capacities(res.searches)
    fit = cs.fit_capacity_lognormal(c, cens, n_boot=0)
    grid = np.geomspace(c.min() * 0.8, c.max() * 1.2, 9)
    binary = cs.binary_outcome_fit(c, cens, grid)
    assert fit["status"] == "fit" and binary["theta"] is not None
    assert binary["theta"] == pytest.approx(fit["theta"], rel=0.1)


def _tiny_headline(backend: str, workers: int = 1) -> dict:
    from agents.evaluation.capacity_benchmark import run

    return run(
        ["passive", "pid"],
        ["paper-2000-straight"],
        ["roughness"],
        seeds=[1_000_000, 1_000_001, 1_000_002],
        distance_km=0.2,
        workers=workers,
        backend=backend,
        n_boot=50,
        progress=False,
        ratio=1.1,
    )


def test_local_workers_give_the_same_capacities() -> None:
    one = _tiny_headline("local", 1)
    two = _tiny_headline("local", 2)
    assert one["capacities"] == two["capacities"]
    assert one["headline"]["verdicts"] == two["headline"]["verdicts"]


@pytest.mark.slow
def test_ray_backend_gives_the_same_capacities() -> None:
    pytest.importorskip("ray", reason="needs Ray (optional extra: pip install -e '.[ray]')")
    assert _tiny_headline("local")["capacities"] == _tiny_headline("ray")["capacities"]


def test_capacity_cli_uses_the_shared_seed_policy(tmp_path, capsys) -> None:  # noqa: ANN001
    from agents.cli.capacity import main

    with pytest.raises(SystemExit) as e:
        main(["--entrants", "ppo", "--seed0", "5", "--seeds", "2", "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "--allow-training-seeds" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["--seed-list", "3", "3", "--out", str(tmp_path / "o")])
    assert "repeated" in capsys.readouterr().err and not (tmp_path / "o").exists()
    with pytest.raises(SystemExit):
        main(["--entrant-seeds", "mpc:16", "--out", str(tmp_path / "o")])
    assert "expected LABEL=N" in capsys.readouterr().err and not (tmp_path / "o").exists()
    with pytest.raises(SystemExit) as e:
        main(["--entrants", "pid", "--entrant-seeds", "mpc=8", "--out", str(tmp_path / "o")])
    assert (
        e.value.code == 2
        and "'mpc' is not an entrant" in capsys.readouterr().err
        and not (tmp_path / "o").exists()
    )


class _PassiveSingle:
    """passive without act_batch: the bias currents (action 0) through act only."""

    name = "passive-single"

    def __init__(self, ctx) -> None:  # noqa: ANN001
        self.n = ctx.actuators.size

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, obs: np.ndarray) -> np.ndarray:
        return np.zeros(self.n, dtype=np.float32)


def test_a_controller_without_act_batch_gets_the_same_capacities() -> None:
    """It flies one run at a time on one row: the same searches as the batched passive."""
    from agents.controllers.registry import _REGISTRY, register_controller

    register_controller("passive-single-test", lambda ctx, **kw: _PassiveSingle(ctx))
    try:
        t = _task(4)
        single = run_task(
            CapacityTask("passive-single-test", t.config, t.families, t.seeds, rows=4)
        )
        batched = run_task(t)
    finally:
        _REGISTRY.pop("passive-single-test", None)
    assert [s.to_dict() for s in single.searches] == [s.to_dict() for s in batched.searches]
    assert single.steps == single.run_steps  # one row: never idle


def test_an_entrant_on_fewer_seeds_is_paired_on_those() -> None:
    """``entrant_seeds``: pid flies the first 2 of 3 seeds; its capacities are the full run's
    first two (common random numbers), its verdict against passive is that of those two
    seeds, and the settings record it (also in the README text)."""
    from agents.evaluation import capacity_stats as cs
    from agents.evaluation.capacity_benchmark import run
    from agents.evaluation.capacity_report import readme_block

    full = _tiny_headline("local")
    red = run(
        ["passive", "pid"],
        ["paper-2000-straight"],
        ["roughness"],
        seeds=[1_000_000, 1_000_001, 1_000_002],
        distance_km=0.2,
        n_boot=50,
        progress=False,
        ratio=1.1,
        entrant_seeds={"pid": 2},
    )
    cond = "paper-2000-straight"
    cf, cr = full["capacities"][cond]["roughness"], red["capacities"][cond]["roughness"]
    assert cr["passive"] == cf["passive"]
    assert cr["pid"] == cf["pid"][:2] and [d["seed"] for d in cr["pid"]] == [1_000_000, 1_000_001]
    assert red["settings"]["entrant_seeds"] == {"pid": 2}
    assert full["settings"]["entrant_seeds"] == {}
    (v,) = red["analysis"][cond]["roughness"]["verdicts"]
    c = {k: np.array([d["capacity"] for d in cf[k]]) for k in ("passive", "pid")}
    z = np.zeros(2, dtype=bool)
    ref = cs.compare_paired(c["passive"][:2], z, c["pid"][:2], z, n_boot=2000, seed=0)
    assert v["n"] == 2 and v["ratio"] == ref["ratio"] and v["verdict"] == ref["verdict"]
    assert "pid: the first 2" in readme_block(red)
    tasks = {t["entrant"]: t for t in red["settings"]["tasks"]}
    assert tasks["pid"]["seeds"] == 2 and tasks["passive"]["seeds"] == 3
    assert all(t["wall_s"] > 0 and t["run_steps"] <= t["steps"] for t in tasks.values())
    assert all(t["sts_s"] > 0 for t in tasks.values())  # every level's STS is timed


def test_cost_table_sums_each_entrants_tasks() -> None:
    from agents.evaluation.capacity_report import cost_table

    def task(ent: str, seeds: int, wall: float, sts: float, steps: int, run: int) -> dict:
        d = {"entrant": ent, "seeds": seeds, "wall_s": wall, "steps": steps, "run_steps": run}
        return {**d, "sts_s": sts, "condition": "c"}

    doc = {
        "settings": {
            "entrants": ["lqr", "mpc"],
            "workers": 2,
            "wall_s": 300.0,
            "tasks": [
                task("lqr", 4, 60.0, 30.0, 100, 80),
                task("lqr", 4, 60.0, 30.0, 100, 80),
                task("mpc", 2, 120.0, 0.0, 100, 100),
            ],
        }
    }
    rows = {r.split(" | ")[0].strip("| "): r for r in cost_table(doc).splitlines()}
    # lqr: 2 min of flights, 1 of STS, 120 s / 8 seeds = 15 s per seed, 20 % idle, 180/300
    assert rows["lqr"] == "| lqr | 4 | 2.0 | 1.0 | 15.0 | 1.00 | 20 % | 60.0 % |"
    assert rows["mpc"] == "| mpc | 2 | 2.0 | 0.0 | 60.0 | 4.00 | 0 % | 40.0 % |"
    assert "Recorded worker time 5.0 min on 2 workers; wall time 5.0 min." in cost_table(doc)
    with pytest.raises(ValueError, match="no settings.tasks"):
        cost_table({"settings": {"entrants": []}})


def test_reduced_seeds_come_from_the_registry_and_are_validated(monkeypatch) -> None:
    import dataclasses

    from agents.controllers import registry
    from agents.controllers.registry import ControllerSpec
    from agents.evaluation.capacity_benchmark import reduced_seeds

    assert reduced_seeds(["pid", "mpc", "lqr+g"], 32) == {}  # every built-in: all seeds
    mpc16 = dataclasses.replace(registry._REGISTRY["mpc"], entrant_seeds=16)
    monkeypatch.setitem(registry._REGISTRY, "mpc", mpc16)
    assert reduced_seeds(["pid", "mpc", "lqr+g"], 32) == {"mpc": 16}
    assert reduced_seeds(["pid", "mpc"], 16) == {}  # 16 of 16: all seeds
    assert reduced_seeds(["pid", "mpc"], 32, {}) == {}
    assert reduced_seeds(["pid", "lqr+g"], 32, {"lqr+g": 8}) == {"lqr+g": 8}
    with pytest.raises(ValueError, match="'sac' is not an entrant"):
        reduced_seeds(["pid"], 32, {"sac": 8})
    with pytest.raises(ValueError, match=r"entrant_seeds\['pid'\] must be an int >= 2"):
        reduced_seeds(["pid"], 32, {"pid": 1})
    with pytest.raises(ValueError, match="entrant_seeds must be None or an int >= 2"):
        ControllerSpec("x", "a.b:c", entrant_seeds=1)


def test_paired_verdicts_need_common_seeds() -> None:
    from agents.evaluation import capacity_stats as cs

    z = np.zeros(6, bool)
    a = (np.arange(1.0, 7.0), z, [1, 2, 3, 4, 5, 6])
    b_caps = np.array([6.5, 4.4, 3.3, 2.2, 1.1, 0.9])  # seeds 6, 5, …, 1 (and 8: a lacks it)
    b = (np.append(b_caps, 7.0), np.zeros(7, bool), [6, 5, 4, 3, 2, 1, 8])
    (v,) = cs.verdict_matrix({"a": a, "b": b}, n_boot=50)
    ref = cs.compare_paired(a[0], z, b_caps[::-1], z, n_boot=50)  # seed 1 with 1, …
    assert v["n"] == 6 and {k: v[k] for k in ref} == ref
    # (the ratio alone cannot tell: a geometric mean does not see how the pairs are formed)
    wrong = cs.compare_paired(a[0], z, b_caps, z, n_boot=50)
    assert wrong["ratio"] == pytest.approx(ref["ratio"]) and wrong["lo"] != ref["lo"]
    with pytest.raises(ValueError, match="share 1 seeds"):
        cs.verdict_matrix({"a": a, "b": (b[0][:1], b[1][:1], [6])})
    with pytest.raises(ValueError, match="seeds for every entrant or for none"):
        cs.verdict_matrix({"a": a, "b": b[:2]})
