"""Tests of the single Gymnasium environment HyperloopSuspension-v0."""

from __future__ import annotations

import math
import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import hyperloop_env  # noqa: F401  (registration)
from hyperloop_env.env import HyperloopSuspensionEnv
from hyperloop_env.observation import (
    OBS_ACC,
    OBS_CURRENT,
    OBS_CURV,
    OBS_GAP,
    OBS_GAP_RATE,
    OBS_LAT,
    OBS_SIZE,
    OBS_SPEED,
    PREVIEW_DISTANCES_M,
    action_to_current,
)
from hyperloop_env.reward import REWARD_TERMS
from hyperloop_env.scenarios import SCENARIOS

ENV_ID = "HyperloopSuspension-v0"
INFO_KEYS = {
    "position_m",
    "time_s",
    "gap_excursion_m",
    "lateral_offset_m",
    "current_A",
    "acceleration_m_s2",
    "contact",
    "reward_terms",
    "speed_kmh",
    "curve_radius_m",
    "state",
}


def make(**kwargs) -> HyperloopSuspensionEnv:
    return gym.make(ENV_ID, **kwargs).unwrapped


def rollout(env, actions, seed=None):
    """Observations, rewards, flags and gaps of a rollout (reset on done)."""
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for a in actions:
        obs, r, te, tr, info = env.step(a)
        out += [obs, np.array([r, te, tr]), info["gap_excursion_m"], info["state"]]
        if te or tr:
            out.append(env.reset()[0])
    return out


