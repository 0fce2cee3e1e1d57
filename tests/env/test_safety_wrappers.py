"""The safe-RL wrappers: Safety-Gymnasium's 6-tuple step and the Lagrangian reward."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import hyperloop_env  # noqa: F401  (registration)
from hyperloop_env.safety_wrappers import LagrangianReward, SafetyGymnasiumStep

ID = "hyperloop_env:HyperloopSuspension-v0"
KW = {"scenario": "paper-1000-straight", "track_length_m": 60.0, "safety_margin_mm": 3.0}
CLOSING = np.full(4, -1.0, np.float32)  # the gaps close: cost, then contact


def test_six_tuple_step_carries_the_info_cost() -> None:
    env = SafetyGymnasiumStep(gym.make(ID, **KW))
    check_env(env.unwrapped, skip_render_check=True)  # the inner env passes Gymnasium's checker
    obs, info = env.reset(seed=2)
    costs = []
    while True:
        out = env.step(CLOSING)
        assert len(out) == 6
        obs, reward, cost, terminated, truncated, info = out
        assert cost == info["cost"] and isinstance(cost, float)
        costs.append(cost)
        if terminated or truncated:
            break
    assert terminated and costs[-1] >= 1.0 and costs[0] == 0.0


def test_lagrangian_reward_is_reward_minus_multiplier_times_cost() -> None:
    plain = gym.make(ID, **KW)
    lag = LagrangianReward(gym.make(ID, **KW), multiplier=2.5)
    plain.reset(seed=4)
    lag.reset(seed=4)
    seen_cost = False
    while True:
        _, r, te, tr, info = plain.step(CLOSING)
        _, r_lag, te2, tr2, info2 = lag.step(CLOSING)
        assert info2["reward"] == r and info2["cost"] == info["cost"]
        assert r_lag == pytest.approx(r - 2.5 * info["cost"], abs=0.0)
        seen_cost |= info["cost"] > 0
        assert (te, tr) == (te2, tr2)
        if te or tr:
            break
    assert seen_cost


def test_multiplier_and_missing_cost_refused() -> None:
    lag = LagrangianReward(gym.make(ID, **KW))
    for bad in (-1.0, float("nan"), float("inf"), "x"):
        with pytest.raises(ValueError, match="multiplier"):
            lag.multiplier = bad
    lag.multiplier = np.float32(0.5)  # numpy scalars are numbers
    assert lag.multiplier == 0.5
    env = SafetyGymnasiumStep(gym.make("Pendulum-v1"))
    env.reset(seed=0)
    with pytest.raises(KeyError, match="no 'cost'"):
        env.step(np.zeros(1, np.float32))
