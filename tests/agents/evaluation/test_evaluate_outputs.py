"""The evaluation CLI's output folder: one run per folder, figures written atomically,
distinct figure files for controllers whose names give the same file name."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from agents.evaluation.outputs import output_lock

ROOT = Path(__file__).resolve().parents[3]

SHORT = [
    "--scenarios",
    "paper-2000-straight",
    "--distance-km",
    "0.2",
    "--seeds",
    "1",
    "--settle-s",
    "0.1",
    "--no-progress",
    "--n-boot",
    "10",
]


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}


def _run_main(*args: str) -> subprocess.CompletedProcess[str]:
    code = "import sys; from agents.evaluation.evaluate import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run(
        [sys.executable, "-c", code, *args],
        cwd=ROOT,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_evaluate_refuses_a_folder_another_run_holds(tmp_path: Path) -> None:
    out = tmp_path / "out"
    with output_lock(out, "test"):
        proc = _run_main("--controllers", "passive", "--no-figures", *SHORT, "--out", str(out))
        assert proc.returncode == 2, proc.stderr
        assert str(out) in proc.stderr and "in use" in proc.stderr, proc.stderr
        assert "Traceback" not in proc.stderr
        assert not (out / "results.json").exists()
        assert not (out / "report.md").exists()
    # once released, the same folder is used (and the lock file is gone afterwards)
    proc = _run_main("--controllers", "passive", "--no-figures", *SHORT, "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    assert (out / "results.json").is_file()
    assert not (out / ".lock").exists()
