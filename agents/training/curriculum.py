"""A curriculum over a disturbance's severity that rises as the agent holds (the preset
option ``curriculum``; native vector env).

Training at the full severity from the first step wastes most episodes on contacts the
untrained policy cannot avoid; training only at easy severities never shows the agent the
conditions that set its capacity. The curriculum starts easy and raises the severity each
time the agent holds at the current one:

* every episode (a row's reset through this wrapper) flies the disturbance ``family`` at a
  severity drawn uniformly in ``[floor·level, level]``, rounded to 0.001, in place of the
  scenario's own draw of that family (the other families and the operating condition are
  the scenario's);
* ``level`` starts at ``start``; once ``window`` episodes begun at the current level have
  ended, the level rises by ``step`` (at most to ``stop``) if at least ``hold`` of them held
  (ended by the time limit, not by contact: Gymnasium's ``truncated`` without
  ``terminated``), and the count starts again either way. The level never falls.

The record (all fields required, checked by :func:`check_curriculum`)::

    "curriculum": {"family": "roughness", "start": 0.2, "stop": 0.8, "step": 0.05,
                   "hold": 0.9, "window": 64, "floor": 0.5}

``family`` is a disturbance family of :data:`hyperloop_env.disturbances.DISTURBANCES`
(``roughness``: the amplitude factor of the German "low" spectrum, the capacity
benchmark's roughness family); the severities must be valid for it. The draws come from
their own generator, seeded from the run's seed: the same seed gives the same curriculum
for the same outcomes. A checkpoint stores the level (:meth:`SeverityCurriculum.state`);
a resumed run continues from it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium.vector import VectorWrapper

CURRICULUM_FIELDS = ("family", "start", "stop", "step", "hold", "window", "floor")
"""The fields of a curriculum record (module docstring)."""
_STREAM = 0x6375_7272  # the curriculum's own stream of the run's seed ("curr")


def _real(rec: dict[str, Any], key: str, lo: float, hi: float, lo_open: bool = False) -> float:
    v = rec[key]
    ok = isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
    if not ok or not ((lo < v) if lo_open else (lo <= v)) or v > hi:
        bound = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
        raise ValueError(f"curriculum[{key!r}] must be a number in {bound}, got {v!r}")
    return float(v)


def check_curriculum(record: Any) -> dict[str, Any]:
    """The curriculum ``record`` normalised; ``ValueError`` naming the field that is
    missing, unknown or out of bounds (module docstring)."""
    from hyperloop_env.disturbances import DISTURBANCES, make_disturbance

    if not isinstance(record, dict):
        raise ValueError(f"curriculum must be an object with {list(CURRICULUM_FIELDS)}")
    missing = [k for k in CURRICULUM_FIELDS if k not in record]
    unknown = sorted(set(record) - set(CURRICULUM_FIELDS))
    if missing or unknown:
        raise ValueError(
            f"curriculum: missing {missing}, unknown {unknown}; the fields are "
            f"{list(CURRICULUM_FIELDS)}"
        )
    family = record["family"]
    if family not in DISTURBANCES:
        raise ValueError(
            f"curriculum['family'] must be a disturbance family, one of "
            f"{sorted(DISTURBANCES)}, got {family!r}"
        )
    rec: dict[str, Any] = {"family": family}
    rec["start"] = _real(record, "start", 0.0, 1e3, lo_open=True)
    rec["stop"] = _real(record, "stop", rec["start"], 1e3)
    rec["step"] = _real(record, "step", 0.0, 1e3, lo_open=True)
    rec["hold"] = _real(record, "hold", 0.0, 1.0, lo_open=True)
    rec["floor"] = _real(record, "floor", 0.0, 1.0)
    w = record["window"]
    if isinstance(w, bool) or not isinstance(w, int) or w < 1:
        raise ValueError(f"curriculum['window'] must be an integer >= 1, got {w!r}")
    rec["window"] = w
    for key in ("start", "stop"):  # the family's own bounds on its severity
        try:
            make_disturbance(family, rec[key])
        except (TypeError, ValueError) as exc:
            raise ValueError(f"curriculum[{key!r}] = {rec[key]:g}: {exc}") from None
    return rec


class SeverityCurriculum(VectorWrapper):
    """The native vector env ``env`` whose episodes fly the record's family at the
    curriculum's severities (module docstring); ``seed``: the run's seed."""

    def __init__(self, env: Any, record: dict[str, Any], seed: int) -> None:
        super().__init__(env)
        self.record = check_curriculum(record)
        self.level = self.record["start"]
        self.history: list[tuple[int, float]] = [(0, self.level)]  # (env steps, level)
        self._rng = np.random.default_rng([int(seed), _STREAM])
        n = self.num_envs
        self._row_level = np.full(n, -1.0)  # the level each row's episode was drawn at
        self._ended = 0
        self._held = 0
        self._steps = 0

    @property
    def supports_reset_mask(self) -> bool:
        return bool(getattr(self.env, "supports_reset_mask", False))

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_") or name == "env":
            raise AttributeError(name)
        return getattr(self.env, name)

    def state(self) -> dict[str, Any]:
        """What a checkpoint keeps: the level and its history."""
        return {"level": self.level, "history": [list(h) for h in self.history]}

    def load_state(self, state: dict[str, Any], seed: int) -> None:
        """Continue from a checkpoint's :meth:`state`, the draws from a new ``seed`` (a
        resumed segment's) and the count of the current level started anew."""
        level = state.get("level") if isinstance(state, dict) else None
        ok = isinstance(level, int | float) and not isinstance(level, bool)
        if not ok or not self.record["start"] <= level <= self.record["stop"]:
            raise ValueError(f"curriculum state: level must be in [start, stop], got {level!r}")
        self.level = float(level)
        self.history = [(int(s), float(v)) for s, v in state.get("history", [])] or [
            (0, self.level)
        ]
        self._rng = np.random.default_rng([int(seed), _STREAM])
        self._ended = self._held = 0

    def _draws(self, rows: np.ndarray) -> list[dict[str, float] | None]:
        lo, hi = self.record["floor"] * self.level, self.level
        s = np.round(self._rng.uniform(lo, hi, rows.size), 3)
        out: list[dict[str, float] | None] = [None] * self.num_envs
        for i, v in zip(rows, s, strict=True):
            out[int(i)] = {self.record["family"]: float(max(v, 0.0))}
        self._row_level[rows] = self.level
        return out

    def reset(self, *, seed: Any = None, options: dict[str, Any] | None = None) -> Any:
        opts = dict(options or {})
        if "disturbances" in opts:
            raise ValueError("reset options['disturbances'] are the curriculum's to set")
        mask = opts.get("reset_mask")
        n = self.num_envs
        rows = np.arange(n) if mask is None else np.flatnonzero(np.asarray(mask, bool))
        opts["disturbances"] = self._draws(rows)
        return self.env.reset(seed=seed, options=opts)

    def step(self, actions: Any) -> Any:
        obs, reward, terminated, truncated, info = self.env.step(actions)
        self._steps += self.num_envs
        term = np.asarray(terminated, bool)
        done = term | np.asarray(truncated, bool)
        if done.any():
            current = done & (self._row_level == self.level)
            self._ended += int(current.sum())
            self._held += int((current & ~term).sum())
            self._row_level[done] = -1.0  # counted once
            if self._ended >= self.record["window"]:
                if self._held >= self.record["hold"] * self._ended:
                    self._raise()
                self._ended = self._held = 0
        return obs, reward, terminated, truncated, info

    def _raise(self) -> None:
        new = min(self.level + self.record["step"], self.record["stop"])
        if new > self.level:
            self.level = new
            self.history.append((self._steps, new))


def find_curriculum(env: Any) -> SeverityCurriculum | None:
    """The :class:`SeverityCurriculum` under ``env``'s wrappers (SB3's ``venv`` and
    Gymnasium's ``env`` chains), or None."""
    seen = 0
    while env is not None and seen < 32:
        if isinstance(env, SeverityCurriculum):
            return env
        env = getattr(env, "venv", None) or env.__dict__.get("env")
        seen += 1
    return None
