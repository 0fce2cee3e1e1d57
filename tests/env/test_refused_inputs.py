"""Inputs that used to be accepted silently (issue 17, part 2, point 9): a complex action
lost its imaginary part; ``curve_radius_m=1`` gave observations up to 1e5."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import hyperloop_env  # noqa: F401 - registers the env
from hyperloop_env.config import MIN_CURVE_RADIUS_M, EnvConfig
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv


@pytest.mark.parametrize(
    "action",
    [
        np.array([0.5 + 0.5j, 0.0, 0.0, 0.0]),
        [0.1j, 0, 0, 0],
        np.zeros(4, np.complex64),
    ],
)
def test_a_complex_action_is_refused_naming_action(action: object) -> None:
    env = gym.make("HyperloopSuspension-v0", track_length_m=300.0)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action must be real numbers.*complex"):
        env.step(action)
    venv = HyperloopSuspensionVectorEnv(2, "paper-1000-straight", track_length_m=300.0)
    venv.reset(seed=0)
    with pytest.raises(ValueError, match="action must be real numbers.*complex"):
        venv.step(np.stack([np.asarray(action, dtype=np.complex128)] * 2))
    env.close()
    venv.close()


@pytest.mark.parametrize("radius", [1.0, 100.0, MIN_CURVE_RADIUS_M * 0.999])
def test_a_curve_radius_below_the_minimum_is_refused(radius: float) -> None:
    for build in (
        lambda: EnvConfig(scenario="paper-1000-curved", curve_radius_m=radius),
        lambda: gym.make("HyperloopSuspension-v0", curve_radius_m=radius),
        lambda: HyperloopSuspensionVectorEnv(2, "random", curve_radius_m=radius),
    ):
        with pytest.raises(ValueError, match=r"curve_radius_m must be >= 1000 m"):
            build()


def test_the_minimum_radius_is_accepted_and_observations_stay_bounded() -> None:
    env = gym.make(
        "HyperloopSuspension-v0",
        scenario="paper-1000-curved",
        curve_radius_m=MIN_CURVE_RADIUS_M,
        track_length_m=1200.0,
    )
    obs, _ = env.reset(seed=0)
    peak = np.abs(obs).max()
    while True:
        obs, _, te, tr, _ = env.step(np.zeros(4, np.float32))
        peak = max(peak, np.abs(obs).max())
        if te or tr:
            break
    assert peak <= 100.0 + 1e-6  # κ·1e5 m at 1 km; it was 1e5 at 1 m
    env.close()
