"""Tests of the native batched environment (vector_entry_point)."""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import hyperloop_env  # noqa: F401  (registration)
from hyperloop_env import vector_env
from hyperloop_env.env import HyperloopSuspensionEnv
from hyperloop_env.observation import OBS_SIZE
from hyperloop_env.reward import REWARD_TERMS
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

ENV_ID = "HyperloopSuspension-v0"
KEYS = [
    "position_m",
    "time_s",
    "gap_excursion_m",
    "lateral_offset_m",
    "current_A",
    "acceleration_m_s2",
    "contact",
    "speed_kmh",
    "curve_radius_m",
    "state",
]


def make_vec(n, **kwargs):
    return gym.make_vec(ENV_ID, num_envs=n, vectorization_mode="vector_entry_point", **kwargs)


def test_spaces_and_metadata():
    envs = make_vec(5)
    assert envs.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    # as on Gymnasium's own vector envs (TorchRL reads the attribute)
    assert envs.autoreset_mode == AutoresetMode.NEXT_STEP
    assert gym.vector.SyncVectorEnv([lambda: gym.make("CartPole-v1")]).autoreset_mode == (
        AutoresetMode.NEXT_STEP
    )
    assert envs.single_action_space == gym.spaces.Box(-1, 1, (4,), np.float32)
    assert envs.single_observation_space.shape == (OBS_SIZE,)
    assert envs.action_space.shape == (5, 4) and envs.observation_space.shape == (5, OBS_SIZE)
    obs, info = envs.reset(seed=0)
    assert obs.shape == (5, OBS_SIZE) and obs.dtype == np.float32
    assert obs in envs.observation_space
    obs, rew, te, tr, info = envs.step(envs.action_space.sample())
    assert rew.shape == (5,) and te.dtype == np.bool_ and tr.dtype == np.bool_
    for k in KEYS:
        assert len(info[k]) == 5 and info["_" + k].all()
    assert info["gap_excursion_m"].shape == (5, 4)
    assert info["acceleration_m_s2"].shape == (5, 2)
    for t in REWARD_TERMS:
        assert info["reward_terms"][t].shape == (5,)
    total = sum(info["reward_terms"][t] for t in REWARD_TERMS)
    np.testing.assert_allclose(total, rew, atol=1e-12)
    assert envs.nominal_current_A.shape == (5,)
    assert envs.action_to_current(np.zeros((5, 4))).shape == (5, 4)
    envs.close()


@pytest.mark.parametrize(
    "kwargs",
    [
        {"scenario": "random", "track_length_m": 40.0, "sensor_noise_std": 0.01},
        {"scenario": "paper-2000-curved", "track_length_m": 60.0, "sensor_delay": 1},
        {"scenario": "paper-1000-straight", "magnet": "attracting", "track_length_m": 300.0},
    ],
)
@pytest.mark.parametrize("parallel", [False, True])
def test_matches_single_envs_step_for_step(kwargs, parallel, monkeypatch):
    # parallel: step through BatchSimulator.step (threads) even for a small batch
    monkeypatch.setattr(vector_env, "PARALLEL_MIN_ENVS", 1 if parallel else 10**9)
    n, seed = 4, 100
    envs = make_vec(n, **kwargs)
    singles = [HyperloopSuspensionEnv(**kwargs) for _ in range(n)]
    obs_v, info_v = envs.reset(seed=seed)
    for i, env in enumerate(singles):
        obs, info = env.reset(seed=seed + i)
        assert np.array_equal(obs, obs_v[i])
    rng = np.random.default_rng(1)
    done = [False] * n
    resets = 0
    for _ in range(600):
        actions = rng.uniform(-1, 1, (n, 4)).astype(np.float32) * 0.3
        obs_v, rew_v, te_v, tr_v, info_v = envs.step(actions)
        for i, env in enumerate(singles):
            if done[i]:  # NEXT_STEP autoreset: this step resets env i
                obs, info = env.reset()
                rew, te, tr = 0.0, False, False
                resets += 1
                assert info_v["reward_terms"]["survival"][i] == 0.0
            else:
                obs, rew, te, tr, info = env.step(actions[i])
            done[i] = te or tr
            assert np.array_equal(obs, obs_v[i])
            assert rew == rew_v[i] and te == te_v[i] and tr == tr_v[i]
            for k in KEYS:
                assert np.array_equal(info[k], info_v[k][i]), k
            for t in REWARD_TERMS:
                assert info["reward_terms"][t] == info_v["reward_terms"][t][i]
    assert resets >= n  # every env went through at least one autoreset
    envs.close()


