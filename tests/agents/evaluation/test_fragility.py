"""Fragility evaluation: streamed runs against the stored-signal evaluation, the batched
protocol, backends (identical for 1 and 2 local workers; Ray in a slow test) and the CLI."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from agents.cli.fragility import main
from agents.controllers import register_controller
from agents.evaluation.batch_rollout import BlockSpec, build_controller, run_block
from agents.evaluation.fragility import fragility
from agents.evaluation.fragility_report import deterministic_view
from agents.evaluation.metrics import summarise
from agents.evaluation.rollout import episode_config, run_episode
from hyperloop_env.comfort import ride_comfort

COND = "paper-1000-straight"


def _cfg(km: float = 0.6, rough: float = 0.3):  # type: ignore[no-untyped-def]
    return episode_config(COND, km, None, {"disturbances": {"roughness": rough}})


def test_streamed_run_equals_the_stored_signal_evaluation() -> None:
    """Stride 1: the STS report, RMS, max, contacts and comfort of the streamed run equal
    agents.evaluation's on the full stored episode."""
    cfg = _cfg()
    spec = BlockSpec("passive", cfg, (0, 1, 5), settle_s=0.3, thin_stride=1)
    block = run_block(spec)
    eps = [run_episode(lambda env: build_controller(spec), cfg, s, 0.6, None) for s in (0, 1, 5)]
    assert [r.terminated for r in block.runs] == [e.terminated for e in eps]
    assert any(e.terminated for e in eps) and not all(e.terminated for e in eps)
    for r, e in zip(block.runs, eps, strict=True):
        assert r.n_steps == e.n_steps
        np.testing.assert_array_equal(r.thinned_gap, e.gap_m[1:])
        np.testing.assert_array_equal(r.thinned_lateral, e.lateral_m[1:])
        assert r.distance_m == pytest.approx(e.distance_m, abs=1e-9)
        if r.terminated:
            assert (r.contact_kind, r.contact_position_m) == (e.contact_kind, e.contact_position_m)
        c = ride_comfort(e.acc_m_s2[1:, 0], e.acc_m_s2[1:, 1], e.dt_s, 0.3)
        assert r.a_wz_m_s2 == pytest.approx(c.a_wz_m_s2, rel=1e-9)
        assert r.a_v_m_s2 == pytest.approx(c.a_v_m_s2, rel=1e-9)
        post = e.gap_m[1 + 300 :]
        np.testing.assert_allclose(
            np.sqrt(r.gap["sumsq"] / r.gap["n"]), np.sqrt((post**2).mean(axis=0)), rtol=1e-12
        )
        np.testing.assert_array_equal(r.gap["maxabs"], np.abs(post).max(axis=0))
        np.testing.assert_array_equal(r.exceed[-1], (np.abs(post) >= 0.008).sum(axis=0))
    from agents.evaluation.fragility import Group, summarise_group

    g = Group(0, "passive", COND, 0.3, cfg, 1, 2160)
    row = summarise_group(g, [block], n_boot=30, settle_s=0.3)
    report, metrics, guidance = summarise(eps, 0.3, n_boot=30)
    assert row["p_unsteady"] == report.worst_p_unsteady
    assert row["sts"]["units"][0]["p_unsteady_fit_ci"] == list(report.units[0].p_unsteady_fit_ci)
    assert row["p_unsteady_guidance"] == guidance.worst_p_unsteady
    assert row["rms_lateral_mm"] == pytest.approx(metrics["rms_lateral_mm"], rel=1e-9)
    assert row["rms_gap_mm"] == pytest.approx(metrics["rms_gap_mm"], rel=1e-12)
    assert row["max_abs_gap_mm"] == pytest.approx(metrics["max_abs_gap_mm"], rel=1e-12)
    assert row["a_v_m_s2"] == pytest.approx(metrics["a_v_m_s2"], rel=1e-9)
    k = sum(e.terminated for e in eps)
    assert (row["n_contacts"], row["n_runs"]) == (k, 3)
    dist = sum(e.distance_m for e in eps) / 1e5
    assert row["contact_rate_per_100km"] == pytest.approx(k / dist, rel=1e-12)