def assert_same(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert np.array_equal(x, y)


@pytest.mark.parametrize("scenario", sorted(SCENARIOS))
def test_gymnasium_check_env(scenario, monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")  # check_env also renders in "human"
    env = gym.make(ENV_ID, scenario=scenario, render_mode="rgb_array")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)
    env.close()


@pytest.mark.parametrize("scenario", sorted(SCENARIOS))
def test_sb3_check_env(scenario):
    env = gym.make(ENV_ID, scenario=scenario)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sb3_check_env(env)


def test_spaces_and_info():
    env = make()
    assert env.action_space == gym.spaces.Box(-1, 1, (4,), np.float32)
    assert env.observation_space.shape == (OBS_SIZE,)
    assert env.observation_space.dtype == np.float32
    obs, info = env.reset(seed=0)
    assert obs.dtype == np.float32 and obs.shape == (OBS_SIZE,)
    assert INFO_KEYS <= set(info)
    assert set(info["reward_terms"]) == set(REWARD_TERMS)
    obs, reward, te, tr, info = env.step(np.zeros(4, np.float32))
    assert INFO_KEYS <= set(info)
    assert info["gap_excursion_m"].shape == (4,)
    assert info["lateral_offset_m"].shape == (4,)
    assert info["current_A"].shape == (4,)
    assert info["acceleration_m_s2"].shape == (2,)
    assert info["contact"] is False
    assert info["speed_kmh"] == 1000.0 and math.isinf(info["curve_radius_m"])
    assert info["state"].shape == env.state.shape
    assert reward == pytest.approx(sum(info["reward_terms"].values()), abs=1e-12)
    assert isinstance(reward, float)
    assert env.sim is env.unwrapped.sim


def test_observation_layout_matches_contract():
    env = make(scenario="paper-1000-curved", coil_time_constant_s=0.0)
    obs, info = env.reset(seed=1)
    assert np.all(obs[OBS_GAP_RATE] == 0.0)
    prev_gap = info["gap_excursion_m"]
    a = np.array([0.1, -0.2, 0.3, 0.0], np.float32)
    for _ in range(60):
        obs, _, _, _, info = env.step(a)
        p = env.params
        omega = p.magnet.clearance_m
        gap = info["gap_excursion_m"]
        np.testing.assert_allclose(obs[OBS_GAP], gap / omega, rtol=1e-6)
        rate = (gap - prev_gap) / p.simulation.control_dt_s
        np.testing.assert_allclose(obs[OBS_GAP_RATE], rate, rtol=1e-5, atol=1e-6)
        prev_gap = gap
        lat = info["lateral_offset_m"] / p.guidance.clearance_m
        np.testing.assert_allclose(obs[OBS_LAT], lat, rtol=1e-6)
        np.testing.assert_allclose(obs[OBS_ACC], info["acceleration_m_s2"] / 9.81, rtol=1e-5)
        i0 = env.nominal_current_A
        np.testing.assert_allclose(obs[OBS_CURRENT], info["current_A"] / i0 - 1, atol=1e-6)
    assert obs[OBS_SPEED] == pytest.approx(1000 / 2000)
    # tau = 0: the applied current is the commanded one
    np.testing.assert_allclose(info["current_A"], action_to_current(a, i0), rtol=1e-12)
    # curvature preview at x, x + 250, 500, 1000 m: clothoid 100 … 600 m to 1/200 km
    x = info["position_m"]
    kappa = [min(max((x + d - 100.0) / 500.0, 0.0), 1.0) / 2e5 for d in PREVIEW_DISTANCES_M]
    np.testing.assert_allclose(obs[OBS_CURV], np.array(kappa) * 1e5, rtol=1e-6, atol=1e-9)


def test_action_map_and_clipping():
    env = make()
    env.reset(seed=0)
    a = np.array([-1.0, -0.5, 0.5, 1.0])
    np.testing.assert_array_equal(
        env.action_to_current(a), action_to_current(a, env.nominal_current_A, 1.0)
    )
    assert 39 < env.nominal_current_A < 42
    big = make(action_scale=0.5)
    big.reset(seed=0)
    np.testing.assert_allclose(big.action_to_current([1, 1, 1, 1]), 1.5 * big.nominal_current_A)
    # out-of-range actions are clipped to [-1, 1]
    acts = [np.array([5.0, -7.0, 1e6, -1e6])] * 30
    clipped = [np.clip(x, -1, 1) for x in acts]
    assert_same(rollout(make(), acts, seed=4), rollout(make(), clipped, seed=4))


def test_reset_seed_then_reset_reproduces():
    acts = [np.full(4, 0.2 * np.sin(k / 7), np.float32) for k in range(50)]
    e1, e2 = make(scenario="random"), make(scenario="random")
    e1.reset(seed=11)
    e2.reset(seed=11)
    first1, first2 = e1.reset()[0], e2.reset()[0]  # the second reset continues np_random
    assert np.array_equal(first1, first2)
    assert_same(rollout(e1, acts), rollout(e2, acts))
    # and the same seed reproduces the first episode
    o1, _ = e1.reset(seed=5)
    o2, _ = e1.reset(seed=5)
    assert np.array_equal(o1, o2)


def test_identical_seeds_bit_identical_and_different_seeds_differ():
    rng = np.random.default_rng(0)
    acts = [rng.uniform(-1, 1, 4).astype(np.float32) for _ in range(300)]
    kw = dict(scenario="paper-2000-curved", sensor_noise_std=0.02, track_length_m=60.0)
    a, b = rollout(make(**kw), acts, seed=42), rollout(make(**kw), acts, seed=42)
    assert_same(a, b)
    c = rollout(make(**kw), acts, seed=43)
    assert not np.array_equal(a[1], c[1])


def test_pickle_roundtrip_and_steps():
    env = make(render_mode="rgb_array")
    env.reset(seed=3)
    env.render()
    for _ in range(10):
        env.step(np.full(4, 0.1, np.float32))
    clone = pickle.loads(pickle.dumps(env))
    a = np.array([0.2, -0.1, 0.0, 0.3], np.float32)
    for _ in range(20):
        r1, r2 = env.step(a), clone.step(a)
        assert np.array_equal(r1[0], r2[0]) and r1[1] == r2[1]
    assert clone.render().shape == (360, 640, 3)


@pytest.mark.parametrize(
    "bad",
    [
        np.array([np.nan, 0, 0, 0]),
        np.array([0, np.inf, 0, 0]),
        np.array([0, 0, -np.inf, 0], np.float32),
        np.zeros(3),
        np.zeros((1, 4)),
        np.zeros(5),
        "abcd",
    ],
)
def test_bad_actions_raise_value_error(bad):
    env = gym.make(ENV_ID)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(bad)


def test_step_before_reset_and_after_end_raise():
    env = make(track_length_m=5.0)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(4, np.float32))
    env.reset(seed=0)
    steps = 0
    while True:
        _, _, te, tr, _ = env.step(np.zeros(4, np.float32))
        steps += 1
        if te or tr:
            break
    assert tr and not te and steps == math.ceil(5.0 / (1000 / 3.6 * 1e-3))
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(4, np.float32))
    env.reset()
    env.step(np.zeros(4, np.float32))