def test_autoreset_next_step_semantics():
    envs = make_vec(2, track_length_m=3.0)  # 11 steps at 1000 km/h
    envs.reset(seed=0)
    a = np.zeros((2, 4), np.float32)
    for _ in range(10):
        _, _, te, tr, _ = envs.step(a)
        assert not (te.any() or tr.any())
    _, _, te, tr, info = envs.step(a)
    assert tr.all() and not te.any()
    obs, rew, te, tr, info = envs.step(a)
    assert np.all(rew == 0.0) and not (te.any() or tr.any())
    assert np.all(info["time_s"] == 0.0) and np.all(obs[:, 4:8] == 0.0)


def test_bad_actions_raise():
    envs = make_vec(3)
    with pytest.raises(RuntimeError, match="reset"):
        envs.step(np.zeros((3, 4)))
    envs.reset(seed=0)
    for bad in (np.zeros((3, 3)), np.zeros(4), np.full((3, 4), np.nan)):
        with pytest.raises(ValueError, match="action"):
            envs.step(bad)


def test_sync_vectorization_also_works():
    envs = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="sync")
    envs.reset(seed=0)
    obs, *_ = envs.step(np.zeros((2, 4), np.float32))
    assert obs.shape == (2, OBS_SIZE)
    envs.close()


def test_pickle_and_render():
    envs = HyperloopSuspensionVectorEnv(2, render_mode="rgb_array")
    envs.reset(seed=0)
    frames = envs.render()
    assert len(frames) == 2 and frames[0].shape[2] == 3 and frames[0].dtype == np.uint8
    clone = pickle.loads(pickle.dumps(envs))
    a = np.full((2, 4), 0.1, np.float32)
    assert np.array_equal(envs.step(a)[0], clone.step(a)[0])


def test_reset_mask_resets_only_masked_envs():
    env = HyperloopSuspensionVectorEnv(num_envs=3, track_length_m=300.0)
    env.reset(seed=5)
    for _ in range(20):
        obs, *_ = env.step(np.full((3, 4), 0.3, dtype=np.float32))
    mask = np.array([False, True, False])
    obs2, _ = env.reset(options={"reset_mask": mask})
    assert np.array_equal(obs2[[0, 2]], obs[[0, 2]])
    fresh, _ = HyperloopSuspensionVectorEnv(num_envs=3, track_length_m=300.0).reset(seed=5)
    assert not np.array_equal(obs2[1], obs[1])
    assert np.all(obs2[1, 4:8] == 0.0)  # gap rate is zero right after a reset
    assert np.array_equal(obs2[1, 18:], fresh[1, 18:])
    with pytest.raises(ValueError, match="reset_mask"):
        env.reset(options={"reset_mask": np.array([1, 0, 1])})
    env.close()


def assert_identical(got, want, path="info"):
    """``got`` is ``want`` bit for bit: the same keys (nested dicts recursively), each array
    of the same type, shape and dtype with the same bytes; an object array (``final_obs``)
    entry by entry (None where ``want`` has None)."""
    if isinstance(want, dict):
        assert isinstance(got, dict), path
        assert set(got) == set(want), (path, set(got) ^ set(want))
        for k in want:
            assert_identical(got[k], want[k], f"{path}[{k!r}]")
        return
    if want is None:
        assert got is None, path
        return
    assert type(got) is type(want), (path, type(got), type(want))
    if not isinstance(want, np.ndarray):
        assert got == want, path
        return
    assert got.shape == want.shape and got.dtype == want.dtype, (
        path,
        (got.shape, got.dtype),
        (want.shape, want.dtype),
    )
    if want.dtype == object:
        for i, (g, w) in enumerate(zip(got, want, strict=True)):
            assert_identical(g, w, f"{path}[{i}]")
    else:
        assert got.tobytes() == want.tobytes(), path


def test_assert_identical_sees_shape_dtype_and_container():
    row = np.arange(3, dtype=np.float32)
    ragged = np.empty(2, dtype=object)
    ragged[0], ragged[1] = row, None
    assert_identical(ragged, ragged.copy())
    broadcast = np.array([row, row], dtype=object)  # (2, 3) of Python floats
    both = np.empty(2, dtype=object)
    both[0], both[1] = row, row.copy()
    for got, want in [
        (broadcast, both),
        (row.astype(np.float64), row),
        (row[None], row),
        ({"a": row}, {"a": row, "_a": row}),
        (np.zeros(3), -np.zeros(3)),
    ]:
        with pytest.raises(AssertionError):
            assert_identical(got, want)


