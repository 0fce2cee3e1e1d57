"""Stable-Baselines3 glue: the vector-env adapter used for training and the RL controller.

* :class:`GymnasiumVectorToSB3` turns a Gymnasium :class:`~gymnasium.vector.VectorEnv` (for
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
    environments, across autoresets (tests/test_train.py).
  The native env is ~1.4x faster than ``DummyVecEnv`` for rollouts (8 envs); in PPO
  training the gradient updates dilute that to ~1.15x (``benchmarks/bench_train.py``).

* :class:`SB3Controller` is a trained SB3 policy (PPO or SAC) wrapped in the controller
  protocol of :mod:`agents` (``name``, ``reset(seed)``, ``act(obs)``, ``act_batch(obs)``):
  it normalises observations with the ``vecnormalize.pkl`` statistics saved beside
  ``model.zip`` and returns the deterministic action (policy mean), clipped to [-1, 1].
  For the usual MLP policies the forward pass runs in NumPy (a copy of the weights), much
  cheaper per step than ``model.predict`` and batched for free. Importing this module
  registers ``ppo`` and ``sac`` with :func:`agents.make_controller` (shipped agent by default,
  ``make_controller("ppo", path="runs/...")`` for another run).

* :func:`load_shipped` loads the agents shipped in ``agents/shipped/<algo>/``.
"""

from __future__ import annotations

import json
import pickle
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

SHIPPED_DIR = Path(__file__).resolve().parent / "shipped"
MODEL_FILE = "model.zip"
VECNORM_FILE = "vecnormalize.pkl"
ALGOS = ("ppo", "sac")


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
    the stale terminal observation) and warns once; :func:`make_native_vec_env` builds the
    hyperloop env with ``reset_mask`` support, so the fallback is never used for it.

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
        "agents.sb3_agent.make_native_vec_env for the hyperloop env.",
        stacklevel=3,
    )


def make_native_vec_env(num_envs: int, **env_kwargs: Any) -> Any:
    """The native batched ``HyperloopSuspension-v0`` (as ``gymnasium.make_vec(...,
    vectorization_mode="vector_entry_point")``) with ``reset_mask`` support, ready for
    :class:`GymnasiumVectorToSB3`."""
    from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

    return HyperloopSuspensionVectorEnv(num_envs=num_envs, **env_kwargs)


_FINAL_KEYS = frozenset({"final_obs", "_final_obs", "final_info", "_final_info"})


# --------------------------------------------------------------------------------------
# Controller
# --------------------------------------------------------------------------------------


def _load_vecnormalize_stats(path: Path) -> dict[str, Any] | None:
    """Observation-normalisation statistics from a saved ``VecNormalize`` (no env needed)."""
    if not path.exists():
        return None
    with path.open("rb") as f:
        vn = pickle.load(f)  # noqa: S301 - our own file, written by train.py
    if not getattr(vn, "norm_obs", False):
        return None
    return {
        "mean": np.asarray(vn.obs_rms.mean, dtype=np.float64),
        "std": np.sqrt(np.asarray(vn.obs_rms.var, dtype=np.float64) + vn.epsilon),
        "clip": float(vn.clip_obs),
    }