def test_batched_and_single_env_runs_are_identical_for_passive() -> None:
    spec = BlockSpec("passive", _cfg(0.4, 0.35), (2, 3, 4), settle_s=0.2, thin_stride=4)
    a = run_block(spec)
    b = run_block(replace(spec, batched=False))
    assert a.batched and not b.batched
    for ra, rb in zip(a.runs, b.runs, strict=True):
        assert (ra.n_steps, ra.terminated, ra.distance_m) == (
            rb.n_steps,
            rb.terminated,
            rb.distance_m,
        )
        np.testing.assert_array_equal(ra.thinned_gap, rb.thinned_gap)
        for k in ("n", "mean", "m2", "sumsq", "maxabs"):
            np.testing.assert_array_equal(ra.gap[k], rb.gap[k])
        assert ra.a_wz_m_s2 == pytest.approx(rb.a_wz_m_s2, rel=1e-12)


class _Stateful:
    """A batched, stateful test controller: integral of the FL gap per row."""

    name = "stateful-test"
    resets: list[np.ndarray] = []
    params: list[Any] = []

    def __init__(self, ctx: Any) -> None:
        _Stateful.params.append(ctx.params)
        self.acc: np.ndarray | None = None

    def reset(self, seed: int | None = None) -> None:
        self.acc = np.zeros(1)

    def act(self, obs: np.ndarray) -> np.ndarray:
        return self.act_batch(obs[None])[0]

    def reset_batch(self, mask: np.ndarray) -> None:
        _Stateful.resets.append(mask.copy())
        if self.acc is None or self.acc.size != mask.size:
            self.acc = np.zeros(mask.size)
        self.acc[mask] = 0.0

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        assert self.acc is not None
        self.acc = self.acc + obs[:, 0]
        out = np.zeros((obs.shape[0], 4), np.float32)
        out[:, 0] = np.clip(-1e-3 * self.acc, -0.2, 0.2)
        return out


def test_batch_protocol_reset_batch_and_nominal_design() -> None:
    register_controller("stateful-test", lambda ctx, **kw: _Stateful(ctx), overwrite=True)
    dist = {"roughness": 0.2, "pier_settlement": 0.001}
    cfg = episode_config(COND, 0.3, None, {"disturbances": dist})
    _Stateful.resets.clear()
    _Stateful.params.clear()
    a = run_block(BlockSpec("stateful-test", cfg, (0, 1), settle_s=0.1))
    assert a.batched and len(_Stateful.resets) == 1 and _Stateful.resets[0].tolist() == [1, 1]
    # designed on the nominal model: the resolved config's base parameters
    assert _Stateful.params == [cfg.resolve().base]
    b = run_block(BlockSpec("stateful-test", cfg, (0, 1), settle_s=0.1, batched=False))
    for ra, rb in zip(a.runs, b.runs, strict=True):  # same per-row state, same runs
        np.testing.assert_array_equal(ra.thinned_gap, rb.thinned_gap)


def _tiny(**kw: Any) -> dict[str, Any]:
    args: dict[str, Any] = dict(
        controllers=["passive"],
        conditions=[COND],
        family="roughness",
        levels=[0.25, 0.5],
        seeds=3,
        distance_km=0.25,
        settle_s=0.2,
        block_size=2,
        n_boot=20,
        n_boot_fragility=50,
        progress=False,
    )
    args.update(kw)
    return fragility(**args)


def test_local_backend_is_identical_for_one_and_two_workers() -> None:
    one = deterministic_view(_tiny(workers=1))
    two = deterministic_view(_tiny(workers=2))
    assert json.dumps(one, sort_keys=True) == json.dumps(two, sort_keys=True)
    assert one["levels"][1]["n_runs"] == 3


