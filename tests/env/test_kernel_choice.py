"""The vector env's choice between the serial and the threaded kernel: by measurement, the
faster one, re-measuring the other; never a different trajectory."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import hyperloop_env  # noqa: F401  (registration)
from hyperloop_env.kernel_choice import KernelChoice
from hyperloop_env.vector_env import PARALLEL_MIN_ENVS


def run(choice: KernelChoice, serial_s: float, threaded_s: float, steps: int) -> list[bool]:
    used = []
    for _ in range(steps):
        p = choice.parallel()
        used.append(p)
        choice.record(p, threaded_s if p else serial_s)
    return used


def test_the_faster_mode_with_a_probe_of_the_other() -> None:
    c = KernelChoice(probe_every=8)
    used = run(c, serial_s=1.0, threaded_s=0.6, steps=64)
    assert used[:8] == [False, True] * 4  # each measured a few times first
    assert used[8:].count(False) == 56 // 8  # then the threads, the serial one every 8th step
    assert all(used[k] for k in range(8, 64) if k % 8)
    used = run(c, serial_s=1.0, threaded_s=10.0, steps=64)  # the load arrives
    assert sum(used[16:]) == 48 // 8  # it follows: serial, probing the threads
    with pytest.raises(ValueError, match="probe_every"):
        KernelChoice(probe_every=1)


def test_chosen_kernels_fly_the_serial_trajectory_bit_for_bit() -> None:
    n = PARALLEL_MIN_ENVS + 4
    kw = {
        "scenario": "paper-1000-straight",
        "track_length_m": 30.0,
        "vectorization_mode": "vector_entry_point",
    }
    auto = gym.make_vec("hyperloop_env:HyperloopSuspension-v0", num_envs=n, **kw)
    serial = gym.make_vec("hyperloop_env:HyperloopSuspension-v0", num_envs=n, parallel=False, **kw)
    choice = auto.unwrapped._choice
    choice.probe_every = 3  # both kernels fly within the test
    o1, _ = auto.reset(seed=9)
    o2, _ = serial.reset(seed=9)
    actions = np.random.default_rng(0).uniform(-0.3, 0.3, (150, n, 4)).astype(np.float32)
    for a in actions:
        r1, r2 = auto.step(a), serial.step(a)
        for x, y in zip(r1[:4], r2[:4], strict=True):
            assert np.array_equal(x, y)
    assert choice.mean_s[False] is not None and choice.mean_s[True] is not None
