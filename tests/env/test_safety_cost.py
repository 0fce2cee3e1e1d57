"""The safety cost (``info["cost"]``, :mod:`hyperloop_env.safety`): the margin logic against
hand-computed cases, both environments through every autoreset mode, the keywords."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import hyperloop_env  # noqa: F401  (registration)
from hyperloop_env.config import EnvConfig
from hyperloop_env.safety import safety_cost

ID = "hyperloop_env:HyperloopSuspension-v0"
KW = {"scenario": "paper-1000-straight", "track_length_m": 60.0}  # 216 steps
MM = 1e-3
OM = 8 * MM  # Ω = Ω_g = 8 mm


def cost(gap_mm, lat_mm, margin_mm=2.0, kind="indicator", contact=False) -> float:
    g = np.asarray(gap_mm, dtype=float) * MM
    z = np.asarray(lat_mm, dtype=float) * MM
    return float(safety_cost(g, z, OM, OM, margin_mm * MM, kind, contact))


def test_indicator_by_hand() -> None:
    quiet = [0.0, 1.0, -2.0, 3.0]
    assert cost(quiet, quiet) == 0.0
    assert cost([0, 0, 0, 5.9], quiet) == 0.0  # 5.9 mm < 8 − 2 mm
    assert cost([0, 0, 0, -6.1], quiet) == 1.0  # |−6.1| > 6: either sign
    assert cost(quiet, [6.5, 0, 0, 0]) == 1.0  # the guidance gap counts too
    assert cost([0, 0, 0, 6.1], quiet, margin_mm=0.5) == 0.0  # a smaller margin: 7.5 mm
    assert cost([0, 0, 0, 7.6], quiet, margin_mm=0.5) == 1.0


def test_continuous_by_hand() -> None:
    quiet = [0.0, 0.0, 0.0, 0.0]
    assert cost([7.0, 0, 0, 0], quiet, kind="continuous") == pytest.approx(0.5)  # (7 − 6)/2
    assert cost(quiet, [0, -9.0, 0, 0], kind="continuous") == pytest.approx(1.5)  # (9 − 6)/2
    both = cost([6.5, 0, 0, 0], [0, 0, 7.5, 0], kind="continuous")
    assert both == pytest.approx(0.75)  # the worst of the eight excursions
    assert cost([5.0, 0, 0, 0], quiet, kind="continuous") == 0.0
    # margin 0: the continuous cost is the indicator
    assert cost([8.5, 0, 0, 0], quiet, margin_mm=0.0, kind="continuous") == 1.0


def test_contact_costs_at_least_one() -> None:
    quiet = [0.0] * 4
    assert cost(quiet, quiet, contact=True) == 1.0
    assert cost([7.0, 0, 0, 0], quiet, kind="continuous", contact=True) == 1.0
    assert cost([12.0, 0, 0, 0], quiet, kind="continuous", contact=True) == pytest.approx(3.0)
    diverged = safety_cost(np.full(4, np.nan), np.zeros(4), OM, OM, 2 * MM, "indicator", True)
    assert float(diverged) == 1.0
    nan_gap = np.array([np.nan, 0.0, 0.0, 0.0])  # never a silent 0 for a non-finite state
    assert float(safety_cost(nan_gap, np.zeros(4), OM, OM, 2 * MM, "continuous")) == 1.0


def test_vectorised_over_steps() -> None:
    gap = np.array([[0, 0, 0, 0], [0, 6.5, 0, 0], [0, 0, 0, 0]]) * MM
    lat = np.array([[0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, -7.0]]) * MM
    np.testing.assert_array_equal(safety_cost(gap, lat, OM, OM, 2 * MM), [0.0, 1.0, 1.0])


def test_keywords_checked_and_left_out_of_to_kwargs_at_their_defaults() -> None:
    assert not {"safety_margin_mm", "safety_cost"} & set(EnvConfig().to_kwargs())
    cfg = EnvConfig(safety_margin_mm=3.0, safety_cost="continuous")
    assert EnvConfig.from_kwargs(**cfg.to_kwargs()) == cfg
    with pytest.raises(ValueError, match="safety_margin_mm"):
        EnvConfig(safety_margin_mm=8.0)  # not below the 8 mm clearance
    with pytest.raises(ValueError, match="safety_margin_mm"):
        EnvConfig(safety_margin_mm=-0.5)
    with pytest.raises(ValueError, match="safety_cost"):
        EnvConfig(safety_cost="binary")


def fly(env: gym.Env, action: np.ndarray) -> tuple[list[float], list[dict]]:
    costs, infos = [], []
    while True:
        _, _, te, tr, info = env.step(action)
        costs.append(info["cost"])
        infos.append(info)
        if te or tr:
            return costs, infos


def test_single_env_cost_is_the_margin_rule_on_its_info() -> None:
    env = gym.make(ID, **KW, safety_margin_mm=0.5)
    _, info = env.reset(seed=3)
    assert info["cost"] == 0.0
    costs, infos = fly(env, np.full(4, -1.0, np.float32))  # the gaps close: contact
    assert infos[-1]["contact"] and costs[-1] >= 1.0
    for c, i in zip(costs, infos, strict=True):
        worst = max(np.abs(i["gap_excursion_m"]).max(), np.abs(i["guidance_gap_excursion_m"]).max())
        assert c == (1.0 if worst > 7.5 * MM or i["contact"] else 0.0)
    env = gym.make(ID, **KW)
    env.reset(seed=3)
    costs, infos = fly(env, np.zeros(4, np.float32))  # nominal currents: no contact
    assert not infos[-1]["contact"] and sum(costs) == 0.0


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
def test_vector_env_cost_through_autoresets(mode: AutoresetMode) -> None:
    n = 3
    venv = gym.make_vec(
        ID, num_envs=n, vectorization_mode="vector_entry_point", autoreset_mode=mode, **KW
    )
    _, info = venv.reset(seed=5)
    np.testing.assert_array_equal(info["cost"], np.zeros(n))
    assert info["_cost"].all()
    action = np.full((n, 4), -1.0, np.float32)
    seen_contact = False
    for _ in range(400):
        _, _, te, _, info = venv.step(action)
        if mode == AutoresetMode.SAME_STEP and te.any():
            final = info["final_info"]
            assert (final["cost"][te] >= 1.0).all()  # the contact step's own cost
            seen_contact = True
        elif te.any():
            assert (info["cost"][te] >= 1.0).all()
            seen_contact = True
        assert info["cost"].shape == (n,) and np.isfinite(info["cost"]).all()
    assert seen_contact
    venv.close()


def test_vector_rows_equal_the_single_env() -> None:
    single = gym.make(ID, **KW, safety_cost="continuous")
    single.reset(seed=11)
    want, _ = fly(single, np.full(4, -0.6, np.float32))
    venv = gym.make_vec(
        ID,
        num_envs=1,
        vectorization_mode="vector_entry_point",
        autoreset_mode=AutoresetMode.DISABLED,
        safety_cost="continuous",
        **KW,
    )
    venv.reset(seed=11)
    got = []
    for _ in want:
        _, _, te, tr, info = venv.step(np.full((1, 4), -0.6, np.float32))
        got.append(float(info["cost"][0]))
    assert got == want
    assert any(c > 0 and not math.isclose(c, 1.0) for c in want)  # graded values flew
