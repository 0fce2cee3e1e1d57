"""``hyperloop tune``: the PID design scan, the preview weight scan and a preset from an
agent search, through the command (agents.cli.tune) and the library modules."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from agents.cli import tune as cli
from agents.controllers.pid import GAINS_FILE, PIDDesign, load_design
from agents.training import tune_preview as tv

ROOT = Path(__file__).resolve().parents[3]


def test_pid_scan_defaults() -> None:
    a = cli.build_parser().parse_args(["pid"])
    assert a.omega == [60, 80, 100, 130] and a.zeta == [0.7, 1.0] and a.rho == [0.1, 0.2]
    assert (a.deriv_ratio, a.distance_km, a.seed, a.settle_s, a.max_radius) == (
        5.0,
        1.0,
        100,
        0.5,
        0.995,
    )
    assert a.scenarios == ["paper-1000-straight", "paper-1000-curved", "paper-2000-straight"]
    assert a.gains_file == GAINS_FILE and not a.dry_run
    assert cli.build_parser().parse_args(["pid", "--settle-s", "1"]).settle_s == 1.0


def test_preview_scan_defaults() -> None:
    a = cli.build_parser().parse_args(["preview"])
    assert a.weights == [0.25, 0.5, 0.75, 1.0]
    assert (a.validation_seeds, a.distance_km) == (16, 3.0)
    assert a.weight_file == ROOT / "agents" / "controllers" / "lqr_preview_weight.json"


def test_pid_scan_writes_the_best_design(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A small grid: designs the closed-loop check rejects are recorded, not flown; the
    best flown design is written with the command and loads as the PID's design."""
    out = tmp_path / "gains.json"
    args = ["pid", "--omega", "40,60", "--zeta", "0.7", "--rho", "0.1,0.2"]
    args += ["--distance-km", "0.3", "--scenarios", "paper-1000-straight"]
    assert cli.main([*args, "--gains-file", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "best: PIDDesign(omega_rad_s=60.0, zeta=0.7, integral_ratio=0.2" in printed
    doc = json.loads(out.read_text())
    assert doc["command"] == "hyperloop tune " + " ".join([*args, "--gains-file", str(out)])
    assert load_design(out) == PIDDesign(60.0, 0.7, 0.2, 5.0)
    rows = doc["search"]["rows"]
    assert [(r["omega_rad_s"], r["integral_ratio"]) for r in rows] == [
        (40.0, 0.1),
        (40.0, 0.2),
        (60.0, 0.1),
        (60.0, 0.2),
    ]
    assert [r["status"] for r in rows].count("ok") == 1
    assert all(r["score_rms_gap_mm"] is None for r in rows if r["status"] != "ok")
    assert set(doc["gains_paper_defaults"]) == {"repelling", "attracting"}
    assert cli.main([*args, "--gains-file", str(tmp_path / "dry.json"), "--dry-run"]) == 0
    assert not (tmp_path / "dry.json").exists()


def test_pid_scan_refuses_bad_values(capsys: pytest.CaptureFixture[str]) -> None:
    for bad in (["--distance-km", "0"], ["--omega", "a,b"], ["--settle-s", "-1"]):
        with pytest.raises(SystemExit) as exc:
            cli.main(["pid", *bad])
        assert exc.value.code == 2, bad
        assert "hyperloop tune pid: error:" in capsys.readouterr().err


def _fake_capacities(
    controller: str, controller_kwargs: dict[str, Any] | None = None, **kw: Any
) -> dict[str, dict[str, list[Any]]]:
    """lqr: capacity 1 on every seed; lqr-preview: 1 + α(1 − α) (best at α = 0.5)."""
    w = (controller_kwargs or {}).get("preview_weight", 0.0)
    c = 1.0 + w * (1.0 - w) if controller == "lqr-preview" else 1.0
    seeds = list(range(2_000_000, 2_000_000 + kw["seeds"]))
    return {
        cond: {"seeds": seeds, "capacity": [c] * len(seeds), "censored": [False] * len(seeds)}
        for cond in ("a", "b")
    }


def test_preview_scan_keeps_the_best_weight(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from agents.training import tune

    monkeypatch.setattr(tune, "validation_capacities", _fake_capacities)
    out = tmp_path / "w.json"
    args = ["preview", "--weights", "0.25,0.5,1", "--validation-seeds", "4"]
    assert cli.main([*args, "--weight-file", str(out)]) == 0
    assert "best alpha 0.5 (score +0.2231)" in capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert doc["weight"] == 0.5 and doc["seeds"] == [2_000_000, 2_000_003]
    assert doc["distance_km"] == 3.0 and doc["command"].startswith("hyperloop tune preview ")
    assert [r["weight"] for r in doc["scan"]] == [0.25, 0.5, 1.0]
    assert doc["scan"][2]["score"] == 0.0
    assert cli.main([*args, "--weight-file", str(tmp_path / "d.json"), "--dry-run"]) == 0
    assert not (tmp_path / "d.json").exists()
    for bad in (["--weights", "3"], ["--validation-seeds", "1"]):
        with pytest.raises(SystemExit) as exc:
            cli.main(["preview", *bad])
        assert exc.value.code == 2
    assert "--validation-seeds must be >= 2" in capsys.readouterr().err
    with pytest.raises(ValueError, match="weights"):
        tv.scan([])


def test_agent_mode_writes_a_preset(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from agents.training import presets

    monkeypatch.setattr(presets, "PRESET_DIR", tmp_path)
    monkeypatch.setitem(presets.PRESETS, "base", {"algo": "ppo", "n_envs": 4})
    res = tmp_path / "tune_results.json"
    res.write_text(json.dumps({"chosen_training_config": {"learning_rate": 5e-4, "seed": 7}}))
    assert cli.main(["agent", str(res), "--base", "base", "--name", "mine"]) == 0
    assert f"wrote {tmp_path / 'mine.json'}" in capsys.readouterr().out
    got = json.loads((tmp_path / "mine.json").read_text())
    assert got == {"algo": "ppo", "n_envs": 4, "learning_rate": 5e-4, "out": "runs/mine"}
    with pytest.raises(SystemExit) as exc:
        cli.main(["agent", str(res), "--base", "base"])
    assert exc.value.code == 2
    assert "--base and --name are required" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        cli.main(["agent", str(tmp_path / "nothing"), "--collect", "4"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("hyperloop tune agent: error: ") and "no Ray Tune search here" in err


def test_tune_is_a_subcommand(capsys: pytest.CaptureFixture[str]) -> None:
    from agents.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["tune", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: hyperloop tune ") and "{agent,pid,preview}" in out
