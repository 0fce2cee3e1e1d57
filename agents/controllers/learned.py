"""Trained agents as controllers: a Stable-Baselines3 policy (PPO or SAC) in the
controller protocol of :mod:`agents.controllers`.

:class:`SB3Controller` normalises observations with the ``vecnormalize.pkl`` statistics
saved beside ``model.zip`` and returns the deterministic action (policy mean), clipped to
[-1, 1]. For the usual MLP policies the forward pass (normalisation, layers, clipping)
runs in compiled, single-threaded kernels on a copy of the weights
(:func:`dense`, :func:`dense_t`), much cheaper per step than ``model.predict`` and batched for free
(``act_batch``); it starts no BLAS threads, which would compete with the simulator's
(:class:`_NumpyPolicy` keeps the same pass in NumPy as the reference: equal up to float64
rounding, and the float32 actions alike). :func:`load_shipped` loads the agents shipped
in ``agents/shipped/<algo>/``; ``make_controller("ppo")`` gives the shipped one,
``make_controller("ppo", path="runs/...")`` another run. Torch and SB3 are imported only
when a model is loaded.
"""

from __future__ import annotations

import json
import pickle
import re
from pathlib import Path
from typing import Any

import numba as nb
import numpy as np

SHIPPED_DIR = Path(__file__).resolve().parents[1] / "shipped"
MODEL_FILE = "model.zip"
VECNORM_FILE = "vecnormalize.pkl"
ALGOS = ("ppo", "sac")


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


@nb.njit(cache=True, nogil=True)
def normalize_obs(obs, mean, std, clip, out):  # pragma: no cover - compiled
    """``out = clip((float64(obs) - mean) / std, -clip, clip)`` row by row (NaN stays NaN,
    as in ``np.clip``): :meth:`SB3Controller.normalize` without the temporaries."""
    for i in range(obs.shape[0]):
        for k in range(obs.shape[1]):
            v = (np.float64(obs[i, k]) - mean[k]) / std[k]
            if v < -clip:
                v = -clip
            elif v > clip:
                v = clip
            out[i, k] = v


@nb.njit(cache=True, nogil=True, fastmath={"contract"})
def dense(x, w, b, out):  # pragma: no cover - compiled
    """``out = x @ w + b`` on one thread (no BLAS): each sum runs over the inputs in order
    (fused multiply-adds where the CPU has them, as the BLAS kernels do), then the bias is
    added; equal to ``x @ w + b`` up to the BLAS kernel's rounding (bit for bit here with
    OpenBLAS's dgemm). Four rows share every pass over a weight row (the inner loop is
    vectorised over the outputs)."""
    n, n_in = x.shape
    n_out = w.shape[1]
    i = 0
    while i + 4 <= n:
        a0, a1, a2, a3 = out[i], out[i + 1], out[i + 2], out[i + 3]
        a0[:] = 0.0
        a1[:] = 0.0
        a2[:] = 0.0
        a3[:] = 0.0
        for k in range(n_in):
            x0, x1, x2, x3 = x[i, k], x[i + 1, k], x[i + 2, k], x[i + 3, k]
            wk = w[k]
            for j in range(n_out):
                wj = wk[j]
                a0[j] += x0 * wj
                a1[j] += x1 * wj
                a2[j] += x2 * wj
                a3[j] += x3 * wj
        i += 4
    while i < n:
        a = out[i]
        a[:] = 0.0
        for k in range(n_in):
            xk = x[i, k]
            wk = w[k]
            for j in range(n_out):
                a[j] += xk * wk[j]
        i += 1
    for r in range(n):
        for j in range(n_out):
            out[r, j] += b[j]


@nb.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def dense_t(x, wt, b, out):  # pragma: no cover - compiled
    """``out = x @ wt.T + b`` on one thread for wide inputs: each output a dot product over
    the inputs, vectorised (so summed in another order than BLAS: equal up to rounding),
    two rows by two outputs at a time; ``wt`` (n_out, n_in) is the transposed weight."""
    n, n_in = x.shape
    n_out = wt.shape[0]
    i = 0
    while i < n:
        two = i + 1 < n
        x0 = x[i]
        x1 = x[i + 1] if two else x[i]
        j = 0
        while j < n_out:
            w0 = wt[j]
            w1 = wt[j + 1] if j + 1 < n_out else wt[j]
            s00 = 0.0
            s01 = 0.0
            s10 = 0.0
            s11 = 0.0
            for k in range(n_in):
                s00 += x0[k] * w0[k]
                s01 += x0[k] * w1[k]
                s10 += x1[k] * w0[k]
                s11 += x1[k] * w1[k]
            out[i, j] = s00 + b[j]
            if two:
                out[i + 1, j] = s10 + b[j]
            if j + 1 < n_out:
                out[i, j + 1] = s01 + b[j + 1]
                if two:
                    out[i + 1, j + 1] = s11 + b[j + 1]
            j += 2
        i += 2


@nb.njit(cache=True, nogil=True)
def clip_to_float32(x, out):  # pragma: no cover - compiled
    """``out = float32(clip(x, -1, 1))`` (NaN stays NaN, as in ``np.clip``)."""
    for i in range(x.shape[0]):
        for j in range(x.shape[1]):
            v = x[i, j]
            if v < -1.0:
                v = -1.0
            elif v > 1.0:
                v = 1.0
            out[i, j] = v


WIDE_INPUT = 64
"""Layers with at least this many inputs run :func:`dense_t` (faster), narrower ones
:func:`dense` (the BLAS order)."""


