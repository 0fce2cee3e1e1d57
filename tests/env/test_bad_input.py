"""Hostile but fair input to the environment: odd numbers get a ValueError that names the
argument the user gave (never ZeroDivisionError, OverflowError, MemoryError or a message
about a physics field the user never set), and NumPy scalars are numbers."""

from __future__ import annotations

import json
import math
import time

import gymnasium as gym
import numpy as np
import pytest

import hyperloop_env  # noqa: F401 - registers the env
from hyperloop_env import config, kernels
from hyperloop_env.config import (
    KEYWORDS,
    MAX_PROFILE_BYTES,
    MAX_REWARD_WEIGHT,
    MAX_SENSOR_NOISE_STD,
    MIN_CONTROL_DT_S,
    MIN_SPEED_KMH,
    REWARD_KEYWORDS,
    EnvConfig,
)
from hyperloop_env.physics.irregularity import N_ROWS
from hyperloop_env.physics.model import profile_grid
from hyperloop_env.physics.params import ModelParams
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

SUBNORMAL = 5e-324


def _all_ways(**kw: object) -> list[object]:
    """Build the config the three ways a user can (each must raise)."""
    return [
        lambda: EnvConfig.from_kwargs(scenario="paper-1000-straight", **kw),
        lambda: gym.make("HyperloopSuspension-v0", scenario="paper-1000-straight", **kw),
        lambda: HyperloopSuspensionVectorEnv(2, "paper-1000-straight", **kw),
    ]


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"speed_kmh": SUBNORMAL}, "speed_kmh must be >= 1.0 km/h"),
        ({"speed_kmh": 1e-300}, "speed_kmh must be >= 1.0 km/h"),
        ({"control_dt_s": SUBNORMAL}, "control_dt_s must be >= 1e-06 s"),
        ({"control_dt_s": 1e-300}, "control_dt_s must be >= 1e-06 s"),
        ({"speed_kmh": "fast"}, "speed_kmh must be a number"),
        ({"track_length_m": math.inf}, "track_length_m must be finite"),
        ({"curve_radius_m": -math.inf}, "curve_radius_m must be > 0"),
    ],
)
def test_degenerate_numbers_raise_value_error_naming_the_argument(
    kw: dict[str, object], message: str
) -> None:
    for build in _all_ways(**kw):
        with pytest.raises(ValueError, match=message):
            build()


def test_lower_bounds_are_accepted() -> None:
    cfg = EnvConfig(speed_kmh=MIN_SPEED_KMH, control_dt_s=MIN_CONTROL_DT_S, track_length_m=1.0)
    assert cfg.resolve().episode_steps >= 1


def test_too_fast_names_speed_and_control_interval() -> None:
    with pytest.raises(ValueError) as exc:
        gym.make("HyperloopSuspension-v0", speed_kmh=1e9)
    msg = str(exc.value)
    assert msg.startswith("speed_kmh=1000000000.0 is too fast for the default control_dt_s=0.001")
    assert "one RK4 substep travels 1.389e+05 m" in msg and "lower speed_kmh or control_dt_s" in msg
    assert "GuidewayParams" not in msg
    v_max = float(msg.split("at most ")[1].split(" km/h")[0])
    EnvConfig(speed_kmh=v_max * 0.999)  # the stated limit is the limit
    with pytest.raises(ValueError, match="too fast"):
        EnvConfig(speed_kmh=v_max * 1.001)
    with pytest.raises(ValueError, match="speed_kmh=300000.0 is too fast for control_dt_s=0.0015"):
        EnvConfig(speed_kmh=3e5, control_dt_s=0.0015)


def test_too_long_control_interval_names_control_dt() -> None:
    for build in _all_ways(control_dt_s=0.008):
        with pytest.raises(ValueError) as exc:
            build()
        msg = str(exc.value)
        assert msg.startswith("control_dt_s=0.008 is too long for the guideway's highest mode")
        assert "substeps >=" not in msg and "SimulationParams" not in msg
    dt_max = float(msg.split("at most ")[1].split(" s")[0])
    EnvConfig(control_dt_s=dt_max * 0.999)
    with pytest.raises(ValueError, match="control_dt_s"):
        EnvConfig(control_dt_s=0.03)  # beyond the physics' own 0.02 s cap: same message
    with pytest.raises(ValueError, match="^control_dt_s=0.005 is too long"):
        EnvConfig(scenario="random", control_dt_s=0.005)