def test_default_episode_length():
    env = make()
    assert env.max_episode_steps == 7200  # 2000 m at 1000 km/h, 1 ms steps: 7.2 s
    assert make(scenario="paper-2000-straight").max_episode_steps == 3600
    assert gym.spec(ENV_ID).max_episode_steps is None


def test_coil_time_constant_default_and_lag():
    env = make()
    assert env.params.magnet.coil_time_constant_s == 2e-3
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.ones(4, np.float32))
    i0 = env.nominal_current_A
    expected = 2 * i0 + (i0 - 2 * i0) * math.exp(-1e-3 / 2e-3)  # one step of the lag
    np.testing.assert_allclose(info["current_A"], expected, rtol=1e-9)
    ideal = make(coil_time_constant_s=0.0)
    ideal.reset(seed=0)
    _, _, _, _, info = ideal.step(np.ones(4, np.float32))
    np.testing.assert_allclose(info["current_A"], 2 * ideal.nominal_current_A, rtol=1e-12)


def test_small_radius_at_2000_kmh_ends_in_contact():
    """Paper finding: small radii lead to contact (R = 10 km, 2000 km/h, bias currents; the
    critical radius of this model is ≈ 90 km there, agents.reproduce_paper)."""
    env = make(scenario="paper-2000-curved", curve_radius_m=10_000.0)
    env.reset(seed=0)
    while True:
        _, reward, te, tr, info = env.step(np.zeros(4, np.float32))
        if te or tr:
            break
    assert te and not tr and info["contact"]
    assert info["reward_terms"]["contact"] == -100.0 and info["reward_terms"]["survival"] == 0.0
    assert reward < -99
    assert np.abs(info["lateral_offset_m"]).max() >= env.params.guidance.clearance_m


def test_attracting_magnet_passive_fails_fast():
    env = make(magnet="attracting")
    env.reset(seed=0)
    for _ in range(250):
        _, _, te, tr, info = env.step(np.zeros(4, np.float32))
        if te or tr:
            break
    assert te and info["time_s"] <= 0.2


def test_passive_repelling_straight_survives_a_while():
    env = make(track_length_m=300.0)
    env.reset(seed=0)
    while True:
        _, r, te, tr, info = env.step(np.zeros(4, np.float32))
        assert 0.5 < r <= 1.0  # the survival bonus dominates while flying
        if te or tr:
            break
    assert tr and not te


def test_sensor_noise_and_delay():
    a = np.zeros(4, np.float32)
    clean, noisy = make(), make(sensor_noise_std=0.05)
    oc, ic = clean.reset(seed=2)
    on, in_ = noisy.reset(seed=2)
    assert not np.array_equal(oc[:18], on[:18])
    assert np.array_equal(oc[18:], on[18:])  # speed and curvature preview are exact
    assert np.array_equal(ic["gap_excursion_m"], in_["gap_excursion_m"])  # info is truth
    assert 0.02 < np.std(on[:18] - oc[:18]) < 0.1
    delayed = make(sensor_delay=1)
    o0, _ = delayed.reset(seed=2)
    clean.reset(seed=2)
    prev = o0
    for _ in range(5):
        od = delayed.step(a)[0]
        assert np.array_equal(od, prev)
        prev = clean.step(a)[0]


def test_render_rgb_array():
    env = gym.make(ENV_ID, render_mode="rgb_array", scenario="paper-2000-curved")
    env.reset(seed=0)
    env.step(np.zeros(4, np.float32))
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    assert frame.std() > 5  # not blank
    assert env.metadata["render_fps"] > 0 and "rgb_array" in env.metadata["render_modes"]
    env.close()


def _headless(monkeypatch):
    for var in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setattr("sys.platform", "linux")


def test_render_human_without_display_warns_clearly(monkeypatch):
    _headless(monkeypatch)
    env = make(render_mode="human")
    with pytest.warns(UserWarning, match="needs a display.*rgb_array"):
        env.reset(seed=0)
    assert env.render() is None
    env.step(np.zeros(4, np.float32))
    env.close()


