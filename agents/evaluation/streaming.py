"""Streaming accumulators for long runs: statistics without storing every sample.

Every accumulator works on *chunks* of a batch of runs: arrays ``(T, N, …)`` (T steps of
N runs) with a boolean ``mask`` ``(T, N)`` marking the samples that count (a run stops at
its first termination or truncation; samples after that, and non-finite samples, are
ignored). State is kept per run (per row), so a run's result does not depend on which
other runs shared its batch, and rows are merged in a fixed order afterwards.

* :class:`Moments` — count, mean, M2 (sum of squared deviations), sum of squares and the
  largest absolute value, per row and column; chunks are merged with Chan et al.'s
  parallel update (numerically stable), so mean, variance and RMS equal numpy's on the
  whole signal to rounding.
* :class:`Exceedances` — exact counts of samples with ``|x| ≥ level`` per level and
  column, and of samples where *any* column exceeds, per row.
* :class:`WeightedRMS` — ISO 2631-1 frequency-weighted RMS acceleration
  (:mod:`hyperloop_env.comfort`) with the ``scipy.signal.sosfilt`` state carried from
  chunk to chunk. The batch function removes the signal's mean *before* filtering, which a
  stream does not know in advance; by linearity
  ``sosfilt(x − m) = sosfilt(x) − m·sosfilt(1)``, so the stream filters ``x`` and the unit
  step in parallel and accumulates ``Σy², Σy·s, Σs²`` after the settling samples; at the
  end ``Σ(y − m·s)² = Σy² − 2mΣys + m²Σs²`` with the exact mean ``m``. The result equals
  :func:`hyperloop_env.comfort.weighted_rms` to rounding.
* :class:`Thinned` — every k-th sample of a signal (steps ``1, 1 + k, 1 + 2k, …``) in a
  preallocated array: the bounded sample the STS fit is made on.

Memory: O(N · columns) per accumulator plus, for :class:`Thinned`, ``ceil(T_max/k) ·
columns`` floats per row.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal as sps

from hyperloop_env.comfort import digital_sos


def _masked(x: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(x with ignored entries set to 0, the effective mask incl. finiteness), broadcasting
    a (T, N) mask over trailing columns."""
    m = mask.reshape(mask.shape + (1,) * (x.ndim - mask.ndim)) & np.isfinite(x)
    return np.where(m, x, 0.0), m


class Moments:
    """Running count / mean / M2 / sum of squares / max |x| per row and column."""

    def __init__(self, n_rows: int, n_cols: int) -> None:
        self.n = np.zeros((n_rows, n_cols), dtype=np.int64)
        self.mean = np.zeros((n_rows, n_cols))
        self.m2 = np.zeros((n_rows, n_cols))
        self.sumsq = np.zeros((n_rows, n_cols))
        self.maxabs = np.zeros((n_rows, n_cols))

    def update(self, x: np.ndarray, mask: np.ndarray) -> None:
        """Add the chunk ``x`` (T, N, C) where ``mask`` (T, N) is True."""
        xz, m = _masked(x, mask)
        nb = m.sum(axis=0)
        if not nb.any():
            return
        sb = xz.sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            mb = np.where(nb > 0, sb / np.maximum(nb, 1), 0.0)
        d = np.where(m, xz - mb[None], 0.0)
        m2b = (d * d).sum(axis=0)
        self._merge(nb, mb, m2b)
        self.sumsq += (xz * xz).sum(axis=0)
        self.maxabs = np.maximum(self.maxabs, np.abs(xz).max(axis=0))

    def _merge(self, nb: np.ndarray, mb: np.ndarray, m2b: np.ndarray) -> None:
        na = self.n
        n = na + nb
        safe = np.maximum(n, 1)
        delta = mb - self.mean
        self.mean = np.where(n > 0, self.mean + delta * (nb / safe), 0.0)
        self.m2 = self.m2 + m2b + delta * delta * (na * nb / safe)
        self.n = n

    def row(self, i: int) -> dict[str, np.ndarray]:
        return {k: getattr(self, k)[i].copy() for k in ("n", "mean", "m2", "sumsq", "maxabs")}


