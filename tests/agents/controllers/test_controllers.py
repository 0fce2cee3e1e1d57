"""Controller protocol, registry and closed-loop behaviour of PID and LQR."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from agents import Controller, PassiveController, make_controller, register_controller
from agents.controllers.base import control_context
from agents.controllers.lqr import design_lqg
from agents.controllers.pid import closed_loop_spectral_radius, design_pid, load_design
from agents.evaluation.rollout import make_env, run_episode
from hyperloop_env.config import build_config
from hyperloop_env.observation import OBS_SIZE


@pytest.mark.parametrize("name", ["passive", "pid", "lqr"])
def test_protocol_and_action_range(name: str) -> None:
    env = make_env("paper-1000-straight", track_length_m=100.0)
    obs, _ = env.reset(seed=0)
    ctrl = make_controller(name, env)
    assert isinstance(ctrl, Controller)
    assert ctrl.name == name
    ctrl.reset(seed=0)
    for _ in range(20):
        a = ctrl.act(obs)
        assert a.shape == (4,) and a.dtype == np.float32
        assert np.all(a >= -1) and np.all(a <= 1)
        obs, *_ = env.step(a)
    big = np.zeros(OBS_SIZE, dtype=np.float32)
    big[:4] = 0.9  # large gap opening -> saturating but bounded action
    assert np.all(np.abs(ctrl.act(big)) <= 1)
    env.close()


def test_make_controller_from_params_and_errors() -> None:
    for name in ("passive", "pid", "lqr"):
        assert make_controller(name).act(np.zeros(OBS_SIZE)).shape == (4,)
    with pytest.raises(ValueError, match="unknown controller"):
        make_controller("nope")
    with pytest.raises(ValueError, match="env_or_params"):
        control_context(42)


def test_user_controller_plugs_in() -> None:
    class Zero(PassiveController):
        name = "user-zero"

    register_controller("user-zero", lambda env_or_params=None, **kw: Zero(), overwrite=True)
    assert make_controller("user-zero").name == "user-zero"
    with pytest.raises(ValueError, match="already registered"):
        register_controller("user-zero", lambda *a, **k: Zero())


def test_passive_batch() -> None:
    assert PassiveController().act_batch(np.zeros((3, OBS_SIZE))).shape == (3, 4)


@pytest.mark.parametrize("magnet", ["repelling", "attracting"])
def test_designs_are_stable_on_the_linear_model(magnet: str) -> None:
    p = build_config("paper-1000-straight", magnet=magnet).base
    gains = design_pid(p, load_design())
    assert closed_loop_spectral_radius(p, gains) < 1.0
    m = design_lqg(p)
    assert m.closed_loop_radius < 1.0
    n = m.Phi.shape[0]
    est = np.abs(np.linalg.eigvals(m.Phi @ (np.eye(n) - m.M @ m.C))).max()
    assert est < 1.0


def _rms(ep, settle_s: float = 0.3) -> float:
    g = ep.gap_m[1 + int(settle_s / ep.dt_s) :]
    return float(np.sqrt(np.mean(g**2)))


GUIDED = {"actuators": "levitation+guidance"}


@pytest.mark.parametrize("name", ["pid", "lqr"])
def test_stabilises_attracting_magnets(name: str) -> None:
    """EMS: the levitation gap and the guidance pairs are both open-loop unstable; with the
    guidance pairs actuated PID and LQR hold both for ~2 s (556 m at 1000 km/h), on the
    straight and in the 200 km curve."""
    passive = run_episode(
        lambda e: make_controller("passive", e),
        "paper-1000-straight",
        1,
        0.556,
        "attracting",
        GUIDED,
    )
    assert passive.terminated and passive.contact_time_s < 0.5
    for sc in ("paper-1000-straight", "paper-1000-curved"):
        ep = run_episode(lambda e: make_controller(name, e), sc, 1, 0.556, "attracting", GUIDED)
        assert not ep.terminated
        assert ep.time_s[-1] >= 1.99
        assert np.max(np.abs(ep.gap_m)) < 0.004
        assert np.max(np.abs(ep.lateral_m)) < 0.004
        assert np.any(np.abs(ep.guidance_current_A) > 0.1)  # the pairs are driven


@pytest.mark.parametrize("name", ["pid", "lqr"])
def test_attracting_without_guidance_actuation_touches_laterally(name: str) -> None:
    """With only the levitation currents actuated the attracting guidance pairs stay at
    bias: open-loop unstable, so the vehicle ends in lateral contact (honest failure)."""
    ep = run_episode(
        lambda e: make_controller(name, e), "paper-1000-straight", 1, 0.556, "attracting"
    )
    assert ep.terminated and ep.contact_kind == "lateral"
    assert np.all(ep.guidance_current_A == 0.0)


@pytest.mark.parametrize("name", ["pid", "lqr"])
def test_reduces_rms_gap_vs_passive_repelling(name: str) -> None:
    passive = run_episode(lambda e: make_controller("passive", e), "paper-1000-straight", 2, 0.4)
    ep = run_episode(lambda e: make_controller(name, e), "paper-1000-straight", 2, 0.4)
    assert not ep.terminated
    assert _rms(ep) < 0.8 * _rms(passive)


@pytest.mark.parametrize("name", ["passive", "pid", "lqr"])
@pytest.mark.parametrize("actuators", ["levitation", "levitation+guidance"])
def test_act_batch_equals_independent_single_controllers(name: str, actuators: str) -> None:
    """act_batch runs N independent copies of the controller: row i equals a single
    controller fed row i's observations (also after resetting some rows)."""
    env = make_env("paper-1000-curved", actuators=actuators)
    env.reset(seed=0)
    batch = make_controller(name, env)
    rng = np.random.default_rng(1)
    n, size = 3, env.observation_space.shape[0]
    singles = [make_controller(name, env) for _ in range(n)]
    if hasattr(batch, "reset_batch"):
        batch.reset_batch(np.ones(n, dtype=bool))
    for k in range(120):
        obs = rng.normal(0.0, 0.3, (n, size)).astype(np.float32)
        if k == 60 and hasattr(batch, "reset_batch"):
            batch.reset_batch(np.array([False, True, False]))
            singles[1].reset()
        a = batch.act_batch(obs)
        assert a.shape == (n, env.action_space.shape[0]) and a.dtype == np.float32
        for i in range(n):
            np.testing.assert_array_equal(a[i], singles[i].act(obs[i]))
    with pytest.raises(ValueError, match="obs must have shape"):
        batch.act_batch(np.zeros((2, size + 1)))


