"""The site's "Extending" page (docs/extending.md): every recipe exercised as the page
writes it.

* A controller: a module with a factory, used by entry point and by a registered name, in
  an evaluation and in a spawned worker of the fragility/capacity backends.
* A disturbance: a frozen dataclass deriving from ``Disturbance`` with a ``profile_offset``
  realisation, added to ``DISTURBANCES``, used through ``gym.make(ENV_ID, disturbances=…)``
  and the vector env.
* An environment keyword: ``tests/env/test_keywords.py`` (a toy declared field).
* An actuator kind: ``tests/env/test_toy_actuator.py`` (a toy kind through
  ``register_actuator_kind``, both envs).

The page must name these tests (checked below), so the recipes and their tests move
together.
"""

from __future__ import annotations

import re
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import gymnasium as gym
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]

CONTROLLER_MODULE = '''
"""A user's controller: a constant small lift on every levitation coil."""
import numpy as np

from agents.controllers.base import control_context


class Lift:
    name = "lift"

    def __init__(self, ctx):
        self.n = ctx.actuators.size
        self.lev = ctx.actuators.slice("levitation")

    def reset(self, seed=None):
        pass

    def act(self, obs):
        a = np.zeros(self.n, dtype=np.float32)
        a[self.lev] = 0.01
        return a


def make(env_or_ctx, **kwargs):
    return Lift(control_context(env_or_ctx), **kwargs)
'''


def _extending_section() -> str:
    return (ROOT / "docs" / "extending.md").read_text()


def test_the_section_names_a_test_for_every_recipe() -> None:
    sec = _extending_section()
    recipes = re.findall(r"^\*\*(An? [^*]+)\*\*", sec, flags=re.M)
    assert {"A controller", "A disturbance", "An environment keyword", "An actuator kind"} <= {
        r.split(" (")[0].split(" —")[0] for r in recipes
    }, recipes
    for test in (
        "tests/test_readme_extending.py",
        "tests/env/test_keywords.py",
        "tests/env/test_toy_actuator.py",
    ):
        assert test in sec and (ROOT / test).exists(), test


