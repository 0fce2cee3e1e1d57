"""A user's controller in every tool: ``package.module:factory`` or a saved model.zip,
built by import in whichever process runs it (spawned local workers included)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from agents.controllers.base import control_context
from agents.controllers.registry import controller_problem, is_entry_point, make_controller
from agents.evaluation.rollout import episode_config

MODULE = textwrap.dedent(
    '''
    """A controller defined outside the package: zero action (the passive suspension)."""
    import numpy as np


    class Zero:
        name = "zero"

        def __init__(self, ctx=None, **kw):
            self.n = 4

        def reset(self, seed=None):
            pass

        def act(self, obs):
            return np.zeros(self.n, dtype=np.float32)

        def act_batch(self, obs):
            return np.zeros((obs.shape[0], self.n), dtype=np.float32)


    def make(env_or_params=None, **kw):
        return Zero(env_or_params, **kw)
    '''
)


@pytest.fixture
def user_module(tmp_path, monkeypatch):  # noqa: ANN001, ANN201
    (tmp_path / "user_ctrl_mod.py").write_text(MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    return "user_ctrl_mod:make"


def test_entry_point_is_built_by_import(user_module) -> None:  # noqa: ANN001
    assert is_entry_point(user_module) and not is_entry_point("pid")
    assert controller_problem(user_module) is None
    ctrl = make_controller(user_module, control_context(None))
    assert np.array_equal(ctrl.act(np.ones(23, np.float32)), np.zeros(4))
    with pytest.raises(ValueError, match="cannot import 'no_such_module_x'"):
        make_controller("no_such_module_x:make")
    with pytest.raises(ValueError, match="has no 'nothing'"):
        make_controller("user_ctrl_mod:nothing")
    assert "unknown controller 'sacc'" in controller_problem("sacc")


def test_entry_point_in_spawned_workers_equals_passive(user_module) -> None:  # noqa: ANN001
    """The capacity search of the user's zero-action controller on 2 spawned workers gives
    the passive controller's capacities exactly."""
    from agents.evaluation.capacity_benchmark import run

    res = run(
        [user_module, "passive"],
        ["paper-2000-straight"],
        ["roughness"],
        seeds=[1_000_000, 1_000_001],
        distance_km=0.2,
        workers=2,
        n_boot=20,
        progress=False,
        ratio=1.1,
    )
    cell = res["capacities"]["paper-2000-straight"]["roughness"]
    caps = {lab: [d["capacity"] for d in v] for lab, v in cell.items()}
    assert caps[user_module] == caps["passive"]


def test_entry_point_on_the_evaluate_command_line(user_module, tmp_path) -> None:  # noqa: ANN001
    out = tmp_path / "ev"
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "agents.evaluate",
            "--controllers",
            user_module,
            "passive",
            "--scenarios",
            "paper-2000-straight",
            "--distance-km",
            "0.7",
            "--seeds",
            "1",
            "--out",
            str(out),
            "--no-figures",
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr[-2000:]
    assert user_module in (out / "report.md").read_text()


def test_saved_model_path_equals_the_registered_agent() -> None:
    pytest.importorskip("stable_baselines3", reason="needs the [train] extra")
    from agents.controllers.learned import MODEL_FILE, shipped_path

    path = str(shipped_path("ppo") / MODEL_FILE)
    ctx = control_context(episode_config("paper-1000-straight", 1.0).resolve().base)
    a = make_controller("ppo", ctx)
    b = make_controller(path, ctx)
    obs = np.random.default_rng(0).normal(size=(5, 23)).astype(np.float32) * 0.1
    assert np.array_equal(a.act_batch(obs), b.act_batch(obs))


@pytest.mark.slow
def test_entry_point_on_ray_workers_equals_passive(user_module) -> None:  # noqa: ANN001
    """Ray workers import the user's module themselves (PYTHONPATH reaches them)."""
    pytest.importorskip("ray", reason="needs Ray (optional extra: pip install -e '.[ray]')")
    from agents.evaluation.capacity_benchmark import run

    res = run(
        [user_module, "passive"],
        ["paper-2000-straight"],
        ["roughness"],
        seeds=[1_000_000, 1_000_001],
        distance_km=0.2,
        backend="ray",
        n_boot=20,
        progress=False,
        ratio=1.1,
    )
    cell = res["capacities"]["paper-2000-straight"]["roughness"]
    assert [d["capacity"] for d in cell[user_module]] == [d["capacity"] for d in cell["passive"]]
