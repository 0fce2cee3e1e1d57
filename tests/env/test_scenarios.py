"""Tests of the named scenarios, keyword overrides and the registration."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import hyperloop_env
from hyperloop_env.config import EnvConfig, RewardWeights, SensorConfig, build_config
from hyperloop_env.env import HyperloopSuspensionEnv
from hyperloop_env.physics.params import IRREGULARITY_CLASSES
from hyperloop_env.scenarios import (
    RANDOM_IRREGULARITY_CLASSES,
    RANDOM_RADIUS_RANGE_M,
    RANDOM_SPEED_RANGE_KMH,
    SCENARIOS,
)
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

ENV_ID = "HyperloopSuspension-v0"


def test_registration():
    assert hyperloop_env.ENV_ID == ENV_ID
    spec = gym.spec(ENV_ID)
    assert spec.vector_entry_point is not None
    assert spec.max_episode_steps is None
    env = gym.make(ENV_ID, scenario="paper-1000-curved", speed_kmh=1200.0)
    assert isinstance(env.unwrapped, HyperloopSuspensionEnv)
    assert env.unwrapped.params.condition.speed_kmh == 1200.0
    envs = gym.make_vec(ENV_ID, num_envs=3, vectorization_mode="vector_entry_point")
    assert isinstance(envs, HyperloopSuspensionVectorEnv) and envs.num_envs == 3
    envs.close()


def test_named_scenarios():
    assert {
        "paper-1000-straight",
        "paper-1000-curved",
        "paper-2000-straight",
        "paper-2000-curved",
        "random",
    } <= set(SCENARIOS)
    for name, speed, radius in [
        ("paper-1000-straight", 1000.0, math.inf),
        ("paper-1000-curved", 1000.0, 200_000.0),
        ("paper-2000-straight", 2000.0, math.inf),
        ("paper-2000-curved", 2000.0, 200_000.0),
    ]:
        p = build_config(name).base
        assert p.condition.speed_kmh == speed and p.condition.curve_radius_m == radius
        assert p.condition.cant_deg == 0.0
        assert p.simulation.track_length_m == 2000.0
        assert p.magnet.orientation == "repelling"
        assert p.magnet.coil_time_constant_s == 2e-3


def test_overrides_reach_the_model():
    env = HyperloopSuspensionEnv(
        "paper-1000-straight",
        speed_kmh=1500.0,
        curve_radius_m=300_000.0,
        cant_deg=2.0,
        track_length_m=500.0,
        irregularity="none",
        control_dt_s=5e-4,
        clearance_m=0.006,
        magnet="attracting",
        coil_time_constant_s=0.0,
    )
    p = env.params
    assert p.condition.speed_kmh == 1500.0 and p.condition.curve_radius_m == 300_000.0
    assert p.condition.cant_deg == 2.0 and p.simulation.track_length_m == 500.0
    assert p.irregularity.spectrum == "none" and p.simulation.control_dt_s == 5e-4
    assert p.magnet.clearance_m == 0.006 and p.magnet.orientation == "attracting"
    assert p.magnet.coil_time_constant_s == 0.0
    straight = HyperloopSuspensionEnv("paper-1000-curved", curve_radius_m=math.inf)
    assert math.isinf(straight.params.condition.curve_radius_m)


def test_unknown_scenario_lists_valid_names():
    with pytest.raises(ValueError, match="paper-1000-straight") as exc:
        gym.make(ENV_ID, scenario="paper-3000")
    for name in SCENARIOS:
        assert name in str(exc.value)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"speed_kmh": -5.0}, "speed_kmh"),
        ({"curve_radius_m": 0.0}, "curve_radius_m"),
        ({"curve_radius_m": float("nan")}, "curve_radius_m"),
        ({"cant_deg": 45.0}, "cant_deg"),
        ({"track_length_m": 0.0}, "track_length_m"),
        ({"irregularity": "bumpy"}, "maglev-rough"),
        ({"control_dt_s": 0.5}, "control_dt_s"),
        ({"clearance_m": 0.02}, "clearance_m"),
        ({"magnet": "floating"}, "attracting"),
        ({"coil_time_constant_s": -1.0}, "coil_time_constant_s"),
        ({"action_scale": 0.0}, "action_scale"),
        ({"sensor_noise_std": -0.1}, "sensor_noise_std"),
        ({"sensor_delay": 2}, "sensor_delay"),
        ({"render_mode": "ascii"}, "rgb_array"),
        ({"contact_weight": float("inf")}, "contact_weight"),
    ],
)
@pytest.mark.filterwarnings("ignore:.*render_mode='ascii'")
def test_bad_overrides_raise_value_error(kwargs, match):
    with pytest.raises(ValueError, match=match):
        gym.make(ENV_ID, **kwargs)
    with pytest.raises(ValueError, match=match):
        HyperloopSuspensionVectorEnv(2, **kwargs)


def test_irregularity_error_lists_classes():
    with pytest.raises(ValueError) as exc:
        gym.make(ENV_ID, irregularity="bumpy")
    for name in IRREGULARITY_CLASSES:
        assert name in str(exc.value)


def test_random_scenario_draws_in_documented_ranges():
    env = HyperloopSuspensionEnv("random", track_length_m=20.0)
    env.reset(seed=0)
    speeds, radii, classes, masses = [], [], set(), []
    for _ in range(60):
        _, info = env.reset()
        p = env.params
        speeds.append(info["speed_kmh"])
        radii.append(info["curve_radius_m"])
        classes.add(p.irregularity.spectrum)
        masses.append(p.vehicle.capsule_mass_kg)
        assert info["speed_kmh"] == p.condition.speed_kmh
        assert env.nominal_current_A == pytest.approx(env.sim.nominal_current_A)
    lo, hi = RANDOM_SPEED_RANGE_KMH
    assert all(lo <= s <= hi for s in speeds) and np.ptp(speeds) > 300
    curved = [r for r in radii if math.isfinite(r)]
    assert 0 < len(curved) < len(radii)
    assert all(RANDOM_RADIUS_RANGE_M[0] <= r <= RANDOM_RADIUS_RANGE_M[1] for r in curved)
    assert classes == set(RANDOM_IRREGULARITY_CLASSES)
    assert all(13_500 <= m <= 16_500 for m in masses) and np.ptp(masses) > 1000
    # the nominal current follows the mass
    env.reset(seed=1)
    i0 = [env.nominal_current_A]
    for _ in range(5):
        env.reset()
        i0.append(env.nominal_current_A)
    assert np.ptp(i0) > 0.1


def test_random_scenario_reproducible_and_overridable():
    a, b = HyperloopSuspensionEnv("random"), HyperloopSuspensionEnv("random")
    a.reset(seed=9)
    b.reset(seed=9)
    assert a.params == b.params
    fixed = HyperloopSuspensionEnv("random", speed_kmh=1300.0, irregularity="none")
    for s in range(5):
        fixed.reset(seed=s)
        assert fixed.params.condition.speed_kmh == 1300.0
        assert fixed.params.irregularity.spectrum == "none"


@pytest.mark.parametrize(
    "make",
    [
        lambda **kw: gym.make(ENV_ID, **kw),
        lambda **kw: HyperloopSuspensionVectorEnv(2, **kw),
        lambda **kw: gym.make_vec(
            ENV_ID, num_envs=2, vectorization_mode="vector_entry_point", **kw
        ),
        lambda **kw: EnvConfig.from_kwargs(**kw),
    ],
)
def test_unknown_keyword_raises_type_error_listing_valid_names(make):
    """Python's convention, on which TorchRL's GymEnv relies (it passes ``frameskip=`` and
    retries without it when the message names it as an unexpected keyword argument)."""
    with pytest.raises(TypeError) as exc:
        make(frameskip=4)
    msg = str(exc.value)
    assert "unexpected keyword argument 'frameskip'" in msg
    for name in ("speed_kmh", "sensor_noise_std", "gap_weight", "disturbances", "actuators"):
        assert name in msg


def test_torchrl_style_retry_without_frameskip():
    try:
        env = gym.make(ENV_ID, frameskip=2)
    except TypeError as err:
        assert "unexpected keyword argument 'frameskip" in str(err)
        env = gym.make(ENV_ID)
    obs, _ = env.reset(seed=0)
    assert obs.shape == env.observation_space.shape


def test_config_and_keywords_build_the_same_env():
    cfg = EnvConfig(
        scenario="paper-2000-curved",
        sensors=SensorConfig(noise_std=0.01),
        reward=RewardWeights(gap=3.0),
    )
    a = gym.make(ENV_ID, config=cfg)
    b = gym.make(ENV_ID, scenario="paper-2000-curved", sensor_noise_std=0.01, gap_weight=3.0)
    assert a.unwrapped.env_config == b.unwrapped.env_config == cfg
    oa, _ = a.reset(seed=3)
    ob, _ = b.reset(seed=3)
    np.testing.assert_array_equal(oa, ob)
    act = np.full(4, 0.1, np.float32)
    np.testing.assert_array_equal(a.step(act)[0], b.step(act)[0])
    # keywords apply on top of a config; the config is frozen and round-trips
    c = gym.make(ENV_ID, config=cfg, speed_kmh=1500.0)
    assert c.unwrapped.params.condition.speed_kmh == 1500.0
    assert EnvConfig.from_kwargs(**cfg.to_kwargs()) == cfg
    with pytest.raises(AttributeError):
        cfg.speed_kmh = 1.0  # type: ignore[misc]
    v = HyperloopSuspensionVectorEnv(2, config=cfg)
    assert v.env_config == cfg


def test_resolved_config_is_what_evaluation_reads():
    r = EnvConfig(scenario="paper-2000-straight", track_length_m=1000.0).resolve()
    # 1000 m at 2000 km/h with 1 ms steps: ceil(1000 / (2000/3.6 * 1e-3)) = 1800
    assert r.episode_steps == 1800
    assert r.expected_steps(0.5) == 900
    assert r.control_dt_s == 1e-3
    assert r.observation.size == 23