@pytest.fixture
def user_package(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    pkg = tmp_path / "userpkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "my_controller.py").write_text(textwrap.dedent(CONTROLLER_MODULE))
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("PYTHONPATH", f"{tmp_path}:{ROOT}")  # spawned workers import it too
    return "userpkg.my_controller:make"


def test_controller_recipe_entry_point_and_registered_name(user_package: str) -> None:
    from agents import register_controller
    from agents.controllers.registry import _REGISTRY
    from agents.evaluation.rollout import episode_config, run_episodes

    cfg = episode_config("paper-1000-straight", 0.1, None, {})
    by_entry = run_episodes(user_package, cfg, [3, 4], 0.1, None)
    register_controller("lift-test", user_package, actuators="levitation", overwrite=True)
    try:
        by_name = run_episodes("lift-test", cfg, [3, 4], 0.1, None)
        passive = run_episodes("passive", cfg, [3, 4], 0.1, None)
        tau = cfg.resolve().base.magnet.coil_time_constant_s
        assert tau > 0
        k = np.arange(1, 21)
        for a, b, p in zip(by_entry, by_name, passive, strict=True):
            np.testing.assert_array_equal(a.current_A, b.current_A)
            # the command 0.01 is I0 (1 + 0.01); the coil follows it with its first-order lag
            i0 = p.current_A[1]  # passive: the bias I0 throughout
            lag = 1 + 0.01 * (1 - np.exp(-k * a.dt_s / tau))
            np.testing.assert_allclose(a.current_A[1:21], lag[:, None] * i0[None, :], rtol=1e-9)
    finally:
        _REGISTRY.pop("lift-test", None)


def test_controller_recipe_reaches_spawned_workers(user_package: str) -> None:
    from agents import register_controller
    from agents.controllers.registry import _REGISTRY
    from agents.evaluation.backends import run_blocks
    from agents.evaluation.batch_rollout import BlockSpec
    from agents.evaluation.rollout import episode_config

    cfg = episode_config("paper-1000-straight", 0.05, None, {})
    register_controller("lift-test", user_package, actuators="levitation", overwrite=True)
    try:
        specs = [BlockSpec("lift-test", cfg, (s,), settle_s=0.01) for s in (1, 2)]
        local = dict(run_blocks(specs, workers=1))
        pooled = dict(run_blocks(specs, workers=2))
        for i in (0, 1):
            a, b = local[i].runs[0], pooled[i].runs[0]
            assert a.n_steps == b.n_steps > 0
            for k in a.gap:
                np.testing.assert_array_equal(a.gap[k], b.gap[k])
        # the user's lift differs from passive (the factory really ran in the workers)
        passive = dict(run_blocks([BlockSpec("passive", cfg, (1,), settle_s=0.01)], workers=2))
        assert not np.array_equal(passive[0].runs[0].gap["mean"], pooled[0].runs[0].gap["mean"])
    finally:
        _REGISTRY.pop("lift-test", None)


def test_disturbance_recipe(monkeypatch: pytest.MonkeyPatch) -> None:
    """A uniform rail lift of ``severity`` metres under both rails, as the recipe builds it."""
    from hyperloop_env import ENV_ID
    from hyperloop_env.disturbances import DISTURBANCES
    from hyperloop_env.disturbances.base import (
        Disturbance,
        check_real,
        profile_realisation,
    )
    from hyperloop_env.physics.irregularity import ROW_LATERAL, ROW_LEFT, ROW_RIGHT
    from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

    @dataclass(frozen=True)
    class RailLift(Disturbance):
        name: ClassVar[str] = "rail_lift_test"
        severity_unit: ClassVar[str] = "rail lift [m]"
        description: ClassVar[str] = "both rails raised by a constant"
        severity: float = 0.0

        def __post_init__(self) -> None:
            check_real(self, "severity", lower=0.0, upper=0.01)

        def realise(self, params, grid, rng):  # noqa: ANN001, ANN201
            return profile_realisation(grid, np.full(grid.n, self.severity))

    monkeypatch.setitem(DISTURBANCES, RailLift.name, RailLift)
    kw = {"scenario": "paper-1000-straight", "track_length_m": 100.0}
    flat = gym.make(ENV_ID, disturbances={"roughness": 0.0}, **kw)
    lifted = gym.make(ENV_ID, disturbances={"roughness": 0.0, RailLift.name: 0.002}, **kw)
    flat.reset(seed=5)
    lifted.reset(seed=5)
    d = lifted.unwrapped.sim.irr - flat.unwrapped.sim.irr
    np.testing.assert_allclose(d[[ROW_LEFT, ROW_RIGHT]], 0.002, rtol=0, atol=1e-15)
    np.testing.assert_allclose(d[ROW_LATERAL], 0.0, rtol=0, atol=1e-15)
    with pytest.raises(ValueError, match="severity"):
        gym.make(ENV_ID, disturbances={RailLift.name: 0.5}, **kw)
    # the vector env flies it too: row 0 (seed 5) equals the single env step for step
    venv = HyperloopSuspensionVectorEnv(
        2, disturbances={"roughness": 0.0, RailLift.name: 0.002}, **kw
    )
    obs_v, _ = venv.reset(seed=[5, 6])
    obs_s, _ = lifted.reset(seed=5)
    np.testing.assert_array_equal(obs_v[0], obs_s)
    for _ in range(5):
        obs_v, *_ = venv.step(np.zeros(venv.action_space.shape, dtype=np.float32))
        obs_s, *_ = lifted.step(np.zeros(lifted.action_space.shape, dtype=np.float32))
    np.testing.assert_array_equal(obs_v[0], obs_s)
    venv.close()
    flat.close()
    lifted.close()
