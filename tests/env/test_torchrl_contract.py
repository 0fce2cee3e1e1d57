"""What TorchRL needs from the environments, checked without TorchRL.

TorchRL (0.14) wraps Gymnasium environments with ``GymEnv``/``GymWrapper``. What it
requires, as its code checks it:

* ``GymWrapper(vector_env)`` accepts ``autoreset_mode`` ``SAME_STEP`` or ``DISABLED``
  only (``RuntimeError`` otherwise); with ``DISABLED`` it resets the ended environments
  itself, ``reset(options={"reset_mask": done})``, and does not read the info;
* a batched environment whose autoreset is not ``DISABLED`` (``GymEnv(id, num_envs=N)``:
  an ``AsyncVectorEnv`` of single environments, or ``SAME_STEP``) has its info read every
  step: every entry stacked into the batch, and a nested dict (the default
  ``reward_terms``) fails (``info="flat"`` avoids it);
* ``GymEnv(id)`` of one environment does not read the info.

:class:`FakeTorchRL` enforces exactly that, and the TorchRL snippet of
docs/getting-started.md is run against it (the real library runs the same snippet in
``tests/test_docs_snippets.py`` where it is installed).
"""

from __future__ import annotations

import re
import sys
import types
from functools import partial
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import hyperloop_env  # noqa: F401  (registration)

ROOT = Path(__file__).resolve().parents[2]
ID = "hyperloop_env:HyperloopSuspension-v0"
KW = {"scenario": "paper-1000-straight", "track_length_m": 30.0}  # 108 steps


def read_info(info: dict[str, Any], n: int, obs_shape: tuple[int, ...]) -> None:
    """TorchRL's reading of a batched info: each public entry one array of the batch, and
    SAME_STEP's ``final_obs`` an (n,) object array of observations (None where not done)."""
    for key, value in info.items():
        if key.startswith("_") or key in ("final_obs", "final_info"):
            continue
        if isinstance(value, dict):
            raise RuntimeError(f"TorchRL cannot stack the nested info entry {key!r}")
        assert np.shape(value)[:1] == (n,), key
    final = info.get("final_obs")
    if final is not None:
        assert final.shape == (n,) and final.dtype == object, (final.shape, final.dtype)
        for obs in final:
            assert obs is None or (obs.shape == obs_shape and obs.dtype == np.float32)


class FakeTorchRL:
    """``torchrl.envs.GymEnv`` and ``GymWrapper`` as far as the environments meet them."""

    def __init__(self) -> None:
        self.made: list[tuple[str, Any]] = []
        fake = self

        class GymWrapper:
            def __init__(self, env: Any, validate: bool = True) -> None:
                mode = getattr(env, "autoreset_mode", None)
                batched = hasattr(env, "num_envs")
                accepted = (AutoresetMode.SAME_STEP, AutoresetMode.DISABLED)
                if validate and batched and mode not in accepted:  # a wrapped vector env
                    raise RuntimeError(
                        "The auto-reset mode must be one of SAME_STEP or DISABLED (which is "
                        f"preferred). Got autoreset_mode={mode}."
                    )
                self.env, self.batched = env, batched
                self.reads_info = batched and mode != AutoresetMode.DISABLED
                fake.made.append((type(self).__name__, env))

            def rollout(self, steps: int) -> int:
                env = self.env
                env.reset(seed=0)
                for _ in range(steps):
                    *_, te, tr, info = env.step(env.action_space.sample())
                    if self.reads_info:
                        read_info(info, env.num_envs, env.single_observation_space.shape)
                    done = np.asarray(te | tr)
                    if self.batched and done.any() and not self.reads_info:
                        env.reset(options={"reset_mask": done})
                    elif not self.batched and done:
                        env.reset()
                return steps

            def close(self) -> None:
                self.env.close()

        class GymEnv(GymWrapper):
            def __init__(self, env_name: str, num_envs: int = 0, **kwargs: Any) -> None:
                if num_envs > 0:  # TorchRL: AsyncVectorEnv([make] * num_envs), NEXT_STEP
                    make = partial(gym.make, env_name, **kwargs)
                    super().__init__(gym.vector.SyncVectorEnv([make] * num_envs), False)
                else:
                    super().__init__(gym.make(env_name, **kwargs))

        self.GymEnv, self.GymWrapper = GymEnv, GymWrapper

    def install(self, monkeypatch: pytest.MonkeyPatch) -> None:
        envs = types.ModuleType("torchrl.envs")
        envs.GymEnv, envs.GymWrapper = self.GymEnv, self.GymWrapper  # type: ignore[attr-defined]
        root = types.ModuleType("torchrl")
        root.envs = envs  # type: ignore[attr-defined]
        monkeypatch.setitem(sys.modules, "torchrl", root)
        monkeypatch.setitem(sys.modules, "torchrl.envs", envs)


def torchrl_snippet() -> str:
    text = (ROOT / "docs" / "getting-started.md").read_text()
    (code,) = re.findall(r"```python\n# client: torchrl[^\n]*\n(.*?)```", text, re.S)
    return code


def test_the_readme_snippet_covers_the_vector_paths_torchrl_accepts(monkeypatch) -> None:
    """The docs' TorchRL snippet builds one environment, ``GymEnv(..., num_envs=N)``
    and ``GymWrapper`` of the native vector env, each as TorchRL accepts it."""
    fake = FakeTorchRL()
    fake.install(monkeypatch)
    code = compile(torchrl_snippet(), "docs/getting-started.md (torchrl snippet)", "exec")
    exec(code, {"__name__": "__snippet__"})
    kinds = [(name, type(env).__name__) for name, env in fake.made]
    assert ("GymEnv", "SyncVectorEnv") in kinds  # GymEnv(num_envs=N)
    assert ("GymWrapper", "HyperloopSuspensionVectorEnv") in kinds  # the native vector env
    assert any(name == "GymEnv" and not hasattr(env, "num_envs") for name, env in fake.made)


def test_what_torchrl_needs_passed_and_what_fails_without_it(monkeypatch) -> None:
    """Rollouts over several autoresets: the defaults work for one environment; the
    batched paths need ``info="flat"`` and, for the native vector env,
    ``autoreset_mode="Disabled"`` (or ``"SameStep"`` with ``info="flat"``)."""
    fake = FakeTorchRL()
    steps = 250

    def native(**kw: Any) -> Any:
        return gym.make_vec(ID, num_envs=2, vectorization_mode="vector_entry_point", **KW, **kw)

    assert fake.GymEnv(ID, **KW).rollout(steps) == steps
    assert fake.GymEnv(ID, num_envs=2, info="flat", **KW).rollout(steps) == steps
    assert fake.GymWrapper(native(autoreset_mode="Disabled")).rollout(steps) == steps
    flat_same_step = native(autoreset_mode="SameStep", info="flat")
    assert fake.GymWrapper(flat_same_step).rollout(steps) == steps
    with pytest.raises(RuntimeError, match="nested info entry 'reward_terms'"):
        fake.GymEnv(ID, num_envs=2, **KW).rollout(steps)
    with pytest.raises(RuntimeError, match="nested info entry 'reward_terms'"):
        fake.GymWrapper(native(autoreset_mode="SameStep")).rollout(steps)
    with pytest.raises(RuntimeError, match="SAME_STEP or DISABLED"):
        fake.GymWrapper(native())
