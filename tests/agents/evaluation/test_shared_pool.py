"""One pool of worker processes for the phases of a study (backends.shared_pool): the calls
inside the context run on the same processes, the results come back in the order of the
specs whatever order they finish in, a failed call does not break the next one, and the
context leaves the environment as it found it."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass

import pytest

from agents.evaluation.backends import results_in_order, shared_pool


@dataclass(frozen=True)
class _Done:
    steps: int
    pid: int
    value: int


def _whoami(spec: tuple[int, float], progress: object = None) -> _Done:
    """Twice the spec's value, after sleeping its delay [s], and the worker's pid."""
    value, delay = spec
    if value < 0:
        raise ValueError(f"a bad spec {value}")
    time.sleep(delay)
    return _Done(0, os.getpid(), 2 * value)


def _specs(n: int) -> list[tuple[int, float]]:
    """The later specs sleep less, so they finish first on two workers."""
    return [(i, 0.05 * (n - i)) for i in range(n)]


def test_the_calls_of_a_context_share_one_pool_and_keep_the_specs_order() -> None:
    with shared_pool(2):
        first = results_in_order(_specs(6), _whoami, workers=2)
        second = results_in_order(_specs(3), _whoami, workers=2)
    assert [r.value for r in first] == [0, 2, 4, 6, 8, 10]
    assert [r.value for r in second] == [0, 2, 4]
    pool = {r.pid for r in first}
    assert len(pool) == 2 and os.getpid() not in pool
    assert {r.pid for r in second} <= pool  # the same processes, not a new pool
    later = results_in_order(_specs(4), _whoami, workers=2)  # outside: a pool of its own
    assert [r.value for r in later] == [0, 2, 4, 6]
    assert not {r.pid for r in later} & pool


def test_a_failed_call_stops_the_pool_and_the_next_call_starts_another() -> None:
    saved = {v: os.environ.get(v) for v in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS")}
    with shared_pool(2):
        assert os.environ["OMP_NUM_THREADS"] == "1"  # the workers spawned later inherit it
        with pytest.raises(ValueError, match="a bad spec -1"):
            results_in_order([(1, 0.0), (-1, 0.0)], _whoami, workers=2)
        again = results_in_order(_specs(2), _whoami, workers=2)
        assert [r.value for r in again] == [0, 2]
    assert {v: os.environ.get(v) for v in saved} == saved


def test_one_worker_runs_here_and_bad_counts_are_refused() -> None:
    with shared_pool(1):
        done = results_in_order(_specs(2), _whoami)
    assert [r.pid for r in done] == [os.getpid()] * 2
    with pytest.raises(ValueError, match="workers must be an int >= 1"):
        with shared_pool(0):
            pass
