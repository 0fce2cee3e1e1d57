"""Stable-Baselines3 glue for training: a Gymnasium ``VectorEnv`` as an SB3 ``VecEnv``.

:class:`GymnasiumVectorToSB3` turns a Gymnasium :class:`~gymnasium.vector.VectorEnv` (for
example the native batched ``HyperloopSuspension-v0`` from ``gymnasium.make_vec(...,
vectorization_mode="vector_entry_point")``) into an SB3
:class:`~stable_baselines3.common.vec_env.VecEnv`. SB3 expects a sub-environment that ends
an episode to be reset *in the same step*, with the last observation of the finished
episode in ``infos[i]["terminal_observation"]`` and ``infos[i]["TimeLimit.truncated"]``
telling a time limit (bootstrap the value) from a real termination (contact). The adapter
supports every Gymnasium autoreset mode:

- ``SAME_STEP``: the vector env already resets in the same step and reports the final
  observation in ``infos["final_obs"]`` (and the final info in ``infos["final_info"]``);
- ``NEXT_STEP`` / ``DISABLED``: the adapter resets the finished sub-environments itself
  with ``reset(options={"reset_mask": done})`` right after the step, so SB3 never sees the
  NEXT_STEP "dummy" transition. ``HyperloopSuspensionVectorEnv`` (NEXT_STEP) implements
  ``reset_mask``; the result is bit-identical to a ``DummyVecEnv`` of single
  environments, across autoresets (tests/agents/training/test_sb3_adapter.py).

The native env is ~1.4x faster than ``DummyVecEnv`` for rollouts (8 envs); in PPO
training the gradient updates dilute that to ~1.15x (``speed/bench_train.py``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

# --------------------------------------------------------------------------------------
# Gymnasium VectorEnv -> SB3 VecEnv
# --------------------------------------------------------------------------------------


def _split_infos(infos: dict[str, Any], n: int) -> list[dict[str, Any]]:
    """Gymnasium vector infos (dict of arrays + ``_key`` masks) -> list of per-env dicts."""
    out: list[dict[str, Any]] = [{} for _ in range(n)]
    for key, value in infos.items():
        if key.startswith("_"):
            continue
        mask = infos.get("_" + key)
        if isinstance(value, dict):  # nested info dict (e.g. reward_terms)
            sub = _split_infos(value, n)
            for i in range(n):
                if (mask is None or mask[i]) and sub[i]:
                    out[i][key] = sub[i]
            continue
        for i in range(n):
            if mask is None or mask[i]:
                try:
                    out[i][key] = value[i]
                except (TypeError, IndexError, KeyError):
                    out[i][key] = value
    return out


def _mode_name(env: Any) -> str:
    mode = getattr(env, "metadata", {}).get("autoreset_mode", "next_step")
    return str(getattr(mode, "value", mode)).lower().replace("_", "")


try:  # the adapter needs SB3; the rest of the module works without it
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv as _VecEnvBase
except ImportError:  # pragma: no cover - SB3 is an optional dependency ("train" extra)
    _VecEnvBase = object  # type: ignore[assignment,misc]


_SYNC_RESET_MASK_CLASSES = ("SyncVectorEnv", "AsyncVectorEnv")


def supports_reset_mask(venv: Any) -> bool:
    """True if ``venv.reset(options={"reset_mask": m})`` resets only the masked envs
    (Gymnasium's Sync/AsyncVectorEnv >= 1.1, or a ``supports_reset_mask`` attribute)."""
    if getattr(venv, "supports_reset_mask", False):
        return True
    return type(venv).__name__ in _SYNC_RESET_MASK_CLASSES


class GymnasiumVectorToSB3(_VecEnvBase):  # type: ignore[misc,valid-type]
    """Expose a Gymnasium ``VectorEnv`` through SB3's ``VecEnv`` API (see module docstring).

    ``full_info=False`` (default, faster) hands SB3 empty info dicts on ordinary steps and
    the full (final) info only for environments whose episode ended, which is all SB3's
    algorithms, ``VecMonitor`` and ``EvalCallback`` read; ``full_info=True`` splits the
    vector info of every step into per-environment dicts.

    A ``NEXT_STEP`` env that cannot reset a subset (no ``reset_mask`` support) falls back to
    passing its "reset step" through (one extra transition with reward 0 per episode, from
    the stale terminal observation) and warns once;
    :func:`agents.training.experiment.make_native_vec_env` builds the hyperloop env with
    ``reset_mask`` support, so the fallback is never used for it.

    >>> import gymnasium as gym
    >>> venv = GymnasiumVectorToSB3(gym.make_vec("Pendulum-v1", num_envs=2))
    >>> venv.reset().shape
    (2, 3)
    """

    def __init__(self, venv: Any, full_info: bool = False) -> None:
        self.venv = venv
        self.full_info = full_info
        self._mode = _mode_name(venv)
        if self._mode not in ("samestep", "nextstep", "disabled"):
            raise ValueError(f"unsupported autoreset mode {self._mode!r}")
        self._masked_reset = supports_reset_mask(venv)
        if self._mode == "disabled" and not self._masked_reset:
            raise ValueError("autoreset mode DISABLED needs a vector env with reset_mask support")
        self._pending = np.zeros(venv.num_envs, dtype=bool)  # NEXT_STEP fallback only
        self._actions: np.ndarray | None = None
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)

    # -- core API ----------------------------------------------------------------------
    def reset(self) -> np.ndarray:
        seeds = self._seeds if any(s is not None for s in self._seeds) else None
        options = self._options[0] if self._options and self._options[0] else None
        obs, infos = self.venv.reset(seed=seeds, options=options)
        self.reset_infos = _split_infos(infos, self.num_envs)
        self._pending[:] = False
        self._reset_seeds()
        self._reset_options()
        return np.asarray(obs)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        obs, rew, term, trunc, infos = self.venv.step(self._actions)
        obs = np.array(obs)  # copy: a native env may hand out its buffer
        rew = np.asarray(rew, dtype=np.float32)
        term = np.asarray(term, dtype=bool)
        trunc = np.asarray(trunc, dtype=bool)
        dones = term | trunc
        n = self.num_envs
        self._pending[:] = False
        if not dones.any():
            info_list = _split_infos(infos, n) if self.full_info else [{} for _ in range(n)]
            return obs, rew, dones, info_list
        done_idx = np.flatnonzero(dones)
        if self._mode == "samestep":
            rest = {k: v for k, v in infos.items() if k not in _FINAL_KEYS}
            info_list = _split_infos(rest, n) if self.full_info else [{} for _ in range(n)]
            final_info = infos.get("final_info")
            finals = _split_infos(final_info, n) if isinstance(final_info, dict) else None
            final_obs = infos["final_obs"]
            for i in done_idx:
                if finals is not None:
                    info_list[i] = finals[i]
                info_list[i]["terminal_observation"] = np.array(final_obs[i])
        else:
            all_infos = _split_infos(infos, n)
            info_list = all_infos if self.full_info else [{} for _ in range(n)]
            for i in done_idx:
                info_list[i] = all_infos[i]
                info_list[i]["terminal_observation"] = obs[i].copy()
            if self._masked_reset:
                reset_obs, reset_infos = self.venv.reset(options={"reset_mask": dones.copy()})
                obs[dones] = np.asarray(reset_obs)[dones]
                r_infos = _split_infos(reset_infos, n)
                for i in done_idx:
                    self.reset_infos[i] = r_infos[i]
            else:  # NEXT_STEP fallback: the env resets these on the next step
                _warn_fallback(self.venv)
                self._pending[dones] = True
        for i in done_idx:
            info_list[i]["TimeLimit.truncated"] = bool(trunc[i] and not term[i])
        return obs, rew, dones, info_list

    def close(self) -> None:
        self.venv.close()

    # -- attributes ----------------------------------------------------------------------
    def _indices(self, indices: Any) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        if isinstance(indices, int):
            return [indices]
        return list(indices)

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        idx = self._indices(indices)
        if hasattr(self.venv, "get_attr") and attr_name != "render_mode":
            try:
                values = self.venv.get_attr(attr_name)
                return [values[i] for i in idx]
            except (AttributeError, NotImplementedError):
                pass
        return [getattr(self.venv, attr_name)] * len(idx)

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        if hasattr(self.venv, "set_attr"):
            self.venv.set_attr(attr_name, value)
        else:
            setattr(self.venv, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any
    ) -> list[Any]:
        idx = self._indices(indices)
        if hasattr(self.venv, "call"):
            values = self.venv.call(method_name, *method_args, **method_kwargs)
            return [values[i] for i in idx]
        result = getattr(self.venv, method_name)(*method_args, **method_kwargs)
        return [result] * len(idx)

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False] * len(self._indices(indices))

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [None] * self.num_envs


_WARNED: set[int] = set()


def _warn_fallback(venv: Any) -> None:
    if id(venv) in _WARNED:
        return
    _WARNED.add(id(venv))
    import warnings

    warnings.warn(
        f"{type(venv).__name__} uses NEXT_STEP autoreset without reset_mask support: each "
        "episode start is preceded by one dummy transition (reward 0). Use "
        "agents.training.experiment.make_native_vec_env for the hyperloop env.",
        stacklevel=3,
    )


_FINAL_KEYS = frozenset({"final_obs", "_final_obs", "final_info", "_final_info"})
