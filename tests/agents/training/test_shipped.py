"""The shipped agents are what their presets and searches say (issue: the headline agents).

For each shipped agent: the search results sit beside the model, the preset that trains it
takes the search's chosen configuration (its width as the critic's, the actor narrowed to
``ACTOR``) and the validation-best length of training among the checkpoints that fly the
paper conditions on validation seeds, the training log records that configuration, the
training seeds only, and a wall time within 45 minutes, and the loaded controller acts on
the actuator set it was trained for."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from agents.controllers.learned import shipped_path
from agents.training.presets import load_preset
from agents.training.tune import SEARCHED_KEYS

SHIPPED = {
    "ppo": ("levitation", 4),
    "ppo-guidance": ("levitation+guidance", 8),
    "ppo-memory": ("levitation", 4),
    "sac": ("levitation", 4),
}
ACTOR = {"ppo": [32, 32], "ppo-guidance": [16, 16], "ppo-memory": [128, 128], "sac": [128, 128]}
"""The shipped actors' hidden layers: the network a controller runs at every control step,
narrowed from the search's width for ``ppo`` and ``ppo-guidance`` so that the closed loop
runs at >= 90 % of the bare physics (issue 19 point 7, README "Performance"); the critic
keeps the search's width. ``ppo-memory`` keeps the search's width: narrowed to [32, 32] its
validation score fell from 0.086 to 0.040 (agents/shipped/README.md); ``sac`` too (its
actor and critics are the trial's width)."""


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_shipped_agent_is_its_preset_and_its_search(name: str) -> None:
    d = shipped_path(name)
    for f in (
        "model.zip",
        "vecnormalize.pkl",
        "training_log.json",
        "tune_results.json",
        "tune_trials.csv",
        "checkpoint_validation.json",
    ):
        assert (d / f).is_file(), f"{d / f} missing"
    log = json.loads((d / "training_log.json").read_text())
    search = json.loads((d / "tune_results.json").read_text())
    preset = load_preset(log["preset"])
    chosen = search["chosen_training_config"]
    for k in SEARCHED_KEYS:
        if k != "net_arch":
            assert preset[k] == chosen[k], k
    ppo = log["algo"] == "ppo"
    critic = chosen["net_arch"] if ppo else None  # SAC: the critics are the actor's width
    assert preset["net_arch"] == ACTOR[name] and preset.get("critic_arch") == critic
    assert preset["ship_name"] == name and preset["scenario"] == "benchmark-train"
    assert preset["env_kwargs"]["actuators"] == SHIPPED[name][0]
    # the chosen configuration is the best finished trial
    finished = [t for t in search["trials"] if t["error"] is None]
    assert search["best"]["index"] == max(finished, key=lambda t: t["score"])["index"]
    assert all(math.isfinite(t["score"]) for t in finished)
    # the training log is of that configuration, on training seeds, within 45 minutes
    hp = log["hyperparameters"]
    assert hp["learning_rate"] == chosen["learning_rate"]
    assert hp["net_arch"] == ACTOR[name] and hp["critic_arch"] == critic
    if ppo:
        assert hp["n_steps"] == chosen["n_steps"]
    for k, v in chosen["env_kwargs"].items():
        assert log["env_kwargs"][k] == v, k
    # the length of training is the validation-best checkpoint of the full-length run
    sel = json.loads((d / "checkpoint_validation.json").read_text())
    flying = [r for r in sel["checkpoints"] if r["flies"]]
    assert flying and sel["best"]["flies"] and not any(sel["best"]["contacts"].values())
    assert sel["best"]["score"] == max(r["score"] for r in flying)
    assert preset["timesteps"] == sel["best"]["steps"] == log["num_timesteps"]
    assert log["seed"] + preset["n_envs"] < 100_000
    assert 0 < log["wall_time_s"] <= 45 * 60


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_shipped_agent_acts_on_its_actuator_set(name: str) -> None:
    import gymnasium as gym

    from agents import make_controller
    from hyperloop_env import ENV_ID

    if not (shipped_path(name) / "model.zip").is_file():
        pytest.fail(f"agents/shipped/{name} has no model")
    acts, n = SHIPPED[name]
    env = gym.make(ENV_ID, scenario="paper-1000-straight", track_length_m=50.0, actuators=acts)
    ctrl = make_controller(name, env.unwrapped)
    obs, _ = env.reset(seed=0)
    ctrl.reset(seed=0)
    a = ctrl.act(obs)
    assert a.shape == (n,) and np.all(np.abs(a) <= 1.0)
    env.close()


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_compiled_forward_pass_is_torchs(name: str) -> None:
    """act_batch runs the policy in one compiled float32 call (no BLAS threads): the actions
    are torch's (``model.predict`` on the normalised observations) and the float64 NumPy
    reference pass's up to float32 rounding, a batch equals its rows one at a time bit for
    bit, float64 observations give the same actions, NaN propagates."""
    from agents.controllers.learned import load_shipped

    ctrl = load_shipped(name)
    pol = ctrl._np_policy
    assert pol is not None
    rng = np.random.default_rng(0)
    for n in (1, 3, 32, 257):
        raw = rng.normal(0.0, 1.0, (n, pol.n_in)).astype(np.float32)
        raw[0, 0] = 50.0  # beyond the normalisation clip
        x = ctrl.normalize(raw)
        a = ctrl.act_batch(raw)
        torch_a, _ = ctrl.model.predict(x.astype(np.float32), deterministic=True)
        np.testing.assert_allclose(a, np.clip(torch_a, -1.0, 1.0), rtol=0, atol=4e-6)
        np.testing.assert_allclose(a, np.clip(pol(x), -1.0, 1.0), rtol=0, atol=4e-6)
        np.testing.assert_array_equal(ctrl.act_batch(raw.astype(np.float64)), a)
        np.testing.assert_array_equal(ctrl.act(raw[-1]), a[-1])
    raw[1, 2] = np.nan
    a = ctrl.act_batch(raw)
    assert np.isnan(a[1]).all() and np.isfinite(np.delete(a, 1, axis=0)).all()
