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

import numpy as np

from hyperloop_env.observation import (
    FRONT_PREVIEW_LEADS_S,
    FRONT_PREVIEW_SIGNALS,
    MAX_FRONT_PREVIEW_DELAY_S,
    SPEED_SCALE_M_S,
    ObservationSpec,
)


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
        self.nm = spec.n_measured
        self.k = m.history
        self.preview = m.front_preview
        self.dt_s = float(dt_s)
        max_delay = int(round(MAX_FRONT_PREVIEW_DELAY_S / dt_s)) if self.preview else 0
        self.L = max(self.k, max_delay + 1)
        self.max_delay = self.L - 1
        self._delay_num = float(set_spacing_m) / (float(dt_s) * SPEED_SCALE_M_S)
        self._speed_col = spec.start("speed")
        self._leads = np.array([round(x / dt_s) for x in FRONT_PREVIEW_LEADS_S], dtype=np.int64)
        self._front_cols = np.array(
            [spec.start(block) + unit for block, unit in FRONT_PREVIEW_SIGNALS], dtype=np.int64
        )
        self._lags = np.arange(1, self.k, dtype=np.int64)
        self.buf = np.zeros((self.n_rows, self.L, self.nm), dtype=np.float32)
        self.t = np.zeros(self.n_rows, dtype=np.int64)  # steps since each row's reset
        self.out = np.zeros((self.n_rows, spec.size), dtype=np.float32)
        self._hist = spec.slices.get("history")
        self._prev = spec.slices.get("front_preview")

    def _rows(self, rows: np.ndarray | None) -> np.ndarray:
        if rows is None:
            return np.arange(self.n_rows)
        r = np.asarray(rows)
        return np.flatnonzero(r) if r.dtype == np.bool_ else r.astype(np.int64)

    def start(self, obs: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        r = self._rows(rows)
        if r.size:
            self.buf[r] = obs[r, None, : self.nm]
            self.t[r] = 0
            self._compose(obs, r)
        return self.out.copy()

    def push(self, obs: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        r = self._rows(rows)
        if r.size:
            self.t[r] += 1
            self.buf[r, self.t[r] % self.L] = obs[r, : self.nm]
            self._compose(obs, r)
        return self.out.copy()

    def delay_steps(self, obs: np.ndarray) -> np.ndarray:
        """τ of each row of ``obs`` in control steps (rounded, capped at ``L − 1``)."""
        v = obs[:, self._speed_col].astype(np.float64)
        with np.errstate(divide="ignore"):
            d = np.where(v > 0, self._delay_num / np.maximum(v, 1e-300), np.inf)
        return np.minimum(np.rint(np.minimum(d, 1e9)), self.max_delay).astype(np.int64)

    def _compose(self, obs: np.ndarray, r: np.ndarray) -> None:
        out = self.out
        out[r, : self.nb] = obs[r, : self.nb]
        t = self.t[r]
        if self._hist is not None:
            idx = (t[:, None] - self._lags[None, :]) % self.L
            out[r, self._hist] = self.buf[r[:, None], idx].reshape(r.size, -1)
        if self._prev is not None:
            lag = np.maximum(self.delay_steps(obs[r])[:, None] - self._leads[None, :], 0)
            idx = (t[:, None] - lag) % self.L
            vals = self.buf[r[:, None, None], idx[:, :, None], self._front_cols[None, None, :]]
            out[r, self._prev] = vals.reshape(r.size, -1)

    def snapshot(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.buf.copy(), self.t.copy(), self.out.copy()

    def restore(self, snap: tuple[np.ndarray, np.ndarray, np.ndarray], rows: np.ndarray) -> None:
        r = self._rows(rows)
        self.buf[r], self.t[r], self.out[r] = snap[0][r], snap[1][r], snap[2][r]
