"""The benchmark suite and headline (agents.evaluation.benchmark)."""

from __future__ import annotations

import json
import math

import pytest

from agents.evaluation import benchmark as bm
from agents.evaluation import benchmark_report


def test_seed_ranges_are_disjoint() -> None:
    r = sorted(bm.SEED_RANGES.values())
    for (a0, a1), (b0, b1) in zip(r, r[1:], strict=False):
        assert a0 <= a1 < b0 <= b1


def test_shipped_suite_loads_and_names_known_families() -> None:
    from hyperloop_env.disturbances import DISTURBANCES

    suite = bm.load_suite()
    assert bm.REFERENCE_FAMILY in suite["families"]
    assert len(suite["families"]) >= 3
    for name, spec in suite["families"].items():
        assert name in DISTURBANCES
        assert spec["levels"] == sorted(spec["levels"])
        for v in spec["levels"]:  # every suite level lies inside its fitting grid
            assert min(spec["grid"]) <= v <= max(spec["grid"])
    assert "| roughness |" in bm.suite_markdown(suite)


def test_suite_errors_name_the_field(tmp_path) -> None:  # noqa: ANN001
    p = tmp_path / "s.json"
    p.write_text(json.dumps({"families": {"roughness": {"levels": [0.2, -1], "grid": [0.1]}}}))
    with pytest.raises(ValueError, match=r"families\.roughness\.levels"):
        bm.load_suite(p)
    p.write_text(json.dumps({"families": {"quake": {"levels": [1], "grid": [1]}}}))
    with pytest.raises(ValueError, match="unknown family 'quake'"):
        bm.load_suite(p)
    with pytest.raises(ValueError, match="no benchmark suite"):
        bm.load_suite(tmp_path / "missing.json")


def test_entrants() -> None:
    assert bm.entrant_actuators("pid") == ("pid", "levitation")
    assert bm.entrant_actuators("lqr+g") == ("lqr", "levitation+guidance")
    assert bm.entrant_label("lqr", "levitation+guidance") == "lqr+g"
    with pytest.raises(ValueError, match="unknown entrant 'nope'"):
        bm.entrant_actuators("nope")


@pytest.mark.parametrize(
    ("fit", "expected"),
    [
        (
            {"status": "fit", "theta": 0.4, "theta_ci": [0.35, 0.47], "levels": [0.2, 0.4]},
            (0.4, 0.35, 0.47, "bootstrap"),
        ),
        (
            {
                "status": "quasi_separated",
                "bounds": {"theta_limit": 0.3},
                "levels": [0.1, 0.2, 0.3, 0.4],
            },
            (0.3, 0.2, 0.4, "bracket"),
        ),
        (
            {
                "status": "separated",
                "bounds": {"theta_lower": 0.2, "theta_upper": 0.3},
                "levels": [0.1, 0.2, 0.3],
            },
            (math.sqrt(0.06), 0.2, 0.3, "bracket"),
        ),
        (
            {"status": "no_contact", "bounds": {"theta_lower": 0.8}, "levels": [0.8]},
            (1.2000000000000002, 0.8, math.inf, "lower bound"),
        ),
        (
            {"status": "all_contact", "bounds": {"theta_upper": 0.1}, "levels": [0.1]},
            (0.1 / 1.5, 0.0, 0.1, "upper bound"),
        ),
    ],
)
def test_capacity_interval(fit: dict, expected: tuple) -> None:
    got = bm.capacity_interval(fit)
    assert got[3] == expected[3]
    assert got[:3] == pytest.approx(expected[:3])


def test_resolved() -> None:
    assert bm.resolved((0.2, 0.3), (0.31, 0.5))
    assert not bm.resolved((0.2, 0.35), (0.31, 0.5))
    assert bm.resolved((0.0, 0.1), (0.8, math.inf))
    assert not bm.resolved((math.nan, 0.1), (0.8, 0.9))