class _NumpyPolicy:
    """Deterministic forward pass of an SB3 MLP actor, copied to NumPy. :meth:`actions`
    runs it with the compiled single-threaded :func:`dense` / :func:`dense_t` layers
    (NumPy's tanh), calling the object runs the reference NumPy pass (BLAS)."""

    def __init__(self, layers: list[tuple[np.ndarray, np.ndarray, str]], squash: bool) -> None:
        self.layers = layers
        self.squash = squash
        self._dense = [
            (
                w.shape[0] >= WIDE_INPUT,
                np.ascontiguousarray(w.T if w.shape[0] >= WIDE_INPUT else w, dtype=np.float64),
                np.ascontiguousarray(b, dtype=np.float64),
                act,
            )
            for w, b, act in layers
        ]
        self.n_in = int(layers[0][0].shape[0])

    def actions(self, obs: np.ndarray, norm: dict[str, Any] | None) -> np.ndarray:
        """float32 actions in [-1, 1] for raw observations ``obs`` (N, n_in), normalised with
        ``norm`` (VecNormalize statistics, or None): the reference pass up to the rounding of
        the matrix products, without BLAS threads."""
        n = obs.shape[0]
        if norm is None:
            x = np.asarray(obs, dtype=np.float64)
        else:
            if obs.dtype != np.float32 and obs.dtype != np.float64:
                obs = obs.astype(np.float64)
            x = np.empty((n, self.n_in))
            normalize_obs(obs, norm["mean"], norm["std"], norm["clip"], x)
        for wide, w, b, act in self._dense:
            y = np.empty((n, b.shape[0]))
            if wide:
                dense_t(x, w, b, y)
            else:
                dense(x, w, b, y)
            if act == "tanh":
                np.tanh(y, out=y)
            elif act == "relu":
                np.maximum(y, 0.0, out=y)
            x = y
        if self.squash:
            np.tanh(x, out=x)
        out = np.empty(x.shape, dtype=np.float32)
        clip_to_float32(x, out)
        return out

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
        if not layers:
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
        pol = self._np_policy
        if pol is not None:
            x = np.atleast_2d(np.asarray(obs))
            if x.ndim == 2 and x.shape[1] == pol.n_in:
                return pol.actions(x, self.obs_norm)
        x = self.normalize(np.atleast_2d(obs))
        if pol is not None:
            a = pol(x)
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


def shipped_path(name: str = "ppo") -> Path:
    return SHIPPED_DIR / name.lower()


def available_shipped() -> list[str]:
    """The folders of ``agents/shipped/`` holding an agent (``ppo``, ``ppo-guidance``)."""
    if not SHIPPED_DIR.is_dir():
        return []
    return sorted(p.name for p in SHIPPED_DIR.iterdir() if (p / MODEL_FILE).is_file())


def load_shipped(
    name: str = "ppo", *, algo: str | None = None, folder: str | None = None, **kwargs: Any
) -> SB3Controller:
    """The agent shipped in ``agents/shipped/<folder>/`` (default ``name``; ``train.py
    --preset shipped-<name>``), trained with ``algo`` (default: the one its training log
    names). The registry's learned entries give both (:mod:`agents.controllers.registry`)."""
    path = shipped_path(folder or name)
    if not (path / MODEL_FILE).exists():
        raise FileNotFoundError(
            f"no shipped {name!r} agent in {path}; available: {available_shipped()} "
            f"(train one with `python train.py --preset shipped-{name}`)"
        )
    kwargs.setdefault("name", name.lower())
    return SB3Controller(path, algo=algo, **kwargs)


# --------------------------------------------------------------------------------------
# registry factory: make_controller("ppo") / make_controller("ppo", path="runs/...")
# --------------------------------------------------------------------------------------

_CACHE: dict[tuple[str, str], SB3Controller] = {}


def make_learned(
    name: str,
    env_or_params: Any = None,
    path: str | Path | None = None,
    *,
    algo: str | None = None,
    folder: str | None = None,
    **kw: Any,
) -> SB3Controller:
    """The agent ``name`` — shipped in ``agents/shipped/<folder>/`` (default ``name``), or
    saved in ``path`` — trained with ``algo`` (default ``name`` if it is an algorithm, else
    the one its training log names); cached per path (the controller is stateless, so one
    instance serves every episode)."""
    algo = algo or (name if name in ALGOS else None)
    p = Path(path) if path is not None else shipped_path(folder or name)
    key = (name, str(p.resolve()))
    if key not in _CACHE:
        if path is None:
            _CACHE[key] = load_shipped(name, algo=algo, folder=folder, **kw)
        else:
            _CACHE[key] = SB3Controller(p, algo=algo, name=kw.pop("name", name), **kw)
    _check_plant(_CACHE[key], env_or_params)
    return _CACHE[key]


def _check_plant(ctrl: SB3Controller, env_or_params: Any) -> None:
    """A clear error when the agent's action size does not fit the plant's actuator set
    (e.g. a ``levitation+guidance`` agent on a ``levitation`` env)."""
    if env_or_params is None:
        return
    from agents.controllers.base import control_context

    try:
        acts = control_context(env_or_params).actuators
    except (TypeError, ValueError):  # an unknown plant type is reported by the caller
        return
    shape = getattr(getattr(ctrl.model, "action_space", None), "shape", None)
    if shape and int(shape[0]) != acts.size:
        raise ValueError(
            f"controller {ctrl.name!r} acts on {int(shape[0])} currents but the plant has "
            f"{acts.size} (actuators={acts.name!r}); pass the env option actuators= the "
            "agent was trained with"
        )
