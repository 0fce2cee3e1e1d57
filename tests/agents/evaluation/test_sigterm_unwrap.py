"""``sigterm_exits`` hands the caller the interrupt a signal handler raised, even when a
compiled (numba) function was running and CPython wrapped it in a ``SystemError``."""

from __future__ import annotations

import os
import signal

import numba
import numpy as np
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


@numba.njit(cache=False)
def _spin(n: int) -> float:
    acc = 0.0
    for i in range(n):
        acc += np.sqrt(i + 1.0)
    return acc


def test_real_sigterm_during_a_compiled_call_exits_143() -> None:
    _spin(10)  # compile first
    with pytest.raises(SystemExit) as info, sigterm_exits():
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        os.kill(os.getpid(), signal.SIGTERM)  # pending: delivered at the next bytecode
        _spin(10)
    assert info.value.code == 143
    assert signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, None)
