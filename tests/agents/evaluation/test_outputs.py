"""No lost or mixed evaluation work: --out is checked before anything runs, a previous report
is never replaced silently (and --overwrite leaves no stale figure), episodes shorter than
the settling time are refused, reproduce_paper leaves no empty folder."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from agents.cli import evaluate as evaluate_cli
from agents.cli import paper as paper_cli
from agents.evaluation import evaluate as ev
from agents.evaluation import outputs
from agents.evaluation import reproduce_paper as rp
from agents.evaluation.outputs import OutputDirError

ROOT = Path(__file__).resolve().parents[3]
SHORT = dict(distance_km=0.3, seeds=1, settle_s=0.2, progress=False, n_boot=20)


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _cli(module: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", module, "--no-progress", *args],
        cwd=ROOT,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )


@pytest.fixture
def quick_figures(monkeypatch: pytest.MonkeyPatch) -> None:
    """Placeholder PNGs instead of matplotlib (the files are what these tests look at)."""
    monkeypatch.setattr(ev, "plot_hist", lambda rep, eps, settle, path, **k: path.write_bytes(b"h"))
    monkeypatch.setattr(ev, "plot_timeseries", lambda ep, path, **k: path.write_bytes(b"t"))


@pytest.fixture
def no_episodes(monkeypatch: pytest.MonkeyPatch) -> None:
    """Fail the test if any episode is run."""

    def boom(*a: object, **k: object) -> None:
        raise AssertionError("an episode ran although the output check should have failed")

    monkeypatch.setattr(ev, "run_cases", boom)


def _under_a_file(tmp_path: Path) -> Path:
    (tmp_path / "afile").write_text("x")
    return tmp_path / "afile" / "report"


# ---- --out checked first ----------------------------------------------------------------------


@pytest.mark.parametrize("where", ["/proc/x", "under a file"])
def test_unwritable_out_fails_at_once_without_computing(
    where: str, tmp_path: Path, no_episodes: None
) -> None:
    out = Path(where) if where.startswith("/") else _under_a_file(tmp_path)
    t0 = time.perf_counter()
    with pytest.raises(OutputDirError, match=re.escape(str(out))):
        ev.evaluate(
            ["passive", "pid", "lqr"], ["paper"], distance_km=10.0, out_dir=out, progress=False
        )
    assert time.perf_counter() - t0 < 0.5


def test_cli_unwritable_out_is_a_usage_error(
    tmp_path: Path, no_episodes: None, capsys: pytest.CaptureFixture[str]
) -> None:
    r = _cli(
        "agents.evaluate", "--controllers", "passive", "--distance-km", "10", "--out", "/proc/x"
    )
    assert r.returncode == 2 and "/proc/x" in r.stderr
    assert r.stdout == ""  # no summary table: nothing was computed
    out = _under_a_file(tmp_path)
    with pytest.raises(SystemExit) as exc:
        evaluate_cli.main(["--controllers", "passive", "--out", str(out), "--no-progress"])
    assert exc.value.code == 2 and "afile exists and is not a directory" in capsys.readouterr().err


# ---- never overwrite silently; --overwrite removes the previous report's files ---------------


def test_second_run_refused_then_overwrite_removes_stale_figures(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, quick_figures: None
) -> None:
    out = tmp_path / "rep"
    ev.evaluate(["passive", "pid"], ["paper-1000-straight"], out_dir=out, **SHORT)
    first = {f: f.read_bytes() for f in out.rglob("*") if f.is_file()}
    pid_figures = sorted(p.name for p in (out / "figures").glob("*pid*"))
    assert pid_figures
    (out / "my_notes.txt").write_text("keep me")

    calls = []
    real = ev.run_cases
    monkeypatch.setattr(ev, "run_cases", lambda *a, **k: calls.append(1) or real(*a, **k))
    with pytest.raises(OutputDirError, match="not empty.*overwrite"):
        ev.evaluate(["passive"], ["paper-1000-straight"], out_dir=out, **SHORT)
    assert not calls  # refused before any episode
    assert {f: f.read_bytes() for f in first} == first  # the first report is intact

    ev.evaluate(["passive"], ["paper-1000-straight"], out_dir=out, overwrite=True, **SHORT)
    assert calls
    figs = sorted(p.name for p in (out / "figures").iterdir() if p.name != "comparison.png")
    assert figs and all("_passive_" in f for f in figs)  # the first run's pid figures are gone
    assert not set(pid_figures) & set(figs)
    data = json.loads((out / "results.json").read_text())
    assert data["settings"]["controllers"] == ["passive"]
    assert "pid" not in (out / "report.md").read_text()
    assert (out / "my_notes.txt").read_text() == "keep me"  # not the report's: kept
    assert not [p for p in out.rglob("*") if p.name.endswith(".tmp")]


def test_cli_second_run_refused_and_overwrite(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "rep"
    args = [
        "--controllers",
        "passive",
        "--scenarios",
        "paper-2000-straight",
        "--distance-km",
        "0.3",
        "--settle-s",
        "0.1",
        "--n-boot",
        "10",
        "--no-figures",
        "--out",
        str(out),
        "--no-progress",
    ]
    assert evaluate_cli.main(args) == 0
    (out / "figures").mkdir()
    (out / "figures" / "hist_old.png").write_bytes(b"stale")
    before = (out / "results.json").read_bytes()
    with pytest.raises(SystemExit) as exc:
        evaluate_cli.main(args)
    assert exc.value.code == 2 and "--overwrite" in capsys.readouterr().err
    assert (out / "results.json").read_bytes() == before
    assert evaluate_cli.main([*args, "--overwrite"]) == 0
    assert (out / "results.json").read_bytes() != before  # a new report (its wall time)
    assert not (out / "figures").exists()


def test_failed_evaluation_leaves_no_empty_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def interrupted(*a: object, **k: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(ev, "run_cases", interrupted)
    out = tmp_path / "new" / "rep"
    with pytest.raises(KeyboardInterrupt):
        ev.evaluate(["passive"], ["paper-1000-straight"], out_dir=out, **SHORT)
    assert not out.exists()


# ---- episodes shorter than the settling time ---------------------------------------------------


def test_episode_shorter_than_settling_is_refused(no_episodes: None, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"settle_s=1 s .*distance_km=0\.2.*0\.72 s") as exc:
        ev.evaluate(
            ["passive"],
            ["paper-1000-straight"],
            distance_km=0.2,
            settle_s=1.0,
            out_dir=tmp_path / "r",
            progress=False,
        )
    assert "raise distance_km to >= 0.306 km or lower settle_s to <= 0.62 s" in str(exc.value)
    assert not (tmp_path / "r").exists()
    # a random scenario is checked at its fastest speed (2000 km/h: 0.6 km lasts 1.08 s)
    with pytest.raises(ValueError, match="2000 km/h"):
        ev.evaluate(
            ["passive"], ["random"], distance_km=0.6, settle_s=1.0, out_dir=None, progress=False
        )


def test_cli_episode_shorter_than_settling_names_the_options(
    tmp_path: Path, no_episodes: None, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exc:
        evaluate_cli.main(
            ["--controllers", "passive", "--distance-km", "0.2", "--out", str(tmp_path / "r")]
        )
    err = capsys.readouterr().err
    assert exc.value.code == 2
    assert "--settle-s=1 s" in err and "--distance-km=0.2" in err
    assert not (tmp_path / "r").exists()


def test_distance_beyond_the_memory_budget_names_distance_km(no_episodes: None) -> None:
    with pytest.raises(ValueError, match=r"distance_km=10000 is too long.*MAX_PROFILE_BYTES"):
        ev.evaluate(
            ["passive"], ["paper-1000-straight"], distance_km=1e4, out_dir=None, progress=False
        )


# ---- reproduce_paper ----------------------------------------------------------------------------


def test_reproduce_paper_bad_settle_leaves_no_folder(tmp_path: Path) -> None:
    out = tmp_path / "paper"
    with pytest.raises(SystemExit) as exc:
        paper_cli.main(["--out", str(out), "--settle-s", "-1", "--no-progress"])
    assert exc.value.code == 2 and not out.exists()
    with pytest.raises(SystemExit):
        paper_cli.main(["--out", str(out), "--distance-km", "0.2", "--no-progress"])
    assert not out.exists()
    with pytest.raises(SystemExit):
        paper_cli.main(["--out", "/proc/x", "--no-progress"])


def test_reproduce_paper_refuses_then_overwrites(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    quick_figures: None,
) -> None:
    # the sweep and bisection are long; the output handling is what is tested here
    monkeypatch.setattr(rp, "radius_sweep", lambda *a, **k: [])
    monkeypatch.setattr(rp, "_run_curve", lambda *a, **k: SimpleNamespace(terminated=False))
    out = tmp_path / "paper"
    args = [
        "--out",
        str(out),
        "--distance-km",
        "0.6",
        "--sweep-km",
        "0.6",
        "--settle-s",
        "0.1",
        "--no-progress",
    ]
    assert paper_cli.main(args) == 0
    stale = out / "passive" / "figures" / "hist_passive_old-scenario_repelling.png"
    stale.write_bytes(b"old")
    report = (out / "report.md").read_text()
    with pytest.raises(SystemExit) as exc:
        paper_cli.main(args)
    assert exc.value.code == 2 and "--overwrite" in capsys.readouterr().err
    assert stale.exists() and (out / "report.md").read_text() == report
    assert paper_cli.main([*args, "--overwrite"]) == 0
    assert not stale.exists()
    assert (out / "passive" / "report.md").exists() and (out / "results.json").exists()


# ---- outputs module ------------------------------------------------------------------------------


def test_atomic_write_keeps_the_old_file_on_failure(tmp_path: Path) -> None:
    target = tmp_path / "results.json"
    outputs.atomic_write_text(target, "old")
    with pytest.raises(RuntimeError), outputs.atomic_path(target) as tmp:
        tmp.write_text("half")
        raise RuntimeError("interrupted")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["results.json"]
