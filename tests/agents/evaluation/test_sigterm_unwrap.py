"""``sigterm_exits`` hands the caller the interrupt a signal handler raised, even when a
compiled (numba) function was running and CPython wrapped it in a ``SystemError``."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from agents.evaluation.backends import sigterm_exits


def _wrapped(inner: BaseException) -> SystemError:
    err = SystemError("CPUDispatcher(<function _sums>) returned a result with an exception set")
    err.__cause__ = inner
    return err


def test_systemexit_under_systemerror_comes_out_as_143() -> None:
    with pytest.raises(SystemExit) as info, sigterm_exits():
        raise _wrapped(SystemExit(143))
    assert info.value.code == 143


def test_keyboard_interrupt_under_systemerror_comes_out_as_itself() -> None:
    with pytest.raises(KeyboardInterrupt), sigterm_exits():
        err = SystemError("wrapped")
        err.__context__ = KeyboardInterrupt()
        raise err


def test_a_plain_systemerror_stays_a_systemerror() -> None:
    with pytest.raises(SystemError, match="plain"), sigterm_exits():
        raise SystemError("plain") from ValueError("not an interrupt")


_SELF_SIGTERM = """
import os, signal
import numba
from agents.evaluation.backends import sigterm_exits

@numba.njit(cache=False)
def spin(n):
    acc = 0.0
    for i in range(n):
        acc += (i + 1.0) ** 0.5
    return acc

spin(10)  # compiled before the signal
with sigterm_exits():
    os.kill(os.getpid(), signal.SIGTERM)  # pending: the handler runs at the next bytecode
    spin(10)
print("not reached")
"""


def test_real_sigterm_in_a_process_exits_143() -> None:
    """In a child process: pytest's own signal handling stays out of it, and a failure
    cannot terminate the test run."""
    root = Path(__file__).resolve().parents[3]
    env = {**os.environ, "PYTHONPATH": str(root)}
    proc = subprocess.run(
        [sys.executable, "-c", _SELF_SIGTERM], cwd=root, env=env, capture_output=True, text=True
    )
    assert proc.returncode == 143, proc.stderr[-2000:]
    assert "not reached" not in proc.stdout