class _NumpyPolicy:
    """Deterministic forward pass of an SB3 MLP actor, copied to NumPy."""

    def __init__(self, layers: list[tuple[np.ndarray, np.ndarray, str]], squash: bool) -> None:
        self.layers = layers
        self.squash = squash

    def __call__(self, x: np.ndarray) -> np.ndarray:
        for w, b, act in self.layers:
            x = x @ w + b
            if act == "tanh":
                x = np.tanh(x)
            elif act == "relu":
                x = np.maximum(x, 0.0)
        return np.tanh(x) if self.squash else x

    @classmethod
    def from_model(cls, model: Any) -> _NumpyPolicy | None:
        import torch.nn as nn

        pol = model.policy
        try:
            if hasattr(pol, "mlp_extractor") and hasattr(pol, "action_net"):  # PPO / A2C
                if pol.features_extractor.__class__.__name__ != "FlattenExtractor":
                    return None
                mods = list(pol.mlp_extractor.policy_net) + [pol.action_net]
                squash = bool(getattr(pol, "squash_output", False))
            elif hasattr(pol, "actor") and hasattr(pol.actor, "latent_pi"):  # SAC / TD3
                mods = list(pol.actor.latent_pi) + [pol.actor.mu]
                squash = True
            else:
                return None
        except (AttributeError, TypeError):
            return None
        layers: list[tuple[np.ndarray, np.ndarray, str]] = []
        for m in mods:
            if isinstance(m, nn.Linear):
                w = m.weight.detach().cpu().numpy().astype(np.float64).T
                b = m.bias.detach().cpu().numpy().astype(np.float64)
                layers.append((w, b, "linear"))
            elif isinstance(m, nn.Tanh | nn.ReLU):
                if not layers or layers[-1][2] != "linear":
                    return None
                w, b, _ = layers[-1]
                layers[-1] = (w, b, "tanh" if isinstance(m, nn.Tanh) else "relu")
            elif isinstance(m, nn.Identity):
                continue
            else:
                return None
        return cls(layers, squash)


class SB3Controller:
    """A trained SB3 agent (``model.zip`` + ``vecnormalize.pkl`` in ``path``) as a controller.

    ``act(obs)`` takes one raw environment observation (shape ``(OBS_SIZE,)``) and returns
    the deterministic action, shape (4,), in [-1, 1]; ``act_batch(obs)`` does the same for a
    batch ``(N, OBS_SIZE) -> (N, 4)``. The controller is stateless (``reset`` only exists for
    the protocol). ``path`` may also be a model file (``model.zip``, a checkpoint
    ``model_<N>_steps.zip`` or ``best/best_model.zip``); the matching VecNormalize statistics
    are found beside it (or pass ``vecnormalize=``).
    """

    def __init__(
        self,
        path: str | Path,
        name: str | None = None,
        algo: str | None = None,
        device: str = "cpu",
        use_numpy: bool = True,
        vecnormalize: str | Path | None = None,
    ) -> None:
        path = Path(path)
        model_path = path if path.suffix == ".zip" else path / MODEL_FILE
        if not model_path.exists():
            raise FileNotFoundError(f"no SB3 model at {model_path}")
        self.path = model_path.parent
        self.algo = (algo or _guess_algo(self.path)).lower()
        if self.algo not in ALGOS:
            raise ValueError(f"algo must be one of {ALGOS}, got {self.algo!r}")
        self.name = name or f"{self.algo}"
        from stable_baselines3 import PPO, SAC

        cls = {"ppo": PPO, "sac": SAC}[self.algo]
        self.model = cls.load(str(model_path), device=device)
        vn_path = Path(vecnormalize) if vecnormalize is not None else _vecnorm_for(model_path)
        if not vn_path.exists():
            import warnings

            warnings.warn(
                f"no VecNormalize statistics at {vn_path}: observations are used unnormalised "
                "(only right for a model trained without VecNormalize)",
                stacklevel=2,
            )
        self.obs_norm = _load_vecnormalize_stats(vn_path)
        self._np_policy = _NumpyPolicy.from_model(self.model) if use_numpy else None
        self.metadata = _read_json(self.path / "training_log.json")

    def reset(self, seed: int | None = None) -> None:
        """Nothing to reset (the policy is memoryless)."""

    def normalize(self, obs: np.ndarray) -> np.ndarray:
        obs = np.asarray(obs, dtype=np.float64)
        if self.obs_norm is None:
            return obs
        n = self.obs_norm
        return np.clip((obs - n["mean"]) / n["std"], -n["clip"], n["clip"])

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        """Deterministic actions for a batch of observations ``(N, OBS_SIZE) -> (N, 4)``."""
        x = self.normalize(np.atleast_2d(obs))
        if self._np_policy is not None:
            a = self._np_policy(x)
        else:
            a, _ = self.model.predict(x.astype(np.float32), deterministic=True)
        return np.clip(np.asarray(a, dtype=np.float64), -1.0, 1.0).astype(np.float32)

    def act(self, obs: np.ndarray) -> np.ndarray:
        """Deterministic action for one observation, shape (4,), in [-1, 1]."""
        return self.act_batch(np.asarray(obs)[None, :])[0]

    __call__ = act

    def __repr__(self) -> str:
        return f"SB3Controller(name={self.name!r}, algo={self.algo!r}, path='{self.path}')"


