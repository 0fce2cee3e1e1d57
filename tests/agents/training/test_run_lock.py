"""One run per directory (issue 17, part 2, point 4): while ``train.py --out D`` runs, a
second ``train.py --out D`` — with ``--resume``, new, or ``--eval-only`` — is refused naming
D and the running pid, and leaves the first run's files alone."""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("stable_baselines3")

from agents.cli import train as cli  # noqa: E402
from agents.training import checkpoints as ck  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
TINY = ["--preset", "tiny", "--no-eval", "--no-progress"]


def test_second_train_on_the_same_out_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1"}
    first = subprocess.Popen(
        [
            sys.executable,
            str(ROOT / "train.py"),
            *TINY,
            "--out",
            str(out),
            "--n-envs",
            "2",
            "--timesteps",
            "10000000",
            "--checkpoint-freq",
            "512",
            "--eval-freq",
            "1000000000",
        ],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 180
        while not [c for c in ck.list_checkpoints(out) if c.manifest is not None]:
            assert first.poll() is None, first.communicate()[1][-2000:]
            assert time.monotonic() < deadline, "no checkpoint from the first run"
            time.sleep(0.2)
        capsys.readouterr()
        second = [*TINY, "--out", str(out), "--n-envs", "2", "--timesteps", "1024"]
        for args in (
            [*second, "--resume"],
            second,
            ["--preset", "tiny", "--no-progress", "--out", str(out), "--eval-only"],
        ):
            code = cli.main(args)
            err = capsys.readouterr().err
            assert code == 2, (args, err)
            assert str(out) in err and f"pid {first.pid}" in err and "in use" in err, err
        assert first.poll() is None  # the first run goes on
        first.send_signal(signal.SIGINT)
        _, err = first.communicate(timeout=120)
    finally:
        if first.poll() is None:
            first.kill()
            first.wait()
    assert first.returncode == 130, err[-2000:]
    assert not (out / ".lock").exists()  # released; the resume of the first run may start
    assert not (out / "model.zip").exists()  # nobody else finished a model into its dir
    # issue 17, point 9: checkpoints honour the umask (they were 0600 whatever it was)
    mask = os.umask(0)
    os.umask(mask)
    files = [f for f in (out / "checkpoints").iterdir() if f.is_file()]
    assert files and {stat.S_IMODE(f.stat().st_mode) for f in files} == {0o666 & ~mask}
