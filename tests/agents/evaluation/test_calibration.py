"""``hyperloop calibrate`` and :mod:`agents.evaluation.calibration`: the published suite
file and calibration report are what the library makes of ``calibration.json``; a tiny
calibration writes its report, keeps an earlier calibration's other families and the
suite's; refusals are one error line and exit 2."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from agents.cli.calibrate import main
from agents.evaluation import calibration as cal

ROOT = Path(__file__).resolve().parents[3]
PUBLISHED = ROOT / "docs" / "benchmark" / "calibration.json"
SUITE = ROOT / "agents" / "evaluation" / "benchmark_suite.json"


def _refused(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if "error:" in ln]
    assert len(lines) == 1, err
    return lines[0]


def test_help(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        main(["--help"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: hyperloop calibrate") and "--rewrite-suite" in out


def test_the_published_suite_file_is_rewritten_from_the_published_calibration(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "suite.json"
    argv = ["--rewrite-suite", str(PUBLISHED), "--seeds", "6", "--distance-km", "4"]
    assert main([*argv, "--suite-file", str(out)]) == 0
    assert out.read_text() == SUITE.read_text()
    assert f"wrote {out}" in capsys.readouterr().out


def test_the_published_report_is_the_rendering_of_the_published_calibration() -> None:
    """calibration.md below its introduction (written by hand) is
    :func:`calibration_markdown` of calibration.json."""
    md = cal.calibration_markdown(cal.read_calibration(PUBLISHED), "x", 1.0).splitlines()
    pub = (ROOT / "docs" / "benchmark" / "calibration.md").read_text().splitlines()

    def table(lines: list[str]) -> list[str]:
        return lines[next(i for i, ln in enumerate(lines) if ln.startswith("| family |")) :]

    assert table(md) == table(pub)


def test_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    suite = ["--suite-file", str(tmp_path / "suite.json")]
    line = _refused(["--rewrite-suite", str(tmp_path / "none.json"), *suite], capsys)
    assert "none.json: no such file" in line
    bad = tmp_path / "calibration.json"
    bad.write_text(json.dumps({"roughness": {"grid": [0.1]}}))
    line = _refused(["--rewrite-suite", str(bad), *suite], capsys)
    assert "calibration.json: family 'roughness' has no 'fixed'" in line
    assert "--distance-km" in _refused(
        ["--distance-km", "0", "--out", str(tmp_path), *suite], capsys
    )
    assert not (tmp_path / "suite.json").exists()
    cwd = os.getcwd()
    os.chdir(tmp_path)  # not a checkout: the checkout's default paths are refused
    try:
        assert "pass --out and --suite-file" in _refused([], capsys)
        assert "pass --suite-file" in _refused(["--out", "r"], capsys)
    finally:
        os.chdir(cwd)


def test_a_tiny_calibration_keeps_the_earlier_families(tmp_path: Path) -> None:
    out = tmp_path / "bench"
    out.mkdir()
    earlier = cal.read_calibration(PUBLISHED)
    (out / "calibration.json").write_text(json.dumps(earlier))
    suite_file = tmp_path / "suite.json"
    suite_file.write_text(SUITE.read_text())
    grids = {"sensor_dropout": {**cal.GRIDS["sensor_dropout"], "levels": [0.05, 0.8]}}
    spec = cal.CalibrationSpec(seeds=2, distance_km=0.8, families=("sensor_dropout",), grids=grids)
    lines: list[str] = []
    res = cal.run(spec, out, suite_file, workers=1, figures=False, log=lines.append)
    assert len(lines) == 1 and lines[0].startswith("sensor_dropout: levels [")
    now = res["calibration"]["sensor_dropout"]
    assert now["grid"] == [0.05, 0.8] and now["controllers"] == ["pid"]
    assert now["report"] == str(out / "calibration" / "sensor_dropout" / "report.md")
    assert (out / "calibration" / "sensor_dropout" / "fragility_fits.csv").is_file()
    written = json.loads((out / "calibration.json").read_text())
    assert list(written) == list(earlier)  # the family order of GRIDS
    assert written["roughness"] == earlier["roughness"] and written["sensor_dropout"] == now
    md = (out / "calibration.md").read_text()
    assert md.startswith("# Benchmark suite calibration\n\nCommand: `hyperloop calibrate --seeds 2")
    suite = json.loads(suite_file.read_text())
    assert suite["calibration"]["seeds"] == [cal.CALIBRATION_SEED0, cal.CALIBRATION_SEED0 + 1]
    old = json.loads(SUITE.read_text())
    assert suite["families"]["roughness"] == old["families"]["roughness"]
    if "sensor_dropout" in suite["families"]:
        fam = suite["families"]["sensor_dropout"]
        assert fam["levels"] == now["levels"]
        assert fam["grid"] == cal.fitting_grid(now["levels"], 0.05, 0.8)


def test_fitting_grid() -> None:
    assert cal.fitting_grid([0.21, 0.3, 0.43], 0.1, 0.8) == [
        0.12,
        0.16,
        0.21,
        0.3,
        0.43,
        0.58,
        0.77,
    ]
