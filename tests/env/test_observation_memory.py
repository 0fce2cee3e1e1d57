"""The observation memory options (``observation_history``, ``observation_front_preview``):
values against the plain observations they are built from, both envs' reset paths, and
the controllers that read the plain blocks by name."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import hyperloop_env  # noqa: F401 - registers the env
from hyperloop_env.config import EnvConfig
from hyperloop_env.observation import OBS_SIZE, MemorySpec, observation_spec
from hyperloop_env.observation_memory import ObservationMemory
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

MEM = {"observation_history": 3, "observation_front_preview": True}


def _fly(steps: int, **kw) -> np.ndarray:
    env = gym.make("HyperloopSuspension-v0", **kw)
    obs, _ = env.reset(seed=7)
    out = [obs]
    for _ in range(steps):
        obs, *_ = env.step(np.zeros(env.action_space.shape))
        out.append(obs)
    return np.array(out)


def test_default_observation_is_unchanged() -> None:
    env = gym.make("HyperloopSuspension-v0")
    assert env.observation_space.shape == (OBS_SIZE,) == (23,)
    assert not env.unwrapped.observation_spec.memory.active
    assert "observation_history" not in EnvConfig().to_kwargs()


def test_layout_sizes() -> None:
    spec = observation_spec("levitation", MemorySpec(history=4, front_preview=True))
    assert spec.base_size == 23 and spec.n_measured == 18
    assert spec.slice("history") == slice(23, 23 + 3 * 18)
    assert spec.slice("front_preview") == slice(77, 93) and spec.size == 93
    guided = observation_spec("levitation+guidance", MemorySpec(history=2))
    assert guided.base_size == 31 and guided.size == 31 + 26


def test_history_is_the_previous_measured_entries() -> None:
    plain = _fly(40)
    full = _fly(40, **MEM)
    spec = observation_spec("levitation", MemorySpec(3, True))
    nm = spec.n_measured
    np.testing.assert_array_equal(full[:, :23], plain)  # the plain blocks are unchanged
    h = full[:, spec.slice("history")].reshape(len(full), 2, nm)
    np.testing.assert_array_equal(h[10, 0], plain[9, :nm])  # lag 1
    np.testing.assert_array_equal(h[10, 1], plain[8, :nm])  # lag 2
    np.testing.assert_array_equal(h[1, 1], plain[0, :nm])  # older than the episode: reset
    np.testing.assert_array_equal(h[0, 0], plain[0, :nm])


@pytest.mark.parametrize(
    ("scenario", "delay"), [("paper-1000-straight", 58), ("paper-2000-curved", 29)]
)
def test_front_preview_is_the_front_units_one_set_spacing_earlier(
    scenario: str, delay: int
) -> None:
    """τ = 16 m / v in 1 ms steps: 57.6 → 58 at 1000 km/h, 28.8 → 29 at 2000 km/h; the lead
    ℓ entry is the front units' (FL, FR) gap and lateral entries τ − ℓ steps earlier."""
    plain = _fly(100, scenario=scenario)
    full = _fly(100, scenario=scenario, **MEM)
    spec = observation_spec("levitation", MemorySpec(3, True))
    fp = full[:, spec.slice("front_preview")].reshape(len(full), 4, 4)
    cols = [0, 1, 8, 9]  # gap FL, FR; lateral FL, FR
    t = 90
    for j, lead in enumerate((0, 5, 10, 20)):
        np.testing.assert_array_equal(fp[t, j], plain[t - delay + lead, cols])
    np.testing.assert_array_equal(fp[10, 0], plain[0, cols])  # before τ: the reset value


def test_vector_env_rows_match_the_single_env_through_autoresets() -> None:
    """Both autoreset modes: a row that ended starts its memory anew, like a fresh env."""
    kw = {"track_length_m": 100.0, **MEM}  # 360 steps at 1000 km/h
    single = _fly(0, **kw)[0]
    for mode in ("SameStep", "NextStep"):
        venv = HyperloopSuspensionVectorEnv(
            2, autoreset_mode=mode, config=EnvConfig.from_kwargs(**kw)
        )
        obs, _ = venv.reset(seed=[7, 8])
        np.testing.assert_array_equal(obs[0], single)
        zero = np.zeros((2, 4))
        for _ in range(400):
            obs, _, term, trunc, info = venv.step(zero)
            if trunc[0] or term[0]:
                break
        if mode == "NextStep":
            obs, *_ = venv.step(zero)
        spec = venv.observation_spec
        h = obs[0, spec.slice("history")].reshape(2, -1)
        np.testing.assert_array_equal(h[0], obs[0, : spec.n_measured])  # reset fill
        fp = obs[0, spec.slice("front_preview")].reshape(4, 4)
        np.testing.assert_array_equal(fp[0], obs[0, [0, 1, 8, 9]])


