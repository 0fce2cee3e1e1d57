"""Evaluation runner and CLI (short distances; the 10 km timing run is speed/bench_evaluate.py)."""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from agents.evaluation.evaluate import evaluate, expand_scenarios

ROOT = Path(__file__).resolve().parents[3]


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def test_expand_scenarios() -> None:
    assert len(expand_scenarios(["paper"])) == 4
    assert expand_scenarios(["paper-1000-curved", "paper-1000-curved"]) == ["paper-1000-curved"]
    with pytest.raises(ValueError, match="unknown scenario"):
        expand_scenarios(["moon"])


def test_evaluate_short_writes_all_files(tmp_path: Path) -> None:
    res = evaluate(
        ["passive", "pid"],
        ["paper-1000-straight"],
        0.3,
        1,
        "repelling",
        tmp_path,
        settle_s=0.2,
        progress=False,
        n_boot=50,
    )
    for name in ("report.md", "results.json", "summary.csv", "sts_units.csv"):
        assert (tmp_path / name).stat().st_size > 0
    pngs = sorted((tmp_path / "figures").glob("*.png"))
    # per case: gap histograms, guidance-gap histograms, time series; one comparison
    assert len(pngs) == 7 and (tmp_path / "figures" / "comparison.png") in pngs
    data = json.loads((tmp_path / "results.json").read_text())
    assert data["settings"]["distance_km"] == 0.3
    m = data["results"][0]["metrics"]
    for key in (
        "rms_gap_mm",
        "p_unsteady",
        "a_wz_m_s2",
        "a_wy_m_s2",
        "rms_current_dev_A",
        "n_contact_episodes",
        "time_to_first_contact_s",
    ):
        assert key in m
    units = data["results"][0]["sts"]["units"]
    assert [u["name"] for u in units] == ["FL", "FR", "RL", "RR"]
    assert {"mean_m", "std_m", "ks_pvalue", "p_steady", "p_unsteady", "p_unsteady_ci"} <= set(
        units[0]
    )
    rows = list(csv.DictReader((tmp_path / "summary.csv").open()))
    assert [r["controller"] for r in rows] == ["passive", "pid"]
    md = (tmp_path / "report.md").read_text()
    assert "| FL |" in md and "P(unsteady)" in md
    assert len(res["results"]) == 2


def test_attracting_passive_is_reported_not_dropped(tmp_path: Path) -> None:
    evaluate(
        ["passive"],
        ["paper-1000-straight"],
        0.3,
        1,
        "attracting",
        tmp_path,
        settle_s=0.2,
        progress=False,
        n_boot=50,
    )
    m = json.loads((tmp_path / "results.json").read_text())["results"][0]
    assert m["metrics"]["n_contact_episodes"] == 1
    assert 0 < m["metrics"]["time_to_first_contact_s"] < 0.5
    assert m["metrics"]["p_unsteady"] == 1.0
    assert all(u["p_unsteady"] == 1.0 for u in m["sts"]["units"])
    md = (tmp_path / "report.md").read_text()
    assert "contact" in md and "passive" in md


@pytest.mark.parametrize(
    ("args", "msg"),
    [
        (["--controllers", "nope"], "unknown controller"),
        (["--scenarios", "moon"], "unknown scenario"),
        (["--distance-km", "0"], "distance-km"),
        (["--distance-km", "-1"], "distance-km"),
        (["--seeds", "0"], "seeds"),
        (["--magnet", "sticky"], "magnet"),
    ],
)
def test_cli_rejects_bad_arguments(args: list[str], msg: str, tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "agents.evaluate", "--out", str(tmp_path), "--no-progress", *args],
        cwd=ROOT,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode != 0
    assert msg in proc.stderr
    assert not (tmp_path / "report.md").exists()


def test_cli_runs(tmp_path: Path) -> None:
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "agents.evaluate",
            "--controllers",
            "passive",
            "--scenarios",
            "paper-2000-straight",
            "--distance-km",
            "0.2",
            "--seeds",
            "1",
            "--settle-s",
            "0.1",
            "--out",
            str(tmp_path),
            "--no-progress",
            "--no-figures",
            "--n-boot",
            "20",
        ],
        cwd=ROOT,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "report.md").exists()
