"""Residual controllers: a classical law plus a bounded learned correction.

The action is the base law's (``lqr-preview`` on the plant's actuator set, or any other
registry controller) plus a correction ``c ∈ [-1, 1]^n`` from a trained policy, scaled by
``scale`` (dimensionless, in action units: ``scale = 0.1`` lets the policy move each coil
current by at most 10 % of the action range's half-width, i.e. ``0.1·action_scale·I0``)::

    a = clip(a_base(obs) + scale·c(obs), −1, 1)       (float32, :func:`apply_correction`)

Where ``scale·c`` is zero the base's action is returned unchanged, bit for bit (no clipping,
no sign change of a zero): at zero correction a :class:`ResidualController` flies as its
base law (``tests/agents/controllers/test_residual_controller.py``). The base law keeps
its own state (filter, integrator, delay line) and sees every observation; the policy sees
the same observation. Training: :mod:`agents.training.residual` (the same :func:`apply_correction`
inside an environment wrapper, so the policy is trained on the actions it will fly).

A trained residual agent is a run directory of ``train.py`` (``model.zip``,
``vecnormalize.pkl``, ``training_log.json`` whose ``residual`` record names the base law,
its options and the scale): :func:`make_residual` builds the controller from it
(``make_controller("agents.controllers.residual:make_residual", env, path=run_dir)``),
:func:`ppo_residual` / :func:`ppo_residual_guidance` from the shipped folders
``agents/shipped/ppo-residual[-guidance]/``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numba as nb
import numpy as np

from agents.controllers.base import ControllerError

DEFAULT_BASE = "lqr-preview"
"""The base law a residual agent corrects unless its record names another."""
RESIDUAL_KEY = "residual"
"""The key of the residual record in a run's ``training_log.json`` (and a preset)."""


def check_scale(scale: Any) -> float:
    """``scale`` as a float; ``ValueError`` unless a finite number in [0, 2]."""
    ok = isinstance(scale, int | float) and not isinstance(scale, bool)
    if not ok or not math.isfinite(scale) or not 0.0 <= scale <= 2.0:
        raise ValueError(f"residual scale must be a number in [0, 2], got {scale!r}")
    return float(scale)


def apply_correction(base: np.ndarray, correction: np.ndarray, scale: float) -> np.ndarray:
    """``clip(base + scale·correction, −1, 1)`` in float32, elementwise; where
    ``scale·correction`` is zero the entry is ``base``'s, bit for bit (``base`` (…, n), the
    base law's actions; ``correction`` of the same shape, a policy's output in [-1, 1]; the
    two broadcast as NumPy's). One compiled pass (:func:`corrected`)."""
    b = np.asarray(base, dtype=np.float32)
    c = np.asarray(correction, dtype=np.float32)
    if b.shape != c.shape:
        b, c = np.broadcast_arrays(b, c)
    out = np.empty(b.shape, dtype=np.float32)
    corrected(
        np.ascontiguousarray(b).reshape(-1),
        np.ascontiguousarray(c).reshape(-1),
        np.float32(scale),
        out.reshape(-1),
    )
    return out


@nb.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def corrected(b, c, s, out):  # pragma: no cover - compiled
    """``out[i] = b[i]`` where ``d = s·c[i]`` is zero, else ``clip(b[i] + d, −1, 1)``, all in
    float32 (the clip as NumPy's ``np.clip``: NaN stays NaN)."""
    for i in range(b.shape[0]):
        d = s * c[i]
        if d == 0:
            out[i] = b[i]
        else:
            v = b[i] + d
            v = np.float32(-1.0) if v < -1.0 else v
            out[i] = np.float32(1.0) if v > 1.0 else v


class ZeroPolicy:
    """A correction policy that always returns zeros (``n_actions`` of them): the residual
    controller of a base law before any training, and the reference of the bit-for-bit
    test."""

    name = "zero"

    def __init__(self, n_actions: int) -> None:
        self.n_actions = int(n_actions)

    def reset(self, seed: int | None = None) -> None:
        pass

    def reset_batch(self, mask: np.ndarray) -> None:
        pass

    def act(self, obs: np.ndarray) -> np.ndarray:
        return np.zeros(self.n_actions, dtype=np.float32)

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        return np.zeros((np.shape(obs)[0], self.n_actions), dtype=np.float32)


class ResidualController:
    """``base`` (a controller with ``act``/``act_batch``/``reset``/``reset_batch``) plus
    ``scale`` times the output of ``policy`` (a controller of the same actions, e.g. an
    :class:`~agents.controllers.learned.SB3Controller`): :func:`apply_correction`. ``act``
    and ``act_batch`` run the base's and the policy's ``act`` / ``act_batch`` (separate
    states, as theirs); ``reset`` / ``reset_batch`` reset both."""

    def __init__(self, base: Any, policy: Any, scale: float, name: str | None = None) -> None:
        self.base = base
        self.policy = policy
        self.scale = check_scale(scale)
        self.name = name or f"{getattr(base, 'name', 'base')}+residual"

    def reset(self, seed: int | None = None) -> None:
        """Start an episode (the base's and the policy's state of :meth:`act`)."""
        self.base.reset(seed=seed)
        self.policy.reset(seed=seed)

    def reset_batch(self, mask: np.ndarray) -> None:
        """Start the rows ``mask`` of :meth:`act_batch` anew (base and policy)."""
        for part in (self.base, self.policy):
            fn = getattr(part, "reset_batch", None)
            if callable(fn):
                fn(mask)

    def act(self, obs: np.ndarray) -> np.ndarray:
        """The action for one observation, ``(obs_size,) -> (n,)`` float32."""
        return apply_correction(self.base.act(obs), self.policy.act(obs), self.scale)

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        """Actions for N vehicles, ``(N, obs_size) -> (N, n)`` float32."""
        return apply_correction(self.base.act_batch(obs), self.policy.act_batch(obs), self.scale)

    def __repr__(self) -> str:
        return (
            f"ResidualController(name={self.name!r}, base={self.base!r}, "
            f"policy={self.policy!r}, scale={self.scale})"
        )