@pytest.mark.parametrize("mode", list(AutoresetMode))
def test_autoreset_modes_match_sync_vector_env(mode):
    """Each autoreset mode is bit-identical to Gymnasium's SyncVectorEnv of single envs in
    the same mode, over several autoresets (DISABLED: the caller resets the ended envs):
    observations, rewards, flags and the whole info dict, SAME_STEP's ``final_obs``
    (an (n,) object array of float32 rows, None where not done) and ``final_info`` (values
    of the ended envs only, masked) included. The first episodes all end on the same step
    (the end of the track); later environment 0 is driven into contact, so that only
    some end on a step."""
    kw = {"scenario": "paper-2000-straight", "track_length_m": 40.0, "sensor_noise_std": 0.01}
    n = 3
    native = make_vec(n, autoreset_mode=mode, **kw)
    sync = gym.vector.SyncVectorEnv(
        [lambda: HyperloopSuspensionEnv(**kw) for _ in range(n)], autoreset_mode=mode
    )
    assert native.metadata["autoreset_mode"] == mode == native.autoreset_mode
    obs_n, info_n = native.reset(seed=7)
    obs_s, info_s = sync.reset(seed=7)
    assert_identical(obs_n, obs_s, "obs")
    assert_identical(info_n, info_s)
    rng = np.random.default_rng(3)
    ends = {"all": 0, "some": 0}
    for t in range(200):
        a = (rng.uniform(-1, 1, (n, 4)) * 0.3).astype(np.float32)
        if t >= 80:
            a[0] = -1.0  # into contact: environment 0 ends before the others
        out_n = native.step(a)
        out_s = sync.step(a)
        names = ("obs", "reward", "terminated", "truncated", f"info of step {t}")
        for name, x, y in zip(names, out_n, out_s, strict=True):
            assert_identical(x, y, name)
        done = out_n[2] | out_n[3]
        if mode == AutoresetMode.SAME_STEP and done.any():
            assert set(out_n[4]) >= {"final_obs", "_final_obs", "final_info", "_final_info"}
        if mode == AutoresetMode.DISABLED and done.any():
            with pytest.raises(RuntimeError, match="reset_mask"):
                native.step(a)
            on, i_n = native.reset(options={"reset_mask": done})
            os_, i_s = sync.reset(options={"reset_mask": done})
            assert_identical(on, os_, "obs")
            assert_identical(i_n, i_s)
        if done.all():
            ends["all"] += 1
        elif done.any():
            ends["some"] += 1
    assert ends["all"] >= 1 and ends["some"] >= 1, ends
    with pytest.raises(ValueError, match="autoreset_mode"):
        make_vec(2, autoreset_mode="sometimes")


def test_per_env_disturbances_match_single_envs():
    """reset(options={"disturbances": [...]}) gives env i the episode of a single env made
    with those disturbances; None keeps the configured ones."""
    kw = {"scenario": "paper-1000-straight", "track_length_m": 200.0}
    dist = [{"roughness": 0.3}, None, {"pier_settlement": 0.002, "roughness": 0.5}]
    env = HyperloopSuspensionVectorEnv(3, autoreset_mode="Disabled", **kw)
    obs_v, _ = env.reset(seed=[11, 12, 13], options={"disturbances": dist})
    a = np.full((3, 4), 0.1, np.float32)
    for i, d in enumerate(dist):
        single = HyperloopSuspensionEnv(**kw, **({"disturbances": d} if d else {}))
        assert np.array_equal(single.reset(seed=11 + i)[0], obs_v[i])
        assert np.array_equal(single.unwrapped.sim.irr, env.sim.IRR[i])
    o1 = env.step(a)[0]
    # the rows differ only by their disturbances: same seed, other severity -> other track
    env2 = HyperloopSuspensionVectorEnv(3, autoreset_mode="Disabled", **kw)
    env2.reset(seed=[11, 12, 13])
    assert not np.array_equal(env2.step(a)[0][0], o1[0])
    with pytest.raises(ValueError, match=r"options\['disturbances'\]\[1\]"):
        env.reset(seed=1, options={"disturbances": [None, {"roughness": -1.0}, None]})
    with pytest.raises(ValueError, match="num_envs=3"):
        env.reset(seed=1, options={"disturbances": [None]})


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
def test_info_off_and_parallel_choice_change_no_value(mode):
    """``info=False`` returns empty info dicts (SAME_STEP: still the final observations) and
    ``parallel`` only chooses the threads: observations, rewards and episode ends are the
    default env's, bit for bit, over autoresets."""
    kw = {"scenario": "paper-2000-straight", "track_length_m": 40.0, "sensor_noise_std": 0.01}
    n = 3
    ref = make_vec(n, autoreset_mode=mode, **kw)
    others = [make_vec(n, autoreset_mode=mode, info=False, parallel=p, **kw) for p in (False, True)]
    assert [e.unwrapped.parallel for e in others] == [False, True] and not ref.unwrapped.parallel
    obs, info = ref.reset(seed=5)
    for e in others:
        o, i = e.reset(seed=5)
        assert np.array_equal(o, obs) and i == {}
    rng = np.random.default_rng(2)
    ended = 0
    for _ in range(150):
        a = (rng.uniform(-1, 1, (n, 4)) * 0.3).astype(np.float32)
        out = ref.step(a)
        done = out[2] | out[3]
        ended += int(done.sum())
        for e in others:
            got = e.step(a.astype(np.float64))
            for x, y in zip(out[:4], got[:4], strict=True):
                assert np.array_equal(x, y)
            if mode == AutoresetMode.SAME_STEP and done.any():
                assert set(got[4]) == {"final_obs", "_final_obs", "final_info", "_final_info"}
                for i in np.flatnonzero(done):
                    assert np.array_equal(got[4]["final_obs"][i], out[4]["final_obs"][i])
            else:
                assert got[4] == {}
    assert ended >= n
    with pytest.raises(ValueError, match="parallel"):
        make_vec(2, parallel="yes")