def test_default_check_env_passes_headless(monkeypatch):
    """``check_env(gym.make(ID).unwrapped)`` re-makes the env with render_mode="human";
    on a machine without a display it must pass (as CartPole does), with a warning."""
    _headless(monkeypatch)
    env = gym.make(ENV_ID)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        check_env(env.unwrapped)
    env.close()


EXTREME = st.sampled_from([1.0, -1.0, 1e6, -1e6, 0.0, 3.0])


@st.composite
def action_sequences(draw):
    kind = draw(st.sampled_from(["random", "extreme", "alternating", "bang"]))
    n = draw(st.integers(50, 400))
    if kind == "random":
        vals = draw(st.lists(st.floats(-2.0, 2.0), min_size=4, max_size=4 * 8))
        base = np.resize(np.array(vals), (n, 4))
    elif kind == "extreme":
        base = np.full((n, 4), draw(EXTREME))
    elif kind == "alternating":
        amp = draw(EXTREME)
        period = draw(st.integers(1, 20))
        sign = np.where((np.arange(n) // period) % 2 == 0, 1.0, -1.0)
        base = amp * sign[:, None] * np.array([1.0, -1.0, -1.0, 1.0])
    else:
        base = np.resize(np.array([draw(EXTREME) for _ in range(4)]), (n, 4))
    return base.astype(np.float32) if draw(st.booleans()) else base


@settings(
    max_examples=50, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    actions=action_sequences(),
    magnet=st.sampled_from(["repelling", "attracting"]),
    scenario=st.sampled_from(sorted(SCENARIOS)),
    tau=st.sampled_from([0.0, 2e-3]),
    seed=st.integers(0, 2**31 - 1),
)
def test_property_observations_and_rewards_stay_finite(actions, magnet, scenario, tau, seed):
    env = HyperloopSuspensionEnv(
        scenario, magnet=magnet, coil_time_constant_s=tau, track_length_m=60.0
    )
    obs, _ = env.reset(seed=seed)
    assert np.isfinite(obs).all()
    for a in actions:
        obs, r, te, tr, info = env.step(a)
        assert np.isfinite(obs).all() and math.isfinite(r)
        assert obs in env.observation_space
        assert np.all(info["current_A"] >= 0) and np.all(info["current_A"] <= 100.0)
        if te or tr:
            obs, _ = env.reset()


def test_action_to_current_maps_every_channel_as_step_applies_it():
    """With guidance actuated, ``action_to_current`` gives each channel's commanded current
    as the simulator applies it (no coil lag: the applied current is the command):
    levitation I0·(1 + s·a), guidance pairs the differential I_g0·s·a — in the single and the
    vector env."""
    from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

    kw = {
        "actuators": "levitation+guidance",
        "scenario": "paper-1000-straight",
        "coil_time_constant_s": 0.0,
        "action_scale": 0.5,
    }
    a = np.array([0.2, -0.1, 0.0, 0.5, 0.3, -0.4, 0.0, 1.0], dtype=np.float32)
    env = make(**kw)
    env.reset(seed=1)
    c = env.action_to_current(a)
    from hyperloop_env.physics.model import guidance_bias_A

    i0, ig0 = env.nominal_current_A, guidance_bias_A(env.unwrapped.sim.params)
    assert 15 < ig0 < 17  # I_g0 ≈ 16.2 A by the design rule
    np.testing.assert_allclose(c[:4], i0 * (1 + 0.5 * a[:4].astype(float)), rtol=1e-12)
    np.testing.assert_allclose(c[4:], ig0 * 0.5 * a[4:].astype(float), rtol=1e-12)
    _, _, _, _, info = env.step(a)
    np.testing.assert_allclose(info["current_A"], c[:4], rtol=1e-12)
    np.testing.assert_allclose(info["guidance_current_A"], c[4:], rtol=1e-12)
    venv = HyperloopSuspensionVectorEnv(2, **kw)
    venv.reset(seed=[1, 2])
    np.testing.assert_allclose(venv.action_to_current(np.stack([a, a]))[0], c, rtol=1e-12)
    venv.close()