def test_track_beyond_the_memory_budget_is_refused_at_once() -> None:
    t0 = time.perf_counter()
    for length in (1e7, 1e9):
        with pytest.raises(ValueError, match="MAX_PROFILE_BYTES"):
            EnvConfig(track_length_m=length)  # first: a regression must not allocate GBs
        with pytest.raises(ValueError, match="MAX_PROFILE_BYTES") as exc:
            gym.make("HyperloopSuspension-v0", track_length_m=length)
        assert f"track_length_m={length!r} is too long" in str(exc.value)
    assert time.perf_counter() - t0 < 1.0
    longest = float(str(exc.value).split("at most ")[1].split(" m")[0])
    ok = EnvConfig(track_length_m=longest)  # the stated maximum fits the budget
    n, _ = profile_grid(ok.resolve().base)
    assert N_ROWS * n * 8 <= MAX_PROFILE_BYTES
    with pytest.raises(ValueError, match="MAX_PROFILE_BYTES"):
        EnvConfig(track_length_m=longest + 1.0)
    with pytest.raises(ValueError, match="MAX_PROFILE_BYTES"):
        HyperloopSuspensionVectorEnv(4, track_length_m=1e7)


def test_sensor_noise_is_bounded_and_observations_stay_in_the_space() -> None:
    with pytest.raises(ValueError, match="sensor_noise_std must be <= 10"):
        gym.make("HyperloopSuspension-v0", sensor_noise_std=1e39)
    env = gym.make(
        "HyperloopSuspension-v0",
        scenario="paper-1000-straight",
        track_length_m=50.0,
        sensor_noise_std=MAX_SENSOR_NOISE_STD,
    )
    obs, _ = env.reset(seed=0)
    for _ in range(50):
        assert np.all(np.isfinite(obs)) and env.observation_space.contains(obs)
        obs, *_ = env.step(np.zeros(4, dtype=np.float32))


NUMPY_KWARGS = {
    "speed_kmh": np.float32(1500.0),
    "curve_radius_m": np.int64(300_000),
    "cant_deg": np.float32(1.0),
    "track_length_m": np.int64(60),
    "control_dt_s": np.float32(0.001),
    "clearance_m": np.float64(0.0079),
    "coil_time_constant_s": np.float32(0.002),
    "action_scale": np.float32(0.5),
    "sensor_noise_std": np.float32(0.01),
    "sensor_delay": np.int64(1),
    "gap_weight": np.float32(3.0),
    "contact_weight": np.int64(50),
}


def test_numpy_scalars_are_numbers_everywhere() -> None:
    cfg = EnvConfig.from_kwargs(scenario="paper-1000-curved", **NUMPY_KWARGS)
    kw = cfg.to_kwargs()
    for k in NUMPY_KWARGS:
        assert type(kw[k]) in (float, int), (k, type(kw[k]))
    json.dumps(kw)  # a run's configuration can be stored
    assert cfg == EnvConfig.from_kwargs(**kw)
    for env in (
        gym.make("HyperloopSuspension-v0", scenario="paper-1000-curved", **NUMPY_KWARGS),
        HyperloopSuspensionVectorEnv(np.int64(2), "paper-1000-curved", **NUMPY_KWARGS),
    ):
        env.reset(seed=0)
        a = np.zeros(env.action_space.shape, dtype=np.float32)
        _, reward, *_ = env.step(a)
        assert np.all(np.isfinite(reward))
        env.close()


@pytest.mark.parametrize(
    ("seed", "what"),
    [
        ("x", "got str 'x'"),
        (b"x", "got bytes"),
        (1.5, "got float 1.5"),
        (-1, "negative int -1"),
        ([0, "y"], "entry str 'y'"),
        ([0, -3], "negative entry -3"),
        ([0, 1, 2], "sequence of length 3"),
    ],
)
def test_vector_reset_seed_says_what_a_seed_must_be(seed: object, what: str) -> None:
    env = HyperloopSuspensionVectorEnv(2, "paper-1000-straight", track_length_m=50.0)
    with pytest.raises(ValueError) as exc:
        env.reset(seed=seed)
    msg = str(exc.value)
    assert msg.startswith("seed must be None, an int >= 0 or a list of num_envs=2 ints >= 0")
    assert what in msg
    env.reset(seed=np.int64(3))
    env.reset(seed=[np.int64(1), None])
    env.close()


def test_numpy_integer_seed_is_an_int() -> None:
    import gymnasium as gym

    env = gym.make("HyperloopSuspension-v0")
    a, _ = env.reset(seed=np.int64(3))
    b, _ = env.reset(seed=3)
    np.testing.assert_array_equal(a, b)


NUMERIC_KEYWORDS = [n for n, d in KEYWORDS.items() if d.keyword.bounds is not None]