def test_flat_info_has_one_entry_per_reward_term():
    """info="flat": no nested dict (TorchRL stacks info arrays); the same values as the
    nested reward_terms, in the single and the vector env."""
    kw = {"scenario": "paper-1000-straight", "track_length_m": 50.0}
    nested = make_vec(2, **kw)
    flat = make_vec(2, info="flat", **kw)
    nested.reset(seed=3)
    flat.reset(seed=3)
    a = np.full((2, 4), 0.2, np.float32)
    _, _, _, _, i_n = nested.step(a)
    _, _, _, _, i_f = flat.step(a)
    assert "reward_terms" not in i_f
    assert not any(isinstance(v, dict) for v in i_f.values())
    for t in REWARD_TERMS:
        assert np.array_equal(i_f["reward_" + t], i_n["reward_terms"][t])
        assert i_f["_reward_" + t].all()
    single = gym.make(ENV_ID, info="flat", **kw)
    single.reset(seed=3)
    *_, info = single.step(a[0])
    assert not any(isinstance(v, dict) for v in info.values())
    assert info["reward_survival"] == i_n["reward_terms"]["survival"][0]
    with pytest.raises(ValueError, match="info must be"):
        gym.make(ENV_ID, info="deep")


def test_held_rows_keep_their_state_and_the_others_fly_as_without_the_hold():
    a, b = make_vec(3, autoreset_mode="Disabled"), make_vec(3, autoreset_mode="Disabled")
    a.reset(seed=4)
    b.reset(seed=4)
    held = np.array([False, True, False])
    b.hold(held)
    y1 = b.sim.Y[1].copy()
    act = np.full((3, a.action_space.shape[1]), 0.2, dtype=np.float32)
    for _ in range(30):
        oa, *_ = a.step(act)
        ob, *_ = b.step(act)
    np.testing.assert_array_equal(oa[~held], ob[~held])
    np.testing.assert_array_equal(b.sim.Y[1], y1)
    assert not np.array_equal(a.sim.Y[1], y1)
    b.hold(None)
    b.step(act)
    assert not np.array_equal(b.sim.Y[1], y1)
    with pytest.raises(ValueError, match=r"hold: mask must be a bool array of shape \(3,\)"):
        b.hold(np.array([1, 0, 0]))


def test_actions_in_any_layout_and_float_dtype_fly_the_same():
    """Actions strided, in Fortran order, in float64 (the same values) and C-ordered float32,
    in turn, give the flight of C-ordered float32 actions, bit for bit (the action map reads
    strides and converts to float64)."""
    plain, mixed = HyperloopSuspensionVectorEnv(4), HyperloopSuspensionVectorEnv(4)
    a_obs, _ = plain.reset(seed=[1, 2, 3, 4])
    b_obs, _ = mixed.reset(seed=[1, 2, 3, 4])
    rng = np.random.default_rng(3)
    for k in range(24):
        act = rng.uniform(-1.0, 1.0, (4, 4)).astype(np.float32)
        wide = np.zeros((8, 8), dtype=np.float32)
        wide[::2, ::2] = act
        seen = (wide[::2, ::2], np.asfortranarray(act), act.astype(np.float64), act)[k % 4]
        a_obs, a_rew, *_ = plain.step(act)
        b_obs, b_rew, *_ = mixed.step(seen)
        np.testing.assert_array_equal(b_obs, a_obs)
        np.testing.assert_array_equal(b_rew, a_rew)


def test_pickle_mid_flight_continues_the_flight():
    """A vector env pickled after steps (its compiled calls bound) flies on as the original."""
    envs = HyperloopSuspensionVectorEnv(3)
    envs.reset(seed=[4, 5, 6])
    rng = np.random.default_rng(7)
    for _ in range(3):
        envs.step(rng.uniform(-1, 1, (3, 4)).astype(np.float32))
    clone = pickle.loads(pickle.dumps(envs))
    for _ in range(3):
        a = rng.uniform(-1, 1, (3, 4))  # float64: the other dtype's entry, bound on the clone
        for x, y in zip(envs.step(a)[:4], clone.step(a)[:4], strict=True):
            np.testing.assert_array_equal(x, y)