@pytest.mark.parametrize("name", ["pid", "lqr", "lqr-preview"])
def test_act_batch_takes_any_layout_and_float_dtype(name: str) -> None:
    """Observations strided, in Fortran order, in float64 (the same values) and C-ordered
    float32, in turn, give the actions of a controller fed C-ordered float32 only, bit for bit
    (the compiled law reads strides and converts to float64)."""
    env = make_env("paper-1000-curved", actuators="levitation+guidance")
    env.reset(seed=0)
    plain, mixed = make_controller(name, env), make_controller(name, env)
    rng = np.random.default_rng(2)
    n, size = 5, env.observation_space.shape[0]
    for c in (plain, mixed):
        c.reset_batch(np.ones(n, dtype=bool))
    for k in range(40):
        obs = rng.normal(0.0, 0.3, (n, size)).astype(np.float32)
        wide = np.zeros((2 * n, 2 * size), dtype=np.float32)
        wide[::2, ::2] = obs
        seen = (wide[::2, ::2], np.asfortranarray(obs), obs.astype(np.float64), obs)[k % 4]
        np.testing.assert_array_equal(mixed.act_batch(seen), plain.act_batch(obs))


@pytest.mark.parametrize("name", ["lqr", "lqr-preview", "ppo"])
def test_controller_pickled_mid_flight_acts_as_the_original(name: str) -> None:
    """A controller pickled after steps (its compiled calls bound) gives the original's
    actions from there on, bit for bit."""
    env = make_env("paper-1000-curved")
    env.reset(seed=0)
    ctrl = make_controller(name, env)
    rng = np.random.default_rng(4)
    n, size = 3, env.observation_space.shape[0]
    ctrl.reset_batch(np.ones(n, dtype=bool))
    for _ in range(5):
        ctrl.act_batch(rng.normal(0.0, 0.3, (n, size)).astype(np.float32))
    clone = pickle.loads(pickle.dumps(ctrl))
    for _ in range(5):
        obs = rng.normal(0.0, 0.3, (n, size)).astype(np.float32)
        np.testing.assert_array_equal(clone.act_batch(obs), ctrl.act_batch(obs))


def test_missing_pid_gains_file_is_an_error_naming_it(tmp_path) -> None:  # noqa: ANN001
    """The tuned PID design is package data: a missing file is an error naming it, never a
    silent fallback to other gains (issue 16, point 2)."""
    missing = tmp_path / "pid_gains.json"
    with pytest.raises(FileNotFoundError, match="pid_gains.json"):
        load_design(missing)


def test_make_controller_takes_the_native_vector_env() -> None:
    """``make_controller(name, venv)`` designs on the vector env's nominal model: the same
    controller as the evaluation engine's (``build_controller``), acting on its batch."""
    from agents import make_controller
    from agents.evaluation.engine import build_controller
    from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

    venv = HyperloopSuspensionVectorEnv(3, scenario="paper-1000-straight", track_length_m=50.0)
    obs, _ = venv.reset(seed=[1, 2, 3])
    a = make_controller("lqr", venv).act_batch(obs)
    b = build_controller("lqr", venv.env_config).act_batch(obs)
    np.testing.assert_array_equal(a, b)
    assert a.shape == (3, 4) and np.any(a != 0.0)
    venv.close()


@pytest.mark.parametrize("name", ["ppo", "ppo-memory"])
def test_learned_agent_flies_a_new_batch_size_after_reset_batch(name: str) -> None:
    """A shipped agent is shared by its callers: ``reset_batch`` of a new number of rows
    starts a new batch (it once broadcast the old rows' pending mask against the new one),
    and that batch's actions are the agent's for those rows alone."""
    from agents.controllers.registry import make_controller

    ctrl = make_controller(name)
    obs = np.random.default_rng(3).normal(size=(64, 23)).astype(np.float32)
    ctrl.reset_batch(np.ones(64, dtype=bool))
    ctrl.act_batch(obs)
    ctrl.reset_batch(np.ones(64, dtype=bool))  # pending, never stepped
    ctrl.reset_batch(np.ones(8, dtype=bool))  # the next flight: 8 rows
    got = ctrl.act_batch(obs[:8])
    fresh = make_controller(name).fresh()
    fresh.reset_batch(np.ones(8, dtype=bool))
    np.testing.assert_array_equal(got, fresh.act_batch(obs[:8]))