def _vecnorm_for(model_path: Path) -> Path:
    """``vecnormalize.pkl`` beside ``model.zip``; for a checkpoint ``model_<N>_steps.zip``
    the ``model_vecnormalize_<N>_steps.pkl`` that CheckpointCallback saved with it."""
    m = re.fullmatch(r"(.*)_(\d+)_steps\.zip", model_path.name)
    if m:
        ckpt = model_path.with_name(f"{m.group(1)}_vecnormalize_{m.group(2)}_steps.pkl")
        if ckpt.exists():
            return ckpt
    if model_path.parent.name == "best":  # EvalCallback's best model: stats of the run
        return model_path.parent.parent / VECNORM_FILE
    return model_path.parent / VECNORM_FILE


def _guess_algo(path: Path) -> str:
    meta = _read_json(path / "training_log.json")
    if meta and "algo" in meta:
        return str(meta["algo"])
    low = str(path).lower()
    for algo in ALGOS:
        if algo in Path(low).name or f"{algo}-" in low or f"/{algo}" in low:
            return algo
    return "ppo"


def _read_json(path: Path) -> dict[str, Any] | None:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def shipped_path(algo: str = "ppo") -> Path:
    return SHIPPED_DIR / algo.lower()


def available_shipped() -> list[str]:
    return [a for a in ALGOS if (shipped_path(a) / MODEL_FILE).exists()]


def load_shipped(algo: str = "ppo", **kwargs: Any) -> SB3Controller:
    """The agent shipped in ``agents/shipped/<algo>/`` (``train.py --preset shipped-<algo>``)."""
    path = shipped_path(algo)
    if not (path / MODEL_FILE).exists():
        raise FileNotFoundError(
            f"no shipped {algo!r} agent in {path}; available: {available_shipped()} "
            f"(train one with `python train.py --preset shipped-{algo}`)"
        )
    kwargs.setdefault("name", algo.lower())
    return SB3Controller(path, algo=algo, **kwargs)


# --------------------------------------------------------------------------------------
# registry: make_controller("ppo") / make_controller("ppo", path="runs/...")
# --------------------------------------------------------------------------------------

_CACHE: dict[tuple[str, str], SB3Controller] = {}


def _factory(algo: str) -> Any:
    def make(env_or_params: Any = None, path: str | Path | None = None, **kw: Any) -> SB3Controller:
        """The shipped ``algo`` agent, or the one saved in ``path`` (cached per path; the
        controller is stateless, so one instance serves every episode)."""
        p = Path(path) if path is not None else shipped_path(algo)
        key = (algo, str(p.resolve()))
        if key not in _CACHE:
            if path is None:
                _CACHE[key] = load_shipped(algo, **kw)
            else:
                _CACHE[key] = SB3Controller(p, algo=algo, name=kw.pop("name", algo), **kw)
        return _CACHE[key]

    return make


def register_sb3_controllers() -> None:
    """Register ``ppo`` and ``sac`` with :func:`agents.make_controller` (idempotent)."""
    from agents.registry import register_controller

    for algo in ALGOS:
        register_controller(algo, _factory(algo), overwrite=True)


register_sb3_controllers()
