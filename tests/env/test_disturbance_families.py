"""Pier settlement, joint steps and sensor dropout: values against independent
expectations, validation, seeding, and end to end in both environments."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from hyperloop_env import ENV_ID
from hyperloop_env.disturbances import (
    DISTURBANCES,
    DropoutSchedule,
    JointSteps,
    PierSettlement,
    ProfileGrid,
    SensorDropout,
    make_disturbance,
    realise_episode,
)
from hyperloop_env.disturbances.sensor_dropout import dropout_intervals
from hyperloop_env.physics import ModelParams
from hyperloop_env.physics.units import UNIT_NAMES
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

P = ModelParams()
SPAN = P.guideway.span_m


def test_registry_has_the_new_families() -> None:
    assert {"pier_settlement", "joint_steps", "sensor_dropout"} <= set(DISTURBANCES)
    assert make_disturbance("pier_settlement", 0.003) == PierSettlement(severity=0.003)
    assert make_disturbance("joint_steps", 0.001) == JointSteps(severity=0.001)
    assert make_disturbance("sensor_dropout", 0.2, unit="RL") == SensorDropout(0.2, unit="RL")


@pytest.mark.parametrize(
    ("factory", "match"),
    [
        (lambda: PierSettlement(severity=-0.001), "PierSettlement.severity must be >= 0"),
        (lambda: PierSettlement(severity=math.inf), "PierSettlement.severity must be a finite"),
        (lambda: PierSettlement(lateral_fraction=-1), "PierSettlement.lateral_fraction"),
        (lambda: JointSteps(severity=0.5), "JointSteps.severity must be <= 0.02"),
        (lambda: JointSteps(ramp_m=-0.1), "JointSteps.ramp_m"),
        (lambda: SensorDropout(severity=1.0), "SensorDropout.severity must be < 1"),
        (lambda: SensorDropout(severity=-0.1), "SensorDropout.severity must be >= 0"),
        (lambda: SensorDropout(mean_duration_s=0.0), "SensorDropout.mean_duration_s must be > 0"),
        (lambda: SensorDropout(unit="XX"), "SensorDropout.unit must be 'any' or one of"),
    ],
)
def test_bad_values_raise_naming_the_field(factory, match) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match=match):
        factory()


def test_pier_settlement_is_linear_between_independently_drawn_piers() -> None:
    grid = ProfileGrid(n=3000, step_m=0.1)  # 300 m: 10 spans, piers on grid points
    d = PierSettlement(severity=0.003, lateral_fraction=0.5)
    off = d.realise(P, grid, np.random.default_rng(4)).profile_offset
    assert off is not None and off.shape == (3, grid.n)
    # the same draws, written out again: vertical first, then lateral, N(0, σ²) per pier
    rng = np.random.default_rng(4)
    n_piers = 11  # piers at 0, 30, …, 300 m: the first one past the grid's end (299.9 m)
    vert = rng.normal(size=n_piers) * 0.003
    lat = rng.normal(size=n_piers) * 0.0015
    x = grid.x_m
    for j in range(n_piers - 1):
        i0 = round(j * SPAN / 0.1)
        assert off[0, i0] == pytest.approx(vert[j], abs=1e-15)
        assert off[2, i0] == pytest.approx(lat[j], abs=1e-15)
        m = (x >= j * SPAN) & (x <= (j + 1) * SPAN)
        xi = (x[m] - j * SPAN) / SPAN
        np.testing.assert_allclose(off[0, m], vert[j] + xi * (vert[j + 1] - vert[j]), atol=1e-15)
        np.testing.assert_allclose(off[2, m], lat[j] + xi * (lat[j + 1] - lat[j]), atol=1e-15)
    np.testing.assert_array_equal(off[0], off[1])  # both rails follow the pier
    # kinks only at the piers: the second difference vanishes inside the spans
    d2 = np.abs(np.diff(off[0], 2))
    inner = np.ones(d2.size, bool)
    inner[np.round(np.arange(1, n_piers - 1) * SPAN / 0.1).astype(int) - 1] = False
    assert d2[inner].max() < 1e-15 and d2[~inner].max() > 1e-6


def test_pier_settlement_statistics_over_many_piers() -> None:
    grid = ProfileGrid(n=2**18, step_m=0.1)  # 26 km, 873 piers
    off = PierSettlement(severity=0.002).realise(P, grid, np.random.default_rng(0)).profile_offset
    assert off is not None
    idx = np.round(np.arange(0, grid.n * 0.1 / SPAN - 1) * SPAN / 0.1).astype(int)
    piers = off[0, idx]
    n = piers.size
    # σ of the piers and σ·√2 of adjacent differences, within 4 standard errors
    assert abs(piers.std() - 0.002) < 4 * 0.002 / math.sqrt(2 * n)
    assert abs(np.diff(piers).std() - 0.002 * math.sqrt(2)) < 5 * 0.002 * math.sqrt(2 / (2 * n))
    assert abs(off[2, idx].std() - 0.001) < 4 * 0.001 / math.sqrt(2 * n)
    assert abs(np.corrcoef(piers[:-1], piers[1:])[0, 1]) < 4 / math.sqrt(n)  # independent


def test_joint_steps_are_constant_per_span_and_ramped_like_a_moving_average() -> None:
    grid = ProfileGrid(n=3000, step_m=0.1)
    d = JointSteps(severity=0.0008)
    off = d.realise(P, grid, np.random.default_rng(2)).profile_offset
    assert off is not None
    rng = np.random.default_rng(2)
    c = rng.normal(size=11) * 0.0008  # spans 0 … 10 (one past the grid's end)
    x = grid.x_m
    a2 = P.magnet.pole_length_m
    # independent: the step function on a fine grid, averaged over the pole length
    fine = np.arange(-1.0, 302.0, 0.001)
    step_fn = c[np.clip(np.floor(fine / SPAN).astype(int), 0, None)]
    w = round(a2 / 0.001)
    avg = np.convolve(step_fn, np.ones(w) / w, mode="same")
    expect = np.interp(x, fine, avg)
    np.testing.assert_allclose(off[0, :2900], expect[:2900], atol=0.0008 * 1e-2)
    # span centres carry the span's constant exactly; the joint value is the mean of the two
    for j in range(9):
        assert off[0, round((j + 0.5) * SPAN / 0.1)] == pytest.approx(c[j], abs=1e-15)
        if j:
            mid = 0.5 * (c[j - 1] + c[j])
            assert off[0, round(j * SPAN / 0.1)] == pytest.approx(mid, abs=1e-15)
    # ramp_m = 0: the bare step
    bare = JointSteps(0.0008, ramp_m=0.0).realise(P, grid, np.random.default_rng(2)).profile_offset
    assert bare is not None
    np.testing.assert_array_equal(bare[0], c[np.floor(x / SPAN).astype(int)])
    with pytest.raises(ValueError, match="JointSteps.ramp_m must be <= 10.0"):
        JointSteps(0.001, ramp_m=SPAN)


def test_dropout_chain_has_the_stated_fraction_and_durations() -> None:
    d = SensorDropout(severity=0.1, mean_duration_s=0.02)
    q, r = d.step_probabilities(1e-3)
    assert q == pytest.approx(0.05) and r == pytest.approx(0.05 * 0.1 / 0.9)
    n = 3_000_000
    starts, ends = dropout_intervals(n, 0.1, q, np.random.default_rng(0))
    sched = DropoutSchedule(0, (0, 4), starts, ends)
    held = sched.held(n)
    k = starts.size  # ~ n·p·q = 15 000 dropouts
    assert abs(held.mean() - 0.1) < 4 * 0.1 * math.sqrt(2 / k)
    dur = (np.minimum(ends, n) - starts)[:-1]
    assert abs(dur.mean() - 20.0) < 4 * 20.0 / math.sqrt(k)  # geometric, mean 1/q
    up = starts[1:] - ends[:-1]
    assert abs(up.mean() - 180.0) < 4 * 180.0 / math.sqrt(k)  # mean (1-p)/(p q)
    assert starts[0] >= 1 and not held[0]  # the reset observation is live
    # the lookup agrees with the mask
    probe = np.random.default_rng(1).integers(0, n, 2000)
    assert [sched.active(int(i)) for i in probe] == held[probe].tolist()
    with pytest.raises(ValueError, match="raise mean_duration_s"):
        SensorDropout(severity=0.99, mean_duration_s=1e-3).step_probabilities(1e-3)


def _run_single(kw: dict, seed: int, actions: np.ndarray):  # type: ignore[no-untyped-def]
    env = gym.make(ENV_ID, **kw)
    obs, info = env.reset(seed=seed)
    out = [(obs, info["gap_excursion_m"])]
    for a in actions:
        obs, _, te, tr, info = env.step(a)
        out.append((obs, info["gap_excursion_m"]))
        if te or tr:
            break
    return env, out


def test_sensor_dropout_holds_one_units_gap_and_rate_in_the_env() -> None:
    kw = {
        "scenario": "paper-1000-straight",
        "track_length_m": 300.0,
        "disturbances": {"sensor_dropout": {"severity": 0.3, "unit": "RL"}},
    }
    acts = np.random.default_rng(0).uniform(-0.2, 0.2, (1100, 4)).astype(np.float32)
    env, out = _run_single(kw, 3, acts)
    sched = env.unwrapped.sensors._hooks[0]
    assert isinstance(sched, DropoutSchedule) and sched.unit == UNIT_NAMES.index("RL")
    spec = env.unwrapped.observation_spec
    g, r = spec.start("gap") + 2, spec.start("gap_rate") + 2
    # the hook sees SensorModel's step counter: steps completed before the observation's
    # step (the reset observation and the first step's are both step 0)
    held = sched.held(len(out))[np.maximum(np.arange(len(out)) - 1, 0)]
    assert 0.15 < held.mean() < 0.45 and not held[0] and not held[1]
    om = env.unwrapped.params.magnet.clearance_m
    obs = np.array([o for o, _ in out])
    true = np.array([t for _, t in out])
    for k in range(1, len(out)):
        if held[k]:  # frozen: the last delivered value, gap and rate
            assert obs[k, g] == obs[k - 1, g] and obs[k, r] == obs[k - 1, r]
        else:
            assert obs[k, g] == np.float32(true[k, 2] / om)
    # every other unit is live throughout
    np.testing.assert_array_equal(obs[:, 0], (true[:, 0] / om).astype(np.float32))
    # without the disturbance: no hook at all (existing trajectories untouched)
    plain = gym.make(ENV_ID, scenario="paper-1000-straight", track_length_m=300.0)
    plain.reset(seed=3)
    assert plain.unwrapped.sensors.dropout is None


def test_disturbed_single_and_vector_envs_are_bit_identical() -> None:
    dist = {
        "sensor_dropout": {"severity": 0.2, "mean_duration_s": 0.005},
        "pier_settlement": 0.001,
        "joint_steps": 0.0002,
    }
    kw = {"scenario": "paper-1000-straight", "track_length_m": 200.0, "disturbances": dist}
    acts = np.random.default_rng(5).uniform(-0.05, 0.05, (800, 3, 4)).astype(np.float32)
    venv = HyperloopSuspensionVectorEnv(3, **kw)
    vobs, _ = venv.reset(seed=[11, 12, 13])
    singles = [_run_single(kw, s, acts[:, i])[1] for i, s in enumerate((11, 12, 13))]
    n = len(singles[0])
    assert [len(o) for o in singles] == [n] * 3  # all truncated at the end of the section
    for k in range(1, n):
        vobs, *_ = venv.step(acts[k - 1])
        for i in range(3):
            np.testing.assert_array_equal(vobs[i], singles[i][k][0])
    # an autoreset row draws its next episode's schedule as a fresh single env would
    vobs, *_ = venv.step(acts[0])
    env2 = gym.make(ENV_ID, **kw)
    env2.reset(seed=11)
    for k in range(n - 1):
        env2.step(acts[k, 0])
    o2, _ = env2.reset()
    np.testing.assert_array_equal(vobs[0], o2)


def test_passive_vehicle_does_not_feel_the_dropout_but_feels_the_profile() -> None:
    base = {"scenario": "paper-1000-straight", "track_length_m": 250.0, "irregularity": "none"}
    zero = np.zeros((1000, 4), np.float32)
    _, ref = _run_single(base, 1, zero)
    _, drop = _run_single({**base, "disturbances": {"sensor_dropout": 0.4}}, 1, zero)
    np.testing.assert_array_equal(np.array([t for _, t in ref]), np.array([t for _, t in drop]))
    for name, sev in (("pier_settlement", 0.003), ("joint_steps", 0.001)):
        _, dist = _run_single({**base, "disturbances": {name: sev}}, 1, zero)
        g_ref = np.array([t for _, t in ref])[:, 0]
        g_d = np.array([t for _, t in dist])[:, 0]
        assert np.std(g_d - g_ref) > 2e-5, name


def test_realise_episode_combines_profile_and_sensor_parts() -> None:
    grid = ProfileGrid(n=4096, step_m=0.1)
    ds = (PierSettlement(0.002), JointSteps(0.0005), SensorDropout(0.1))
    r = realise_episode(ds, P, grid, seed=9)
    a = PierSettlement(0.002).realise(P, grid, np.random.default_rng([9, 1])).profile_offset
    b = JointSteps(0.0005).realise(P, grid, np.random.default_rng([9, 2])).profile_offset
    assert r.profile_offset is not None and a is not None and b is not None
    np.testing.assert_array_equal(r.profile_offset, a + b)
    assert isinstance(r.sensor_hook, DropoutSchedule)
    assert r.params == P
