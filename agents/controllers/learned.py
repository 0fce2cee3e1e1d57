"""Trained agents as controllers: a Stable-Baselines3 policy (PPO or SAC) in the
controller protocol of :mod:`agents.controllers`.

:class:`SB3Controller` normalises observations with the ``vecnormalize.pkl`` statistics
saved beside ``model.zip`` and returns the deterministic action (policy mean), clipped to
[-1, 1]. For the usual MLP policies the forward pass (normalisation, layers, clipping)
runs in one compiled, single-threaded call on a float32 copy of the weights
(:func:`mlp_forward`): the precision the network was trained in, equal to torch's pass up
to float32 rounding, a row's action independent of the rest of the batch, much cheaper per
step than ``model.predict`` and batched for free (``act_batch``); it starts no BLAS
threads, which would compete with the simulator's (:class:`_NumpyPolicy` keeps a float64
NumPy pass as the reference). :func:`load_shipped` loads the agents shipped
in ``agents/shipped/<algo>/``; ``make_controller("ppo")`` gives the shipped one,
``make_controller("ppo", path="runs/...")`` another run. Torch and SB3 are imported only
when a model is loaded. A model file that is no saved model (not a zip, an empty zip …),
statistics that do not load and an agent whose actions do not fit the plant are a
:class:`~agents.controllers.base.ControllerError` naming the controller and the file.
"""

from __future__ import annotations

import copy
import json
import math
import pickle
import re
import zipfile
from pathlib import Path
from typing import Any

import numba as nb
import numpy as np

from agents.controllers.base import ControllerError, ControllerFileError
from hyperloop_env.observation import MemorySpec, ObservationSpec, observation_spec
from hyperloop_env.physics.arrays import aligned_copy, aligned_zeros, is_float
from hyperloop_env.physics.entry import compiled_entry
from hyperloop_env.physics.params import ModelParams

SHIPPED_DIR = Path(__file__).resolve().parents[1] / "shipped"
MODEL_FILE = "model.zip"
VECNORM_FILE = "vecnormalize.pkl"
ALGOS = ("ppo", "sac")


# --------------------------------------------------------------------------------------
# Controller
# --------------------------------------------------------------------------------------


def _load_vecnormalize_stats(path: Path, label: str = "") -> dict[str, Any] | None:
    """Observation-normalisation statistics from a saved ``VecNormalize`` (no env needed);
    a file that does not load is a :class:`ControllerError` naming it (and the controller
    ``label``)."""
    if not path.exists():
        return None
    try:
        with path.open("rb") as f:
            vn = pickle.load(f)  # noqa: S301 - our own file, written by train.py
        if not getattr(vn, "norm_obs", False):
            return None
        var, eps = vn.obs_rms.var, vn.epsilon
    except Exception as exc:  # truncated, not a pickle, another object …
        who = f"controller {label!r}: " if label else ""
        raise ControllerError(
            f"{who}cannot read the observation statistics {path} "
            f"(a VecNormalize saved by train.py): {type(exc).__name__}: {exc}"
        ) from exc
    std = np.sqrt(np.asarray(var, dtype=np.float64) + eps)
    return {
        "mean": np.asarray(vn.obs_rms.mean, dtype=np.float64),
        "std": std,
        "inv_std": 1.0 / std,
        "clip": float(vn.clip_obs),
    }


# float32 tanh: the rational approximation of Eigen's ``ptanh_float`` (numerator of degree
# 13, denominator of degree 6 in x, argument clamped to ±7.905 where tanh is 1 in float32);
# within a few float32 ulps of tanh (tests/agents/controllers/test_learned_kernels.py), like
# the SIMD tanh of torch and NumPy, and vectorisable where libm's tanhf is not.
_TANH_CLAMP = np.float32(7.90531110763549805)
_TANH_P = tuple(
    np.float32(c)
    for c in (
        -2.76076847742355e-16,
        2.00018790482477e-13,
        -8.60467152213735e-11,
        5.12229709037114e-08,
        1.48572235717979e-05,
        6.37261928875436e-04,
        4.89352455891786e-03,
    )
)
_TANH_Q = tuple(
    np.float32(c)
    for c in (
        1.19825839466702e-06,
        1.18534705686654e-04,
        2.26843463243900e-03,
        4.89352518554385e-03,
    )
)
_P0, _P1, _P2, _P3, _P4, _P5, _P6 = _TANH_P
_Q0, _Q1, _Q2, _Q3 = _TANH_Q

