"""The observation memory: the ``history`` and ``front_preview`` blocks
(:class:`hyperloop_env.observation.MemorySpec`), computed per row from the observations
the sensors returned since the row's reset.

One implementation serves the single env, the native vector env (both autoreset modes)
and the learned controllers that were trained with memory (they rebuild the same blocks
from plain observations: :class:`agents.controllers.learned.SB3Controller`), so the
blocks an agent sees in training and in evaluation are the same numbers.

Each row keeps a ring of its last ``L`` measured entries (the observation's first
``n_measured``), ``L`` = max(k, τ_max/dt + 1) with τ_max =
:data:`~hyperloop_env.observation.MAX_FRONT_PREVIEW_DELAY_S` when the preview is on. At
a reset every slot holds the reset observation, so the entries older than the episode
are the reset observation's. The preview's delay τ = set_spacing / v is recomputed every
step from the observation's speed entry (map data, exact; the vehicle may accelerate):
``d = round(set_spacing_m / (v · dt))`` control steps, capped at ``L − 1``; the entry
of lead ℓ is the one ``max(d − round(ℓ/dt), 0)`` steps old.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from hyperloop_env.observation import (
    FRONT_PREVIEW_LEADS_S,
    FRONT_PREVIEW_SIGNALS,
    MAX_FRONT_PREVIEW_DELAY_S,
    SPEED_SCALE_M_S,
    ObservationSpec,
)


@nb.njit(cache=True)
def _delay(v: float, delay_num: float, max_delay: int) -> int:  # pragma: no cover - compiled
    """round(set_spacing / (v·dt)) from the scaled speed v (``delay_num`` = set_spacing /
    (dt · speed scale)), capped at ``max_delay`` (also for v <= 0)."""
    if not v > 0.0:
        return max_delay
    d = delay_num / v
    if d >= max_delay:
        return max_delay
    return int(np.rint(d))


@nb.njit(cache=True)
def memory_step(
    obs,
    rows,
    start,
    buf,
    t,
    out,
    n_base,
    lags,
    hist0,
    prev0,
    leads,
    front_cols,
    speed_col,
    delay_num,
    max_delay,
):  # pragma: no cover - compiled
    """Start (``start``) or advance the rings of ``rows`` with their observations and write
    their full observations (module docstring) into ``out``."""
    L = buf.shape[1]
    nm = buf.shape[2]
    for r in rows:
        if start:
            for j in range(L):
                for c in range(nm):
                    buf[r, j, c] = obs[r, c]
            t[r] = 0
        else:
            t[r] += 1
            slot = t[r] % L
            for c in range(nm):
                buf[r, slot, c] = obs[r, c]
        for c in range(n_base):
            out[r, c] = obs[r, c]
        k = hist0
        for lag in lags:
            slot = (t[r] - lag) % L
            for c in range(nm):
                out[r, k + c] = buf[r, slot, c]
            k += nm
        if prev0 >= 0:
            d = _delay(np.float64(obs[r, speed_col]), delay_num, max_delay)
            k = prev0
            for ld in leads:
                lag = d - ld
                if lag < 0:
                    lag = 0
                slot = (t[r] - lag) % L
                for c in front_cols:
                    out[r, k] = buf[r, slot, c]
                    k += 1


class ObservationMemory:
    """The memory blocks of ``spec`` for ``n_rows`` rows.

    ``start(obs, rows)`` begins the episodes of ``rows`` (a bool mask, None: all) from
    their reset observations; ``push(obs, rows)`` appends a step's observations of
    ``rows`` (None: all). Both take the plain observations (``(n_rows, spec.base_size)``
    float32) and return the full ones (``(n_rows, spec.size)``, a new array; rows not
    given keep their last full observation)."""

    def __init__(
        self, spec: ObservationSpec, n_rows: int, set_spacing_m: float, dt_s: float
    ) -> None:
        if not spec.memory.active:
            raise ValueError("ObservationMemory needs a spec with memory options")
        if not (set_spacing_m > 0 and dt_s > 0):
            raise ValueError(f"set_spacing_m and dt_s must be > 0, got {set_spacing_m!r}, {dt_s!r}")
        m = spec.memory
        self.spec = spec
        self.n_rows = int(n_rows)
        self.nb = spec.base_size
        max_delay = int(round(MAX_FRONT_PREVIEW_DELAY_S / dt_s)) if m.front_preview else 0
        self.L = max(m.history, max_delay + 1)
        self.max_delay = self.L - 1
        self._delay_num = float(set_spacing_m) / (float(dt_s) * SPEED_SCALE_M_S)
        self._speed_col = spec.start("speed")
        self._leads = np.array([round(x / dt_s) for x in FRONT_PREVIEW_LEADS_S], dtype=np.int64)
        self._front_cols = np.array(
            [spec.start(block) + unit for block, unit in FRONT_PREVIEW_SIGNALS], dtype=np.int64
        )
        self._lags = np.arange(1, m.history, dtype=np.int64)
        self.buf = np.zeros((self.n_rows, self.L, spec.n_measured), dtype=np.float32)
        self.t = np.zeros(self.n_rows, dtype=np.int64)  # steps since each row's reset
        self.out = np.zeros((self.n_rows, spec.size), dtype=np.float32)
        hist, prev = spec.slices.get("history"), spec.slices.get("front_preview")
        self._hist_start = hist.start if hist is not None else -1
        self._prev_start = prev.start if prev is not None else -1
        self._all = np.arange(self.n_rows, dtype=np.int64)

    def _rows(self, rows: np.ndarray | None) -> np.ndarray:
        if rows is None:
            return self._all
        r = np.asarray(rows)
        return np.flatnonzero(r) if r.dtype == np.bool_ else r.astype(np.int64)

    def start(self, obs: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        return self._step(obs, rows, True)

    def push(self, obs: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        return self._step(obs, rows, False)

    def _step(self, obs: np.ndarray, rows: np.ndarray | None, start: bool) -> np.ndarray:
        r = self._rows(rows)
        if r.size:
            memory_step(
                np.ascontiguousarray(obs, dtype=np.float32),
                r,
                start,
                self.buf,
                self.t,
                self.out,
                self.nb,
                self._lags,
                self._hist_start,
                self._prev_start,
                self._leads,
                self._front_cols,
                self._speed_col,
                self._delay_num,
                self.max_delay,
            )
        return self.out.copy()