def test_small_benchmark_end_to_end(tmp_path) -> None:  # noqa: ANN001
    """Two baselines, one condition, a two-family suite, 2 seeds × 0.6 km: the headline's
    capacities are the sweeps' fits and its P(unsteady) rows are the sweeps' level rows."""
    suite = {
        "families": {
            "roughness": {"levels": [0.3], "grid": [0.15, 0.6], "fixed": {}},
            "payload": {"levels": [0.2], "grid": [0.2], "fixed": {}},
        }
    }
    res = bm.run_benchmark(
        ["passive", "pid+g"],
        ["paper-2000-straight"],
        seeds=2,
        distance_km=0.6,
        suite=suite,
        out_dir=tmp_path,
        figures=False,
        progress=False,
        n_boot=10,
        n_boot_fragility=20,
    )
    h = res["headline"]
    assert h["reference_level"] == 0.3
    assert [r["entrant"] for r in h["rows"]] == ["passive", "pid+g"]
    sweep = res["sweeps"]["roughness"]["levitation"]
    fit = next(f for f in sweep["fits"] if f["controller"] == "passive")["fit"]
    cap = h["rows"][0]["capacity"]["roughness"]
    assert cap["status"] == fit["status"]
    assert cap["theta"] == pytest.approx(bm.capacity_estimate(fit))
    lv = next(r for r in sweep["levels"] if r["controller"] == "passive" and r["level"] == 0.3)
    at = h["rows"][0]["at_levels"][0]
    assert at["p_unsteady"] == lv["p_unsteady"]
    assert at["contact_rate_per_100km"] == lv["contact_rate_per_100km"]
    assert (
        "guidance"
        in res["sweeps"]["roughness"]["levitation+guidance"]["settings"]["env_kwargs"]["actuators"]
    )
    md = (tmp_path / "headline.md").read_text()
    assert "## paper-2000-straight" in md and "| pid+g |" in md
    saved = json.loads((tmp_path / "headline.json").read_text())
    assert saved["settings"]["seed_range"] == [bm.EVAL_SEED0, bm.EVAL_SEED0 + 1]
    with pytest.raises(Exception, match="not empty"):
        bm.run_benchmark(
            ["passive"],
            ["paper-2000-straight"],
            seeds=2,
            distance_km=0.6,
            suite=suite,
            out_dir=tmp_path,
            figures=False,
            progress=False,
        )


def test_merged_runs_equal_the_joint_run(tmp_path) -> None:  # noqa: ANN001
    """Baselines and agents may run separately: merging gives the joint run's headline."""
    suite = {"families": {"roughness": {"levels": [0.3], "grid": [0.15, 0.6], "fixed": {}}}}
    kw = dict(
        conditions=["paper-2000-straight"],
        seeds=2,
        distance_km=0.6,
        suite=suite,
        figures=False,
        progress=False,
        n_boot=10,
        n_boot_fragility=50,
    )
    joint = bm.run_benchmark(["passive", "pid", "pid+g"], out_dir=tmp_path / "j", **kw)
    bm.run_benchmark(["passive"], out_dir=tmp_path / "a", **kw)
    bm.run_benchmark(["pid", "pid+g"], out_dir=tmp_path / "b", **kw)
    merged = bm.merge_runs(
        [tmp_path / "a", tmp_path / "b"], tmp_path / "m", n_boot_fragility=50, figures=False
    )
    assert merged["settings"]["entrants"] == ["passive", "pid", "pid+g"]
    assert json.dumps(merged["headline"], sort_keys=True) == json.dumps(
        joint["headline"], sort_keys=True
    )
    assert (tmp_path / "m" / "roughness" / "levitation" / "report.md").exists()

    # issue 17, points 1, 5 and 9: nothing is deleted before everything is validated
    before = {p: p.read_bytes() for p in (tmp_path / "a").rglob("*") if p.is_file()}
    with pytest.raises(ValueError, match="destination is never one of the sources"):
        bm.merge_runs([tmp_path / "a", tmp_path / "b"], tmp_path / "a", overwrite=True)
    assert {p: p.read_bytes() for p in (tmp_path / "a").rglob("*") if p.is_file()} == before
    report = (tmp_path / "m" / "headline.json").read_bytes()
    with pytest.raises(ValueError, match="given twice"):
        bm.merge_runs([tmp_path / "a", tmp_path / "a"], tmp_path / "m", overwrite=True)
    with pytest.raises(ValueError, match="headline.json not found"):
        bm.merge_runs([tmp_path / "a", tmp_path / "missing"], tmp_path / "m", overwrite=True)
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "headline.json").write_text('{"settings": ')
    with pytest.raises(ValueError, match=r"bad/headline.json is damaged"):
        bm.merge_runs([tmp_path / "a", tmp_path / "bad"], tmp_path / "m", overwrite=True)
    assert (tmp_path / "m" / "headline.json").read_bytes() == report
    other = json.loads((tmp_path / "b" / "headline.json").read_text())
    other["settings"]["n_boot"] = 999
    (tmp_path / "b2").mkdir()
    (tmp_path / "b2" / "headline.json").write_text(json.dumps(other))
    with pytest.raises(ValueError, match="'n_boot'"):
        bm.merge_runs([tmp_path / "a", tmp_path / "b2"], tmp_path / "m", overwrite=True)
    assert (tmp_path / "m" / "headline.json").read_bytes() == report
    assert not list(tmp_path.glob(".m.merging-*"))