ACT_LINEAR, ACT_TANH, ACT_RELU = 0, 1, 2
"""Activation codes of :func:`mlp_forward`."""


@nb.njit(inline="always", error_model="numpy")
def tanh32(x):  # pragma: no cover - compiled
    """tanh of a float32 (NaN stays NaN), see ``_TANH_P``."""
    x = _TANH_CLAMP if x > _TANH_CLAMP else x
    x = -_TANH_CLAMP if x < -_TANH_CLAMP else x
    x2 = x * x
    p = x2 * _P0 + _P1
    p = p * x2 + _P2
    p = p * x2 + _P3
    p = p * x2 + _P4
    p = p * x2 + _P5
    p = p * x2 + _P6
    p = p * x
    q = x2 * _Q0 + _Q1
    q = q * x2 + _Q2
    q = q * x2 + _Q3
    return p / q


@nb.njit(cache=True, nogil=True, error_model="numpy")
def tanh32_array(x, out):  # pragma: no cover - compiled
    """``out[i] = tanh32(x[i])`` (for tests and reference)."""
    for i in range(x.shape[0]):
        out[i] = tanh32(x[i])


@nb.njit(cache=True, nogil=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def dense_t32(xt, w, yt):  # pragma: no cover - compiled
    """``yt = (xt.T @ w).T`` in float32 on one thread, rows in the inner loop (``xt`` (n_in,
    N), ``w`` (n_in, n_out), ``yt`` (n_out, N)): each output is summed over the inputs in
    order, one fused multiply-add per input, so a row's result does not depend on the other
    rows of the batch (a batch equals its rows one at a time, bit for bit). Four outputs
    and four inputs share each pass over the rows (an output is loaded and stored once per
    four inputs; the same sums, input by input)."""
    n_in, n = xt.shape
    n_out = w.shape[1]
    j = 0
    while j + 4 <= n_out:
        y0, y1, y2, y3 = yt[j], yt[j + 1], yt[j + 2], yt[j + 3]
        x = xt[0]
        a0, a1, a2, a3 = w[0, j], w[0, j + 1], w[0, j + 2], w[0, j + 3]
        for i in range(n):
            xi = x[i]
            y0[i] = xi * a0
            y1[i] = xi * a1
            y2[i] = xi * a2
            y3[i] = xi * a3
        k = 1
        while k + 4 <= n_in:
            x, z, u, v = xt[k], xt[k + 1], xt[k + 2], xt[k + 3]
            a0, a1, a2, a3 = w[k, j], w[k, j + 1], w[k, j + 2], w[k, j + 3]
            b0, b1, b2, b3 = w[k + 1, j], w[k + 1, j + 1], w[k + 1, j + 2], w[k + 1, j + 3]
            c0, c1, c2, c3 = w[k + 2, j], w[k + 2, j + 1], w[k + 2, j + 2], w[k + 2, j + 3]
            d0, d1, d2, d3 = w[k + 3, j], w[k + 3, j + 1], w[k + 3, j + 2], w[k + 3, j + 3]
            for i in range(n):
                xi, zi, ui, vi = x[i], z[i], u[i], v[i]
                y0[i] = (((y0[i] + xi * a0) + zi * b0) + ui * c0) + vi * d0
                y1[i] = (((y1[i] + xi * a1) + zi * b1) + ui * c1) + vi * d1
                y2[i] = (((y2[i] + xi * a2) + zi * b2) + ui * c2) + vi * d2
                y3[i] = (((y3[i] + xi * a3) + zi * b3) + ui * c3) + vi * d3
            k += 4
        while k < n_in:
            x = xt[k]
            a0, a1, a2, a3 = w[k, j], w[k, j + 1], w[k, j + 2], w[k, j + 3]
            for i in range(n):
                xi = x[i]
                y0[i] = y0[i] + xi * a0
                y1[i] = y1[i] + xi * a1
                y2[i] = y2[i] + xi * a2
                y3[i] = y3[i] + xi * a3
            k += 1
        j += 4
    while j < n_out:
        y = yt[j]
        x = xt[0]
        a0 = w[0, j]
        for i in range(n):
            y[i] = x[i] * a0
        for k in range(1, n_in):
            x = xt[k]
            a0 = w[k, j]
            for i in range(n):
                y[i] = y[i] + x[i] * a0
        j += 1


@nb.njit(cache=True, nogil=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def mlp_forward(obs, mean, inv_std, clip, params, layout, squash, scratch, out):  # pragma: no cover
    """The deterministic actions of an MLP actor for the raw observations ``obs`` (N, n_in),
    in one call: ``x = float32(clip((float64(obs) − mean)·inv_std, ±clip))`` (VecNormalize's
    float64 normalisation, ``inv_std = 1/sqrt(var + ε)``, then the policy's float32), for each
    layer ``x = act(x @ W + b)`` in float32 (:func:`dense_t32`; tanh: :func:`tanh32`), then
    tanh if ``squash`` and ``out = clip(x, −1, 1)``. NaN propagates. The layers are packed:
    ``params`` (float32) holds each layer's W (n_in, n_out) row-major then b, ``layout[L] =
    (offset, n_in, n_out, activation code)``; ``scratch`` (2, max width, N) holds the layers'
    inputs and outputs, transposed (the normalised inputs pass row-major through its second
    half, then transposed into the first: two passes, faster than one that normalises and
    transposes at once, writing every value a whole row apart)."""
    n, m = obs.shape
    xt = scratch[0, :m]
    rows = scratch[1, :m].reshape((n, m))  # free until the first layer's output
    for i in range(n):  # row by row, vectorised over the inputs
        r = obs[i]
        x = rows[i]
        for k in range(m):
            v = (np.float64(r[k]) - mean[k]) * inv_std[k]
            v = -clip if v < -clip else v
            v = clip if v > clip else v
            x[k] = np.float32(v)
    for k in range(m):  # transposed: the rows innermost
        x = xt[k]
        for i in range(n):
            x[i] = rows[i, k]
    for layer in range(layout.shape[0]):
        off, n_in, n_out, act = (
            layout[layer, 0],
            layout[layer, 1],
            layout[layer, 2],
            layout[layer, 3],
        )
        w = params[off : off + n_in * n_out].reshape((n_in, n_out))
        b = params[off + n_in * n_out : off + n_in * n_out + n_out]
        yt = scratch[(layer + 1) % 2, :n_out]
        dense_t32(xt, w, yt)
        for j in range(n_out):
            y = yt[j]
            bj = b[j]
            if act == 1:
                for i in range(n):
                    y[i] = tanh32(y[i] + bj)
            elif act == 2:
                for i in range(n):
                    v = y[i] + bj
                    y[i] = v if v > 0 or v != v else np.float32(0.0)
            else:
                for i in range(n):
                    y[i] = y[i] + bj
        xt = yt
    for i in range(n):
        for j in range(out.shape[1]):
            v = xt[j, i]
            if squash:
                v = tanh32(v)
            v = np.float32(-1.0) if v < -1.0 else v
            v = np.float32(1.0) if v > 1.0 else v
            out[i, j] = v


class _NumpyPolicy:
    """Deterministic forward pass of an SB3 MLP actor, copied out of torch. :meth:`actions`
    runs it compiled in float32, the precision the network was trained in
    (:func:`mlp_forward`: one call, one thread, no BLAS; equal to torch's forward pass up to
    float32 rounding); calling the object runs the float64 NumPy reference pass."""

    def __init__(self, layers: list[tuple[np.ndarray, np.ndarray, str]], squash: bool) -> None:
        self.layers = layers
        self.squash = squash
        codes = {"linear": ACT_LINEAR, "tanh": ACT_TANH, "relu": ACT_RELU}
        parts, rows, off = [], [], 0
        for w, b, a in layers:
            n_in, n_out = w.shape
            parts += [np.asarray(w, dtype=np.float32).ravel(), np.asarray(b, dtype=np.float32)]
            rows.append((off, n_in, n_out, codes[a]))
            off += n_in * n_out + n_out
        self._params = aligned_copy(np.concatenate(parts))  # on a cache line
        self._layout = np.array(rows, dtype=np.int64)
        self.n_in = int(layers[0][0].shape[0])
        self.n_out = int(layers[-1][0].shape[1])
        self._width = max([self.n_in] + [int(w.shape[1]) for w, _, _ in layers])
        self._scratch = np.empty((2, self._width, 0), dtype=np.float32)
        self._no_norm = {
            "mean": np.zeros(self.n_in),
            "inv_std": np.ones(self.n_in),
            "clip": math.inf,
        }
        self._entry: tuple[Any, ...] = (None, None, None, None)  # _bind's, and what it is for

    def __getstate__(self) -> dict[str, Any]:
        return {**self.__dict__, "_entry": (None, None, None, None)}  # bound anew

    def _bind(self, dt: np.dtype, mean: np.ndarray, inv_std: np.ndarray) -> tuple[Any, ...]:
        """:func:`mlp_forward` for C-ordered observations of dtype ``dt`` and these
        normalisation arrays (as they are typed), called without numba's type dispatch
        (:mod:`hyperloop_env.physics.entry`); kept with what it is for: ``(entry, dt.type,
        mean, inv_std)``. C-ordered, not any layout: the normalisation pass over a row
        vectorises only over contiguous inputs (read through strides, the pass of 64 rows of
        ``ppo`` took 2 µs longer, more than the dispatch saves)."""
        for name, v in (("mean", mean), ("inv_std", inv_std)):
            if not isinstance(v, np.ndarray) or v.dtype.kind != "f" or v.shape != (self.n_in,):
                raise ValueError(
                    f"observation statistics: {name} must be a float array of shape "
                    f"({self.n_in},), got {getattr(v, 'dtype', type(v).__name__)} "
                    f"{np.shape(v)}"
                )
        f = compiled_entry(
            mlp_forward,
            nb.from_dtype(dt)[:, ::1],
            mean,
            inv_std,
            nb.float64,
            self._params,
            self._layout,
            nb.boolean,
            nb.float32[:, :, ::1],
            nb.float32[:, ::1],
        )
        self._entry = (f, dt.type, mean, inv_std)
        return self._entry

    def actions(self, obs: np.ndarray, norm: dict[str, Any] | None) -> np.ndarray:
        """float32 actions in [-1, 1] for raw observations ``obs`` (N, n_in), normalised with
        ``norm`` (VecNormalize statistics, or None) — :func:`mlp_forward`."""
        if obs.ndim != 2 or obs.shape[1] != self.n_in:
            raise ValueError(f"obs must have shape (N, {self.n_in}), got {obs.shape}")
        n = obs.shape[0]
        dt = obs.dtype
        if not is_float(dt):
            obs = obs.astype(np.float64)  # (any layout: the compiled pass takes strides)
        norm = self._no_norm if norm is None else norm
        if self._scratch.shape[2] != n:
            self._scratch = aligned_zeros((2, self._width, n), np.float32)
        out = np.empty((n, self.n_out), dtype=np.float32)
        mean, inv_std = norm["mean"], norm["inv_std"]
        e = self._entry
        if e[1] is not obs.dtype.type or e[2] is not mean or e[3] is not inv_std:
            e = self._bind(obs.dtype, mean, inv_std)
        # a C-ordered batch (the environments'): the entry; another layout: numba's dispatch
        f = e[0] if obs.flags.c_contiguous else mlp_forward
        f(
            obs,
            mean,
            inv_std,
            float(norm["clip"]),
            self._params,
            self._layout,
            self.squash,
            self._scratch,
            out,
        )  # = mlp_forward(obs, mean, inv_std, …)
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
    batch ``(N, OBS_SIZE) -> (N, 4)``. ``path`` may also be a model file (``model.zip``, a
    checkpoint ``model_<N>_steps.zip`` or ``best/best_model.zip``); the matching VecNormalize
    statistics are found beside it (or pass ``vecnormalize=``).

    An agent trained with observation memory (the env keywords ``observation_history`` /
    ``observation_front_preview`` in its training log's ``env_kwargs``: ``memory``) takes
    either the full observations of an env with the same options (stateless), or plain
    ones, from which it builds the memory blocks itself with the env's own code
    (:class:`hyperloop_env.observation_memory.ObservationMemory`): then it keeps state per
    row — ``reset()`` / ``reset_batch(mask)`` start episodes anew, and ``act`` and
    ``act_batch`` keep separate states. Without memory the controller is stateless.
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
        label = name or str(model_path)
        if not model_path.exists():
            raise ControllerFileError(
                f"controller {label!r}: no Stable-Baselines3 model at {model_path}"
            )
        self.path = model_path.parent
        self.algo = (algo or _guess_algo(self.path)).lower()
        if self.algo not in ALGOS:
            raise ControllerError(
                f"controller {label!r}: algo must be one of {ALGOS}, got {self.algo!r}"
            )
        self.name = name or f"{self.algo}"
        self.model = load_model(self.algo, model_path, label, device)
        vn_path = Path(vecnormalize) if vecnormalize is not None else _vecnorm_for(model_path)
        if not vn_path.exists():
            import warnings

            warnings.warn(
                f"no VecNormalize statistics at {vn_path}: observations are used unnormalised "
                "(only right for a model trained without VecNormalize)",
                stacklevel=2,
            )
        self.obs_norm = _load_vecnormalize_stats(vn_path, label)
        # a privileged critic's policy (agents.training.privileged_policy): the actor takes
        # the observation's first actor_inputs entries, the simulator's state came after
        self.actor_inputs: int | None = getattr(self.model.policy, "actor_inputs", None)
        if self.actor_inputs is not None and self.obs_norm is not None:
            self.obs_norm = {
                k: v[: self.actor_inputs] if isinstance(v, np.ndarray) else v
                for k, v in self.obs_norm.items()
            }
        self._np_policy = _NumpyPolicy.from_model(self.model) if use_numpy else None
        self.metadata = _read_json(_training_log(model_path))
        self.observation = _trained_observation(self.metadata, self.model, model_path)
        self.memory = self.observation.memory
        nominal = ModelParams()  # make_learned passes the plant's instead
        self._set_geometry(nominal.vehicle.set_spacing_m, nominal.simulation.control_dt_s)

    def _set_geometry(self, set_spacing_m: float, dt_s: float) -> None:
        """Set spacing [m] and control interval [s] the memory blocks are built with (the
        nominal model's: :func:`make_learned` passes the plant's)."""
        self._geometry = (float(set_spacing_m), float(dt_s))
        self._mem: dict[str, Any] = {}  # "single" / "batch" -> ObservationMemory
        self._pending: np.ndarray | None = None  # rows of act_batch to start anew

    def fresh(self) -> SB3Controller:
        """A controller sharing this one's policy with its own (empty) memory state."""
        c = copy.copy(self)
        c._set_geometry(*self._geometry)
        return c

    def reset(self, seed: int | None = None) -> None:
        """Start anew (the memory blocks, if the agent has memory; else nothing)."""
        self._mem = {}
        self._pending = None

    def reset_batch(self, mask: np.ndarray) -> None:
        """Start the rows ``mask`` of ``act_batch`` anew (their next observation is a reset
        observation)."""
        m = np.asarray(mask, dtype=np.bool_)
        if not self.memory.active:  # no state between steps: nothing to start anew
            return
        same = self._pending is not None and self._pending.shape == m.shape
        self._pending = (self._pending | m) if same else m.copy()  # a new size: a new batch

    def _with_memory(self, obs: np.ndarray, which: str) -> np.ndarray:
        """Full observations (memory blocks appended) for plain ones, rows in order."""
        from hyperloop_env.observation_memory import ObservationMemory

        n = obs.shape[0]
        mem = self._mem.get(which)
        pending = self._pending if which == "batch" else None
        if mem is None or mem.n_rows != n:
            mem = ObservationMemory(self.observation, n, *self._geometry)
            self._mem[which] = mem
            out = mem.start(obs)
        elif pending is not None and pending.any():
            if pending.shape != (n,):
                raise ValueError(
                    f"reset_batch mask has shape {pending.shape}, act_batch got {n} rows"
                )
            mem.push(obs, ~pending)
            out = mem.start(obs, pending)
        else:
            out = mem.push(obs)
        if which == "batch":
            self._pending = None
        return out

    def normalize(self, obs: np.ndarray) -> np.ndarray:
        obs = np.asarray(obs, dtype=np.float64)
        if self.obs_norm is None:
            return obs
        n = self.obs_norm
        return np.clip((obs - n["mean"]) / n["std"], -n["clip"], n["clip"])

    def act_batch(self, obs: np.ndarray, _which: str = "batch") -> np.ndarray:
        """Deterministic actions for a batch of observations ``(N, OBS_SIZE) -> (N, 4)``."""
        if self.memory.active:
            x = np.atleast_2d(np.asarray(obs, dtype=np.float32))
            if x.ndim == 2 and x.shape[1] == self.observation.base_size:
                obs = self._with_memory(x, _which)
            elif x.ndim != 2 or x.shape[1] != self.observation.size:
                raise ValueError(
                    f"obs must have {self.observation.base_size} entries (plain) or "
                    f"{self.observation.size} (with the memory blocks of {self.memory}), "
                    f"got shape {np.shape(obs)}"
                )
        pol = self._np_policy
        if pol is not None:
            x = obs if type(obs) is np.ndarray else np.asarray(obs)  # noqa: E721 - hot path
            if x.ndim == 1:
                x = x[None, :]
            if x.ndim == 2 and x.shape[1] == pol.n_in:
                return pol.actions(x, self.obs_norm)
        x = self.normalize(np.atleast_2d(obs))
        if pol is not None:
            a = pol(x)
        else:
            if self.actor_inputs is not None:  # the actor ignores the privileged entries
                pad = self.model.observation_space.shape[0] - x.shape[1]
                x = np.hstack([x, np.zeros((x.shape[0], pad))])
            a, _ = self.model.predict(x.astype(np.float32), deterministic=True)
        return np.clip(np.asarray(a, dtype=np.float64), -1.0, 1.0).astype(np.float32)

    def act(self, obs: np.ndarray) -> np.ndarray:
        """Deterministic action for one observation, shape (4,), in [-1, 1]."""
        return self.act_batch(np.asarray(obs)[None, :], "single")[0]

    __call__ = act

    def __repr__(self) -> str:
        return f"SB3Controller(name={self.name!r}, algo={self.algo!r}, path='{self.path}')"


def model_file_problem(model_path: Path) -> str | None:
    """Why ``model_path`` is no saved Stable-Baselines3 model (one is a zip holding a
    ``data`` entry), or None."""
    if not zipfile.is_zipfile(model_path):
        return "is not a zip file (a saved Stable-Baselines3 model is one)"
    try:
        with zipfile.ZipFile(model_path) as z:
            names = z.namelist()
    except (zipfile.BadZipFile, OSError) as exc:
        return f"is not a readable zip file ({exc})"
    if "data" not in names:
        what = "is empty" if not names else f"holds only {', '.join(names[:5])}"
        return f"holds no saved model (the zip {what}; Stable-Baselines3's model.save writes one)"
    return None


def load_model(algo: str, model_path: Path, label: str, device: str = "cpu") -> Any:
    """The Stable-Baselines3 model (``algo``) saved in ``model_path``; a file that is none,
    or does not load, is a :class:`ControllerError` naming the controller ``label`` and
    the file."""
    problem = model_file_problem(model_path)
    if problem:
        raise ControllerError(f"controller {label!r}: the model file {model_path} {problem}")
    from stable_baselines3 import PPO, SAC

    cls = {"ppo": PPO, "sac": SAC}[algo]
    try:
        return cls.load(str(model_path), device=device)
    except Exception as exc:  # written by another version, truncated inside, another algo …
        raise ControllerError(
            f"controller {label!r}: cannot load the {algo.upper()} model {model_path}: "
            f"{type(exc).__name__}: {exc}"
        ) from exc


def _training_log(model_path: Path) -> Path:
    """The training log of the run a model file belongs to (a checkpoint's or the best
    model's run folder is the parent of theirs)."""
    for d in (model_path.parent, model_path.parent.parent):
        if (d / "training_log.json").is_file():
            return d / "training_log.json"
    return model_path.parent / "training_log.json"


def _trained_observation(
    metadata: dict[str, Any] | None, model: Any, model_path: Path
) -> ObservationSpec:
    """The observation layout the agent was trained on: the actuator set and memory
    options of its training log's ``env_kwargs``, checked against the policy's input."""
    kw = dict((metadata or {}).get("env_kwargs") or {})
    memory = MemorySpec(
        history=kw.get("observation_history", 1),
        front_preview=kw.get("observation_front_preview", False),
    )
    spec = observation_spec(kw.get("actuators", "levitation"), memory)
    shape = getattr(getattr(model, "observation_space", None), "shape", None)
    actor_inputs = getattr(getattr(model, "policy", None), "actor_inputs", None)
    if shape and actor_inputs is not None:  # a privileged critic's: the actor's share
        shape = (int(actor_inputs),)
    if shape and int(shape[0]) != spec.size:
        plain = observation_spec(spec.actuators)
        if metadata is None and int(shape[0]) == plain.size:
            return plain
        raise ValueError(
            f"{model_path}: the policy takes {int(shape[0])} observation entries but its "
            f"training log's env_kwargs give {spec.size} ({spec}); is the training log "
            "of another run?"
        )
    return spec


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
    the one its training log names); the loaded model is cached per path (a stateless
    controller serves every caller; one with observation memory is a fresh copy per call,
    sharing the policy)."""
    algo = algo or (name if name in ALGOS else None)
    p = Path(path) if path is not None else shipped_path(folder or name)
    key = (name, str(p.resolve()))
    if key not in _CACHE:
        if path is None:
            _CACHE[key] = load_shipped(name, algo=algo, folder=folder, **kw)
        else:
            _CACHE[key] = SB3Controller(p, algo=algo, name=kw.pop("name", name), **kw)
    ctrl = _CACHE[key]
    _check_plant(ctrl, env_or_params)
    if ctrl.memory.active:  # stateful: its own memory, built with the plant's geometry
        ctrl = ctrl.fresh()
        if env_or_params is not None:
            from agents.controllers.base import control_context

            params = control_context(env_or_params).params
            ctrl._set_geometry(params.vehicle.set_spacing_m, params.simulation.control_dt_s)
    return ctrl


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
        trained = ctrl.observation.actuators.name
        raise ControllerError(
            f"controller {ctrl.name!r} ({ctrl.path / MODEL_FILE}) acts on {int(shape[0])} "
            f"currents but the plant has {acts.size} (actuators={acts.name!r}); run it with "
            f"the actuators it was trained with, {trained!r} (--actuators {trained} on the "
            "command line, the env option actuators= in Python)"
        )