def test_fragility_api_values_and_validation() -> None:
    res = _tiny(max_samples=500)
    rows = res["levels"]
    assert [r["level"] for r in rows] == [0.25, 0.5]
    for r in rows:
        assert r["thin_stride"] == math.ceil(3 * 900 / 500)  # 900 steps per 250 m run
        assert r["n_thinned_samples"] <= 500 + 3
        lo, hi = r["p_contact_ci"]
        assert lo <= r["p_contact"] <= hi
    with pytest.raises(ValueError, match="unknown disturbance family 'hail'"):
        _tiny(family="hail")
    with pytest.raises(ValueError, match="SensorDropout.severity must be < 1"):
        _tiny(family="sensor_dropout", levels=[0.5, 1.0])
    with pytest.raises(ValueError, match="levels must be distinct"):
        _tiny(levels=[0.3, 0.3])


def test_cli_end_to_end_writes_all_files_and_refuses_a_non_empty_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "frag"
    argv = [
        "--controllers",
        "passive",
        "--conditions",
        COND,
        "--family",
        "joint_steps",
        "--levels",
        "0.0005",
        "0.002",
        "--seeds",
        "2",
        "--distance-km",
        "0.2",
        "--settle-s",
        "0.1",
        "--n-boot",
        "10",
        "--n-boot-fragility",
        "20",
        "--no-progress",
        "--out",
        str(out),
    ]
    assert main(argv) == 0
    for name in ("report.md", "results.json", "fragility_levels.csv", "fragility_fits.csv"):
        assert (out / name).stat().st_size > 0, name
    png = out / "figures" / f"fragility_{COND}.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    data = json.loads((out / "results.json").read_text())
    assert data["settings"]["family"] == "joint_steps" and len(data["levels"]) == 2
    assert data["fits"][0]["fit"]["status"] in (
        "fit",
        "no_contact",
        "all_contact",
        "separated",
        "quasi_separated",
    )
    assert "Fragility functions" in (out / "report.md").read_text()
    lines = (out / "fragility_levels.csv").read_text().splitlines()
    assert len(lines) == 3 and lines[0].startswith("controller,condition,level")
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*")}
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    assert "not empty" in capsys.readouterr().err
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*")} == before  # nothing touched


@pytest.mark.slow
def test_ray_backend_equals_the_local_backend() -> None:
    pytest.importorskip("ray", reason="needs Ray (optional extra: pip install -e '.[ray]')")
    local = deterministic_view(_tiny())
    ray_res = deterministic_view(_tiny(backend="ray"))
    assert json.dumps(local, sort_keys=True) == json.dumps(ray_res, sort_keys=True)


def test_a_run_that_touches_while_settling_has_no_comfort_value() -> None:
    block = run_block(BlockSpec("passive", _cfg(0.3, 1.0), (0,), settle_s=0.3))
    r = block.runs[0]
    assert r.terminated and r.n_steps < 300 + 10  # German "low" at 100 %: touches in ~20 m
    assert math.isnan(r.a_wz_m_s2) and math.isnan(r.a_v_m_s2) and r.n_post == 0


def test_blocks_of_long_runs_are_smaller_to_bound_the_profiles_memory() -> None:
    from agents.evaluation.fragility import PROFILE_BYTES_PER_POINT, block_rows, make_plan

    cfg = episode_config(COND, 800.0, None, {})
    per_row_mb = 2**23 * PROFILE_BYTES_PER_POINT / 2**20  # 0.1 m grid, 2^23 points
    assert block_rows(cfg, 16, 2048) == int(2048 // per_row_mb) == 4
    assert block_rows(cfg, 16, 1.0) == 1 and block_rows(_cfg(), 16, 2048) == 16
    plan = make_plan(
        ["passive"], [COND], "roughness", [0.2], range(5), 800.0, block_size=16, max_block_mb=1024
    )
    assert [b.seeds for b in plan.blocks] == [(0, 1), (2, 3), (4,)]
