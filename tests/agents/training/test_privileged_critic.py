"""The privileged critic (asymmetric actor-critic, the preset option ``privileged_critic``):
the simulator's state appended to the critic's observation, an actor that cannot see it,
and a trained run that flies as an ordinary controller on the plain observation."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

import torch as th  # noqa: E402

from agents.cli import train as cli  # noqa: E402
from agents.controllers.learned import SB3Controller  # noqa: E402
from agents.training import experiment  # noqa: E402
from agents.training.privileged import (  # noqa: E402
    PRIVILEGED_SIZE,
    PrivilegedObservationVecEnv,
)
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv  # noqa: E402


def _fly(env, steps: int, rng_seed: int = 3):
    """Observations and infos of ``steps`` random steps with a masked reset half-way."""
    rng = np.random.default_rng(rng_seed)
    obs, _ = env.reset(seed=[11, 12, 13])
    out = [(np.array(obs), None)]
    for k in range(steps):
        if k == steps // 2:
            obs, _ = env.reset(options={"reset_mask": np.array([False, True, False])})
            out.append((np.array(obs), None))
        a = rng.uniform(-0.3, 0.3, (3, env.single_action_space.shape[0])).astype(np.float32)
        obs, _, _, _, info = env.step(a)
        out.append((np.array(obs), info))
    return out


def test_the_appended_entries_are_the_true_state_and_the_rest_is_untouched() -> None:
    plain = HyperloopSuspensionVectorEnv(3, scenario="paper-1000-curved")
    wrapped = PrivilegedObservationVecEnv(
        HyperloopSuspensionVectorEnv(3, scenario="paper-1000-curved")
    )
    n = plain.single_observation_space.shape[0]
    assert wrapped.single_observation_space.shape == (n + PRIVILEGED_SIZE,) == (n + 42,)
    assert wrapped.actor_inputs == n
    for (o_plain, _), (o_priv, info) in zip(_fly(plain, 6), _fly(wrapped, 6), strict=True):
        np.testing.assert_array_equal(o_priv[:, :n], o_plain)  # the agent's part, bit for bit
        if info is None:
            continue
        s = o_priv[:, n:]
        # the vehicle's q and q̇ (the first 26 state entries), then the true gaps and lateral
        # offsets the env reports in its info (float32, as the observation)
        np.testing.assert_array_equal(s[:, :26], info["state"][:, :26].astype(np.float32))
        np.testing.assert_array_equal(s[:, 26:30], info["gap_excursion_m"].astype(np.float32))
        np.testing.assert_array_equal(s[:, 30:34], info["lateral_offset_m"].astype(np.float32))
        assert np.isfinite(s).all() and np.abs(s[:, 26:30]).max() < 8e-3


def test_the_wrapper_needs_the_native_env() -> None:
    import gymnasium as gym

    venv = gym.make_vec("HyperloopSuspension-v0", num_envs=2, vectorization_mode="sync")
    with pytest.raises(ValueError, match="native vector env"):
        PrivilegedObservationVecEnv(venv)


def _model(tmp_path: Path):
    cfg = cli.resolve_config(
        ["--preset", "tiny", "--out", str(tmp_path / "m"), "--no-eval", "--no-progress"]
    )
    cfg["privileged_critic"] = True
    env = experiment.make_vec_env(experiment.env_config(cfg), 2, 5, "native", privileged=True)
    return experiment.build_model(cfg, env, None), env


def test_the_actor_cannot_see_the_privileged_entries_and_the_critic_does(tmp_path: Path) -> None:
    model, env = _model(tmp_path)
    pol = model.policy
    n = pol.actor_inputs
    assert n == env.observation_space.shape[0] - PRIVILEGED_SIZE
    assert pol.mlp_extractor.policy_net[0].in_features == n  # what a controller runs
    assert pol.mlp_extractor.value_net[0].in_features == n + PRIVILEGED_SIZE
    obs = th.as_tensor(np.random.default_rng(0).normal(size=(5, n + PRIVILEGED_SIZE)))
    other = obs.clone()
    other[:, n:] += 3.0
    with th.no_grad():
        d0 = pol.get_distribution(obs.float()).distribution
        d1 = pol.get_distribution(other.float()).distribution
        assert th.equal(d0.mean, d1.mean) and th.equal(d0.stddev, d1.stddev)
        assert not th.allclose(pol.predict_values(obs.float()), pol.predict_values(other.float()))
    env.close()


def test_a_privileged_run_flies_as_a_controller_on_the_plain_observation(tmp_path: Path) -> None:
    out = tmp_path / "run"
    cfg = cli.resolve_config(
        ["--preset", "tiny", "--out", str(out), "--no-eval", "--no-progress"]
        + ["--timesteps", "1024"]
    )
    cfg["privileged_critic"] = True  # a configuration built in code is checked by train too
    log = experiment.train(cfg)
    assert log["privileged_critic"] is True and log["config"]["privileged_critic"] is True
    ctrl = SB3Controller(out)
    venv = HyperloopSuspensionVectorEnv(3, scenario="paper-2000-straight")
    obs, _ = venv.reset(seed=4)
    a = ctrl.act_batch(obs)
    # the same actor in torch, given the observation with anything in the privileged part
    n = ctrl.actor_inputs
    x = np.clip((obs - ctrl.obs_norm["mean"]) / ctrl.obs_norm["std"], -10, 10)
    full = np.hstack([x, np.full((3, PRIVILEGED_SIZE), 7.0)]).astype(np.float32)
    with th.no_grad():
        ref = ctrl.model.policy.get_distribution(th.as_tensor(full)).mode().numpy()
    assert n == obs.shape[1] and a.shape == (3, 4)
    np.testing.assert_allclose(a, np.clip(ref, -1, 1), atol=1e-5)
    slow = SB3Controller(out, use_numpy=False)  # SB3's predict, padded
    np.testing.assert_allclose(slow.act_batch(obs), a, atol=1e-5)


def test_runs_without_it_keep_their_fingerprint() -> None:
    cfg = cli.resolve_config(["--preset", "tiny"])
    assert cfg["privileged_critic"] is False
    assert "privileged_critic" not in experiment.run_fingerprint(cfg)


@pytest.mark.parametrize(
    ("args", "match"),
    [(["--algo", "sac"], "--algo sac has none"), (["--vec", "dummy"], "native")],
)
def test_it_is_refused_where_it_cannot_train(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], match: str
) -> None:
    preset = tmp_path / "p.json"
    preset.write_text(json.dumps({"privileged_critic": True}))
    with pytest.raises(SystemExit):
        cli.resolve_config(["--preset", str(preset), "--no-eval", *args])
    assert match in capsys.readouterr().err


def test_a_non_boolean_is_a_preset_error(tmp_path: Path) -> None:
    from agents.training.presets import PresetError, load_preset

    preset = tmp_path / "p.json"
    preset.write_text(json.dumps({"privileged_critic": "yes"}))
    with pytest.raises(PresetError, match="privileged_critic"):
        load_preset(str(preset))
