"""Fixtures shared by the test packages."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

_HOLD = (
    "import sys, time; from agents.evaluation.outputs import output_lock\n"
    "with output_lock(sys.argv[1]):\n"
    "    print('locked', flush=True); time.sleep(120)\n"
)


@pytest.fixture
def folder_holder() -> Iterator[Callable[[Path], subprocess.Popen[str]]]:
    """``proc = folder_holder(path)``: another process that holds ``path``'s output lock (as
    a running study does) until the test ends or kills it; returned once the lock is held."""
    procs: list[subprocess.Popen[str]] = []

    def hold(path: Path) -> subprocess.Popen[str]:
        proc = subprocess.Popen(
            [sys.executable, "-c", _HOLD, str(path)],
            stdout=subprocess.PIPE,
            text=True,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
        )
        procs.append(proc)
        assert proc.stdout is not None and proc.stdout.readline().strip() == "locked"
        return proc

    yield hold
    for proc in procs:
        proc.kill()
        proc.wait()