def residual_record(
    base: str = DEFAULT_BASE, scale: float = 0.1, base_kwargs: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The residual record (preset option and training-log entry): the base law's registry
    name, its keyword options and the correction's scale; checked (``ValueError``)."""
    if not isinstance(base, str) or not base:
        raise ValueError(f"residual base must be a controller name, got {base!r}")
    if base_kwargs is not None and not isinstance(base_kwargs, dict):
        raise ValueError(f"residual base_kwargs must be an object, got {base_kwargs!r}")
    return {"base": base, "scale": check_scale(scale), "base_kwargs": dict(base_kwargs or {})}


def check_record(value: Any) -> dict[str, Any]:
    """A residual record (an object with ``base``, ``scale`` and optional ``base_kwargs``)
    normalised by :func:`residual_record`; ``ValueError`` naming what is wrong."""
    if not isinstance(value, dict):
        raise ValueError(f"must be an object {{'base': ..., 'scale': ...}}, got {value!r}")
    unknown = sorted(set(value) - {"base", "scale", "base_kwargs"})
    if unknown:
        raise ValueError(f"unknown key(s) {unknown} (valid: base, scale, base_kwargs)")
    return residual_record(**value)


def make_base(record: dict[str, Any], env_or_params: Any = None) -> Any:
    """The base law of a residual record for the plant ``env_or_params``."""
    from agents.controllers.registry import make_controller

    return make_controller(record["base"], env_or_params, **record.get("base_kwargs", {}))


def run_record(path: str | Path) -> dict[str, Any]:
    """The residual record of a run directory (or a ``model.zip`` in one): its training
    log's ``residual`` entry; :class:`ControllerError` if there is none."""
    p = Path(path)
    folder = p.parent if p.suffix == ".zip" else p
    log_file = folder / "training_log.json"
    if not log_file.is_file() and folder.name == "best":
        log_file = folder.parent / "training_log.json"
    try:
        log = json.loads(log_file.read_text())
    except (OSError, ValueError) as exc:
        raise ControllerError(
            f"residual agent {str(path)!r}: cannot read {log_file} ({exc})"
        ) from None
    rec = log.get(RESIDUAL_KEY) if isinstance(log, dict) else None
    if rec is None:
        raise ControllerError(
            f"residual agent {str(path)!r}: {log_file} has no {RESIDUAL_KEY!r} record (not a "
            "run trained with a residual preset)"
        )
    try:
        return check_record(rec)
    except ValueError as exc:
        raise ControllerError(f"residual agent {str(path)!r}: {log_file}: {exc}") from None


def make_residual(
    env_or_params: Any = None,
    path: str | Path | None = None,
    *,
    base: str | None = None,
    scale: float | None = None,
    base_kwargs: dict[str, Any] | None = None,
    name: str | None = None,
    **policy_kw: Any,
) -> ResidualController:
    """The residual controller of the run ``path`` (its base law and scale from the
    training log's record, :func:`run_record`; ``base`` / ``scale`` / ``base_kwargs``
    override them) for the plant ``env_or_params``; without ``path`` the base law with a
    :class:`ZeroPolicy` (flies as the base, bit for bit). ``policy_kw`` go to the policy's
    loader (:func:`agents.controllers.learned.make_learned`)."""
    rec = run_record(path) if path is not None else residual_record()
    rec = residual_record(
        base if base is not None else rec["base"],
        scale if scale is not None else rec["scale"],
        base_kwargs if base_kwargs is not None else rec["base_kwargs"],
    )
    law = make_base(rec, env_or_params)
    if path is None:
        from agents.controllers.base import control_context

        policy: Any = ZeroPolicy(control_context(env_or_params).n_actions)
        label = name or f"{rec['base']}+zero-residual"
    else:
        from agents.controllers.learned import make_learned

        label = name or str(path)
        policy = make_learned(label, env_or_params, path, **policy_kw)
    return ResidualController(law, policy, rec["scale"], name=label)


def _shipped(folder: str) -> Any:
    def make(env_or_params: Any = None, path: str | Path | None = None, **kw: Any) -> Any:
        from agents.controllers.learned import shipped_path
        from agents.installation import require_extra

        require_extra("train", f"controller {folder!r} (a trained Stable-Baselines3 agent)")
        p = Path(path) if path is not None else shipped_path(folder)
        kw.setdefault("name", folder)
        return make_residual(env_or_params, p, **kw)

    make.__doc__ = (
        f"The residual agent shipped in ``agents/shipped/{folder}/`` (or ``path=`` a run)."
    )
    return make


ppo_residual = _shipped("ppo-residual")
ppo_residual_guidance = _shipped("ppo-residual-guidance")