@pytest.mark.parametrize("name", NUMERIC_KEYWORDS)
@pytest.mark.parametrize("value", [1e200, 1e308, -1e308])
def test_huge_numbers_build_or_raise_value_error_naming_the_keyword(
    name: str, value: float
) -> None:
    """Every numeric keyword at a huge magnitude either builds a configuration or raises a
    ValueError naming the keyword (never OverflowError)."""
    try:
        EnvConfig.from_kwargs(**{name: value})
    except ValueError as exc:
        assert name in str(exc), str(exc)


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"speed_kmh": 1e200}, r"^speed_kmh=1e\+200 is too fast"),
        ({"track_length_m": 1e308}, r"^track_length_m=1e\+308 is too long.*MAX_PROFILE_BYTES"),
        ({"gap_weight": 1e308}, r"^gap_weight must be <= 1e\+12 \(MAX_REWARD_WEIGHT"),
        ({"contact_weight": 2 * MAX_REWARD_WEIGHT}, r"^contact_weight must be <= 1e\+12"),
    ],
)
def test_overflowing_numbers_raise_value_error_naming_the_argument(
    kw: dict[str, object], message: str
) -> None:
    for build in _all_ways(**kw):
        with pytest.raises(ValueError, match=message):
            build()


def test_an_arithmetic_error_in_the_model_names_the_numbers_given(monkeypatch) -> None:
    """The last line of defence: an OverflowError or ZeroDivisionError while building the
    model becomes a ValueError naming the numeric keywords the configuration sets."""

    pack = config.pack

    def overflow(params: ModelParams) -> object:
        if params.condition.speed_kmh == 1200.0:  # not the defaults from_kwargs starts from
            raise OverflowError("math range error")
        return pack(params)

    monkeypatch.setattr(config, "pack", overflow)
    with pytest.raises(ValueError) as exc:
        EnvConfig.from_kwargs(speed_kmh=1200.0, gap_weight=2.0, scenario="paper-1000-straight")
    msg = str(exc.value)
    assert "speed_kmh=1200.0" in msg and "gap_weight=2.0" in msg
    assert "OverflowError: math range error" in msg and "scenario" not in msg


def test_the_largest_reward_weights_keep_every_reward_finite_in_float32() -> None:
    """MAX_REWARD_WEIGHT on every term: the reward of the worst possible step (a diverged
    record: every term at its cap) and of a real contact step is finite even as float32."""
    weights = {k: MAX_REWARD_WEIGHT for k in REWARD_KEYWORDS.values()}
    env = HyperloopSuspensionVectorEnv(2, "paper-1000-straight", track_length_m=50.0, **weights)
    env.reset(seed=0)
    rec = np.full_like(env.sim.MEAS, 1e300)
    rec[:, 1::2] = np.nan  # NaN and huge entries: every term takes its cap
    terms, out = np.zeros_like(env._terms), np.zeros(2)
    mode = np.full(2, kernels.MODE_STEP, dtype=np.int8)
    kernels.reward(rec, env.sim.P, mode, env._weights, terms, out)
    assert np.all(np.isfinite(out.astype(np.float32))) and np.all(out < -1e20)
    a = np.full((2, 4), -1.0, np.float32)  # into contact
    for _ in range(200):
        _, reward, terminated, _, _ = env.step(a)
        assert np.all(np.isfinite(reward.astype(np.float32)))
        if terminated.any():
            break
    assert terminated.any()


@pytest.mark.parametrize("seed", [np.array(5), np.array(5, dtype=np.int32)])
def test_a_0d_integer_array_is_an_int_seed(seed: np.ndarray) -> None:
    env = HyperloopSuspensionVectorEnv(2, "paper-1000-straight", track_length_m=50.0)
    a, _ = env.reset(seed=seed)
    b, _ = env.reset(seed=5)
    np.testing.assert_array_equal(a, b)
    single = gym.make("HyperloopSuspension-v0", scenario="paper-1000-straight")
    np.testing.assert_array_equal(single.reset(seed=seed)[0], single.reset(seed=5)[0])


@pytest.mark.parametrize(
    ("seed", "what"),
    [(np.array(5.0), "got float64"), (np.array(True), "got bool"), (np.array(-2), "negative")],
)
def test_a_0d_array_that_is_no_int_seed_names_seed(seed: np.ndarray, what: str) -> None:
    env = HyperloopSuspensionVectorEnv(2, "paper-1000-straight", track_length_m=50.0)
    with pytest.raises(ValueError, match=f"^seed must be None, an int >= 0.*{what}"):
        env.reset(seed=seed)