def test_memory_from_plain_observations_equals_the_env() -> None:
    """What a controller trained with memory rebuilds from plain observations."""
    plain = _fly(80, scenario="paper-2000-straight").astype(np.float32)
    full = _fly(80, scenario="paper-2000-straight", **MEM)
    spec = observation_spec("levitation", MemorySpec(3, True))
    mem = ObservationMemory(spec, 1, 16.0, 1e-3)
    rebuilt = [mem.start(plain[:1])[0]] + [mem.push(plain[i : i + 1])[0] for i in range(1, 81)]
    np.testing.assert_array_equal(np.array(rebuilt), full)


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("observation_history", 0),
        ("observation_history", 17),
        ("observation_history", 2.0),
        ("observation_history", True),
        ("observation_front_preview", "yes"),
        ("observation_front_preview", 1),
    ],
)
def test_bad_memory_options_name_the_keyword(key: str, value: object) -> None:
    with pytest.raises(ValueError, match=key):
        gym.make("HyperloopSuspension-v0", **{key: value})


@pytest.mark.parametrize("name", ["lqr", "pid"])
def test_classical_controllers_read_the_plain_blocks_of_a_memory_env(name: str) -> None:
    from agents.controllers import make_controller

    acts = []
    for kw in ({}, MEM):
        env = gym.make("HyperloopSuspension-v0", scenario="paper-2000-curved", **kw)
        ctrl = make_controller(name, env)
        obs, _ = env.reset(seed=3)
        ctrl.reset(seed=3)
        out = []
        for _ in range(200):
            a = ctrl.act(obs)
            out.append(a)
            obs, *_ = env.step(a)
        acts.append(np.array(out))
    np.testing.assert_array_equal(acts[0], acts[1])


def test_agent_trained_with_memory_acts_on_plain_and_full_observations(tmp_path) -> None:
    """A tiny PPO run with memory options: the controller rebuilds the memory blocks from
    plain observations (act and act_batch, reset_batch starting rows anew) and gives the
    same actions as on the memory env's own observations."""
    pytest.importorskip("stable_baselines3")
    from agents.cli import train as cli
    from agents.controllers import make_controller
    from agents.training import experiment

    out = tmp_path / "mem"
    cfg = cli.resolve_config(
        ["--preset", "tiny", "--timesteps", "1024", "--out", str(out), "--no-eval"]
        + ["--no-progress", "--env-kwarg", "observation_history=3"]
        + ["--env-kwarg", "observation_front_preview=true"]
    )
    experiment.train(cfg)
    full_env = gym.make("HyperloopSuspension-v0", scenario="paper-2000-straight", **MEM)
    plain = _fly(60, scenario="paper-2000-straight")
    full = _fly(60, scenario="paper-2000-straight", **MEM)
    ctrl = make_controller("ppo", full_env, path=out)
    assert ctrl.memory == MemorySpec(3, True)
    ref = ctrl.act_batch(full)  # full observations: stateless
    one = np.array([ctrl.act(o) for o in plain])  # plain: built step by step
    np.testing.assert_array_equal(one, ref)
    other = make_controller("ppo", full_env, path=out)
    assert other is not ctrl  # a fresh memory per caller
    two = np.stack([plain, plain], axis=1)  # two rows flying the same run
    batch = np.array([other.act_batch(two[i]) for i in range(30)])
    np.testing.assert_array_equal(batch[:, 0], ref[:30])
    other.reset_batch(np.array([False, True]))  # row 1 restarts from step 0
    b = np.array([other.act_batch(np.stack([plain[30 + i], plain[i]])) for i in range(30)])
    np.testing.assert_array_equal(b[:, 0], ref[30:60])
    np.testing.assert_array_equal(b[:, 1], ref[:30])
    with pytest.raises(ValueError, match="entries"):
        ctrl.act_batch(np.zeros((1, 40), dtype=np.float32))
