"""Signals on the evaluation CLIs (issue 17, part 2): real signals to real subprocesses.

* point 6: SIGTERM to ``python -m agents.fragility --workers 2`` leaves no process behind
  (its worker processes and multiprocessing's resource tracker end with it);
* point 3: SIGINT while a benchmark block writes its outputs leaves no half-written block,
  and ``--resume`` finishes the run.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1"}


def _sigint_default() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _children(pid: int) -> set[int]:
    """Live (not zombie) processes whose parent is ``pid`` (from /proc; no psutil)."""
    out = set()
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            stat = (d / "stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2 :].split()
        if int(fields[1]) == pid and fields[0] != "Z":
            out.add(int(d.name))
    return out


def _alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2 :].split()[0] != "Z"


def test_sigterm_to_fragility_with_workers_leaves_no_process(tmp_path: Path) -> None:
    log = tmp_path / "stderr.txt"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "agents.fragility",
            "--controllers",
            "passive",
            "pid",
            "--levels",
            "0.1",
            "0.2",
            "0.3",
            "0.4",
            "0.5",
            "0.6",
            "--seeds",
            "2",
            "--distance-km",
            "20",  # long enough to be mid-run at the signal (0.6 km could finish first)
            "--block-size",
            "1",
            "--workers",
            "2",
            "--no-figures",
            "--no-progress",
            "--n-boot",
            "10",
            "--n-boot-fragility",
            "10",
            "--out",
            str(tmp_path / "f"),
        ],
        cwd=ROOT,
        env=_env(),
        stdout=subprocess.DEVNULL,
        stderr=log.open("w"),
    )
    kids: set[int] = set()
    try:
        deadline = time.monotonic() + 120
        while len(kids) < 3:  # two workers and the resource tracker
            assert proc.poll() is None, log.read_text()[-2000:]
            assert time.monotonic() < deadline, f"workers never started: {kids}"
            kids |= _children(proc.pid)
            time.sleep(0.1)
        time.sleep(2.0)  # the workers are busy with blocks
        kids |= _children(proc.pid)
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=60)
        deadline = time.monotonic() + 15
        while any(_alive(k) for k in kids) and time.monotonic() < deadline:
            time.sleep(0.1)
        left = [k for k in kids if _alive(k)]
        assert not left, f"left behind after SIGTERM: {left}"
        assert proc.returncode in (143, -signal.SIGTERM), (proc.returncode, log.read_text()[-2000:])
        assert not (tmp_path / "f" / "results.json").exists()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for k in kids:  # the processes this test started, if the fix failed
            if _alive(k):
                with contextlib.suppress(OSError):
                    os.kill(k, signal.SIGKILL)


def test_sigint_while_a_block_writes_then_resume_finishes(tmp_path: Path) -> None:
    """Ctrl-C while a benchmark block writes its figures: no block directory is left
    without its results.json (a block appears whole or not at all), the refusal of a plain
    rerun points to --resume, and --resume finishes the run with every entrant."""
    import json

    suite = tmp_path / "suite.json"
    suite.write_text(
        json.dumps({"families": {"roughness": {"levels": [0.3], "grid": [0.15, 0.6], "fixed": {}}}})
    )
    out = tmp_path / "bench"
    cmd = [
        sys.executable,
        "-m",
        "agents.benchmark",
        "--entrants",
        "passive",
        "pid+g",
        "--conditions",
        "paper-2000-straight",
        "paper-2000-curved",
        "--seeds",
        "2",
        "--distance-km",
        "0.6",
        "--suite",
        str(suite),
        "--workers",
        "1",
        "--n-boot",
        "10",
        "--n-boot-fragility",
        "20",
        "--no-progress",
        "--out",
        str(out),
    ]
    log = tmp_path / "stderr.txt"
    proc = subprocess.Popen(
        cmd,
        cwd=ROOT,
        env=_env(),
        stdout=subprocess.DEVNULL,
        stderr=log.open("w"),
        # a Ctrl-C from a terminal: SIGINT at its default in the child even when this test
        # runs in a background job, whose shell starts it ignored (POSIX; a child inherits
        # an ignored SIGINT and Python then keeps ignoring it)
        preexec_fn=_sigint_default,
    )
    try:
        deadline = time.monotonic() + 300
        while not any(q.name == "figures" for q in out.rglob("*")):  # the marker
            assert proc.poll() is None, log.read_text()[-2000:]
            assert time.monotonic() < deadline, "no block started writing its figures"
            time.sleep(0.005)
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode != 0
    for block in (out / "roughness").iterdir():  # nothing half-written, no leftovers
        assert not block.name.startswith("."), block
        json.loads((block / "results.json").read_text())
    again = subprocess.run(cmd, cwd=ROOT, env=_env(), capture_output=True, text=True, timeout=300)
    assert again.returncode == 2 and "--resume to continue it" in again.stderr, again.stderr
    resumed = subprocess.run(
        [*cmd, "--resume"], cwd=ROOT, env=_env(), capture_output=True, text=True, timeout=600
    )
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    h = json.loads((out / "headline.json").read_text())
    assert [r["entrant"] for r in h["headline"]["rows"]] == ["passive", "pid+g"] * 2
    assert all(r["capacity"]["roughness"]["theta"] is not None for r in h["headline"]["rows"])
    assert sorted(q.name for q in (out / "roughness").iterdir()) == [
        "levitation",
        "levitation-guidance",
    ]
    assert not (out / ".lock").exists()