def merge_moments(rows: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Merge per-run moment dicts (in the given order) into one."""
    if not rows:
        raise ValueError("no rows to merge")
    out = {k: np.array(v, dtype=float if k != "n" else np.int64) for k, v in rows[0].items()}
    for r in rows[1:]:
        na, nb = out["n"], r["n"]
        n = na + nb
        safe = np.maximum(n, 1)
        delta = r["mean"] - out["mean"]
        out["mean"] = np.where(n > 0, out["mean"] + delta * (nb / safe), 0.0)
        out["m2"] = out["m2"] + r["m2"] + delta * delta * (na * nb / safe)
        out["n"] = n
        out["sumsq"] = out["sumsq"] + r["sumsq"]
        out["maxabs"] = np.maximum(out["maxabs"], r["maxabs"])
    return out


def moments_summary(m: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """mean, var (ddof=0), std and RMS per column (NaN where no samples)."""
    n = m["n"].astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        var = np.where(n > 0, m["m2"] / n, np.nan)
        rms = np.where(n > 0, np.sqrt(m["sumsq"] / n), np.nan)
    mean = np.where(n > 0, m["mean"], np.nan)
    return {"mean": mean, "var": var, "std": np.sqrt(var), "rms": rms, "n": m["n"]}


class Exceedances:
    """Exact counts of ``|x| ≥ level`` per row, level and column, and of samples where any
    column exceeds the level."""

    def __init__(self, n_rows: int, n_cols: int, levels: np.ndarray) -> None:
        self.levels = np.asarray(levels, dtype=np.float64)
        m = self.levels.size
        self.count = np.zeros((n_rows, m, n_cols), dtype=np.int64)
        self.count_any = np.zeros((n_rows, m), dtype=np.int64)
        self.n = np.zeros(n_rows, dtype=np.int64)

    def update(self, x: np.ndarray, mask: np.ndarray) -> None:
        """``x`` (T, N, C); a sample counts where ``mask`` (T, N) and all columns are finite."""
        ok = mask & np.isfinite(x).all(axis=2)
        a = np.abs(np.where(ok[..., None], x, 0.0))
        self.n += ok.sum(axis=0)
        for j, lev in enumerate(self.levels):
            hit = (a >= lev) & ok[..., None]
            self.count[:, j] += hit.sum(axis=0)
            self.count_any[:, j] += hit.any(axis=2).sum(axis=0)


class WeightedRMS:
    """ISO 2631-1 weighted RMS of one signal per row, streamed (see the module docstring).

    ``settle_s`` drops the first ``round(settle_s/dt_s)`` samples of the weighted signal,
    as :func:`hyperloop_env.comfort.weighted_rms` does."""

    def __init__(self, n_rows: int, dt_s: float, kind: str, settle_s: float = 0.0) -> None:
        self.sos = digital_sos(kind, 1.0 / dt_s)  # type: ignore[arg-type]
        ns = self.sos.shape[0]
        self.zi_y = np.zeros((ns, 2, n_rows))
        self.zi_s = np.zeros((ns, 2, n_rows))
        self.n0 = int(round(settle_s / dt_s)) if settle_s > 0 else 0
        self.seen = np.zeros(n_rows, dtype=np.int64)
        self.sum_x = np.zeros(n_rows)
        self.syy = np.zeros(n_rows)
        self.sys = np.zeros(n_rows)
        self.sss = np.zeros(n_rows)
        self.n_after = np.zeros(n_rows, dtype=np.int64)

    def update(self, x: np.ndarray, mask: np.ndarray) -> None:
        """``x`` (T, N); ``mask`` (T, N) must be a prefix per row (a run's samples are
        contiguous from its start) — samples after a row's end are ignored."""
        ok = mask & np.isfinite(x)
        xz = np.where(ok, x, 0.0)
        y, self.zi_y = sps.sosfilt(self.sos, xz, axis=0, zi=self.zi_y)
        s, self.zi_s = sps.sosfilt(self.sos, np.ones_like(xz), axis=0, zi=self.zi_s)
        idx = self.seen[None, :] + np.cumsum(ok, axis=0) - 1  # sample index per row
        after = ok & (idx >= self.n0)
        self.sum_x += xz.sum(axis=0)
        self.syy += np.where(after, y * y, 0.0).sum(axis=0)
        self.sys += np.where(after, y * s, 0.0).sum(axis=0)
        self.sss += np.where(after, s * s, 0.0).sum(axis=0)
        self.n_after += after.sum(axis=0)
        self.seen += ok.sum(axis=0)

    def result(self) -> np.ndarray:
        """Weighted RMS per row [m/s²] (NaN for a row without samples after settling)."""
        out = np.full(self.seen.shape, math.nan)
        for i in range(out.size):
            if self.n_after[i] == 0:
                continue
            m = self.sum_x[i] / self.seen[i]
            ss = self.syy[i] - 2.0 * m * self.sys[i] + m * m * self.sss[i]
            out[i] = math.sqrt(max(ss, 0.0) / self.n_after[i])
        return out


class Thinned:
    """Every ``stride``-th sample (global steps 1, 1 + stride, …) of a (T, N, C) signal per
    row, in preallocated storage of ``ceil(max_steps / stride)`` rows (grown by half if a
    run turns out longer)."""

    def __init__(self, n_rows: int, n_cols: int, max_steps: int, stride: int) -> None:
        if stride < 1:
            raise ValueError(f"stride must be >= 1, got {stride!r}")
        self.stride = int(stride)
        cap = -(-int(max_steps) // self.stride)
        self.data = np.zeros((n_rows, cap, n_cols))
        self.count = np.zeros(n_rows, dtype=np.int64)

    @property
    def nbytes(self) -> int:
        return int(self.data.nbytes)

    def update(self, x: np.ndarray, mask: np.ndarray, first_step: int) -> None:
        """``x`` (T, N, C) holds global steps ``first_step … first_step + T − 1``."""
        t = first_step + np.arange(x.shape[0])
        sel = np.flatnonzero((t - 1) % self.stride == 0)
        if sel.size == 0:
            return
        for i in range(x.shape[1]):
            keep = sel[mask[sel, i] & np.isfinite(x[sel, i]).all(axis=1)]
            k = keep.size
            if k:
                c = self.count[i]
                if c + k > self.data.shape[1]:  # longer than planned: grow (rare)
                    extra = max(c + k - self.data.shape[1], self.data.shape[1] // 2 + 1)
                    pad = np.zeros((self.data.shape[0], extra, self.data.shape[2]))
                    self.data = np.concatenate([self.data, pad], axis=1)
                self.data[i, c : c + k] = x[keep, i]
                self.count[i] = c + k

    def row(self, i: int) -> np.ndarray:
        return self.data[i, : self.count[i]].copy()