def test_resume_reads_finished_blocks_and_equals_the_fresh_run(tmp_path, monkeypatch) -> None:  # noqa: ANN001
    """An interrupted benchmark continues with --resume: the finished family block is read
    (not rerun), the rest runs, the headline equals an uninterrupted run; a block run with
    other settings is refused."""
    import shutil

    from agents.evaluation import fragility as fr

    suite = {"families": {"roughness": {"levels": [0.3], "grid": [0.15, 0.6], "fixed": {}}}}
    kw = dict(
        conditions=["paper-2000-straight"],
        seeds=2,
        distance_km=0.6,
        suite=suite,
        figures=False,
        progress=False,
        n_boot=10,
        n_boot_fragility=50,
    )
    fresh = bm.run_benchmark(["passive", "pid+g"], out_dir=tmp_path / "f", **kw)
    (tmp_path / "r" / "roughness").mkdir(parents=True)
    shutil.copytree(
        tmp_path / "f" / "roughness" / "levitation", tmp_path / "r" / "roughness" / "levitation"
    )
    calls = []
    real = fr.fragility
    monkeypatch.setattr(fr, "fragility", lambda c, *a, **k: calls.append(c) or real(c, *a, **k))
    resumed = bm.run_benchmark(["passive", "pid+g"], out_dir=tmp_path / "r", resume=True, **kw)
    assert calls == [["pid"]]  # only the guidance block ran
    assert json.dumps(resumed["headline"], sort_keys=True) == json.dumps(
        fresh["headline"], sort_keys=True
    )
    with pytest.raises(ValueError, match="was run with seeds"):
        bm.run_benchmark(
            ["passive", "pid+g"], out_dir=tmp_path / "r", resume=True, **{**kw, "seeds": 3}
        )


def test_target_lines_need_resolved_higher_capacity_and_no_worse_comfort() -> None:
    """ppo vs lqr: met only when ppo's roughness interval lies above LQR's at every
    condition and its W_k at the reference level is not above LQR's."""

    def row(cond: str, ent: str, lo: float, hi: float, wk: float) -> dict:
        cap = {"theta": (lo + hi) / 2, "lo": lo, "hi": hi, "kind": "bootstrap", "status": "fit"}
        return {
            "condition": cond,
            "entrant": ent,
            "capacity": {"roughness": cap},
            "at_levels": [{"level": 0.3, "a_wz_m_s2": wk}],
        }

    def h(rows: list[dict]) -> dict:
        return {"reference_level": 0.3, "rows": rows}

    met = h(
        [
            row("paper-1000-straight", "ppo", 0.5, 0.6, 1.0),
            row("paper-1000-straight", "lqr", 0.3, 0.45, 1.2),
        ]
    )
    assert "**met**" in bm.target_lines(met, ["roughness"])
    overlap = h(
        [
            row("paper-1000-straight", "ppo", 0.44, 0.6, 1.0),
            row("paper-1000-straight", "lqr", 0.3, 0.45, 1.2),
        ]
    )
    assert "**not met**" in bm.target_lines(overlap, ["roughness"])
    assert "unresolved" in bm.target_lines(overlap, ["roughness"])
    shaky = h(
        [
            row("paper-1000-straight", "ppo", 0.5, 0.6, 1.3),
            row("paper-1000-straight", "lqr", 0.3, 0.45, 1.2),
        ]
    )
    assert "**not met**" in bm.target_lines(shaky, ["roughness"])
    assert (
        bm.target_lines(h([row("paper-1000-straight", "pid", 0.5, 0.6, 1.0)]), ["roughness"]) == ""
    )


def test_a_bracket_open_at_the_top_of_the_grid_reads_as_infinite() -> None:
    """θ → the top grid level: JSON has no upper bound (null); it is +inf, not unknown."""
    cap = {"theta": 0.0038, "lo": 0.0028, "hi": None, "kind": "bracket"}
    assert benchmark_report._fmt_cap(cap) == "0.0038 [0.0028, ∞] ‡"
    assert bm.resolved(cap, (0.001, 0.002))
    assert not bm.resolved(cap, (0.001, 0.003))
