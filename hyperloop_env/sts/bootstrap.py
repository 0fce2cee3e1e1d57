"""Moving-block bootstrap of the fitted P(unsteady) (exact re-estimation for the normal and
Laplace laws, one-step linearised refits otherwise)."""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numba as nb
import numpy as np
from numpy.typing import NDArray
from scipy import stats

from hyperloop_env.sts import compiled, newton
from hyperloop_env.sts.common import (
    _CLOSED_FORM_REFIT,
    _MAX_GATHER,
    _POSITIVE_SHAPES,
    _REFIT_FALLBACK_MAX,
    CONFIDENCE,
    FloatArray,
)
from hyperloop_env.sts.estimators import (
    _fit,
    _law_p_unsteady,
)
from hyperloop_env.sts.newton import NEWTON_LAWS


def _chunks(n_boot: int, n_blocks: int) -> list[int]:
    per = max(1, _MAX_GATHER // max(1, n_blocks))
    sizes = [per] * (n_boot // per)
    if n_boot % per:
        sizes.append(n_boot % per)
    return sizes


def _block_layout(lengths: Sequence[int], block: int) -> list[tuple[int, int, NDArray[np.int64]]]:
    """(segment offset, block length, lengths of the blocks rebuilding the segment)."""
    layout = []
    off = 0
    for m in lengths:
        b = min(block, m)
        k = -(-m // b)
        lens = np.full(k, b, dtype=np.int64)
        lens[-1] = m - (k - 1) * b
        layout.append((off, b, lens))
        off += m
    return layout


def _block_sum_replicates(
    cum: FloatArray,
    layout: list[tuple[int, int, NDArray[np.int64]]],
    n_boot: int,
    rng: np.random.Generator,
) -> FloatArray:
    """Sums over moving-block bootstrap replicates: ``cum`` is ``(n + 1, k)`` cumulative
    sums with a leading zero row; the blocks' sums are added in a compiled loop in numpy's
    order (``(cum[starts + lens] - cum[starts]).sum(axis=1)``, bit for bit)."""
    n_blocks = sum(lens.size for _, _, lens in layout)
    cum2 = np.ascontiguousarray(cum.reshape(cum.shape[0], -1))
    out = []
    for size in _chunks(n_boot, n_blocks):
        total = np.zeros((size, cum2.shape[1]))
        for off, b, lens in layout:
            m = int(lens.sum())
            starts = off + rng.integers(0, m - b + 1, size=(size, lens.size))
            _add_block_sums(cum2, starts, lens, total)
        out.append(total.reshape(size, *cum.shape[1:]))
    return np.concatenate(out, axis=0)


@nb.njit(cache=True)
def _add_block_sums(
    cum: FloatArray, starts: NDArray[np.int64], lens: NDArray[np.int64], total: FloatArray
) -> None:
    """``total[r] += Σ_j (cum[starts[r, j] + lens[j]] − cum[starts[r, j]])``, summed over j in
    order first (as numpy's ``sum(axis=1)``), then added."""
    k = cum.shape[1]
    acc = np.empty(k)
    for r in range(starts.shape[0]):
        for j in range(starts.shape[1]):
            a = starts[r, j]
            e = a + lens[j]
            for c in range(k):
                d = cum[e, c] - cum[a, c]
                acc[c] = d if j == 0 else acc[c] + d
        for c in range(k):
            total[r, c] += acc[c]


def _replicate_indices(
    layout: list[tuple[int, int, NDArray[np.int64]]],
    size: int,
    rng: np.random.Generator,
) -> NDArray[np.int64]:
    """Materialised indices ``(size, n)`` of ``size`` bootstrap replicates."""
    parts = []
    for off, b, lens in layout:
        m = int(lens.sum())
        starts = off + rng.integers(0, m - b + 1, size=(size, lens.size))
        idx = (starts[:, :, None] + np.arange(b)[None, None, :]).reshape(size, -1)[:, :m]
        parts.append(idx)
    return np.concatenate(parts, axis=1)


def _chart(name: str, params: tuple[float, ...]) -> tuple[FloatArray, NDArray[np.bool_]]:
    n_shapes = len(params) - 2
    logs = list(_POSITIVE_SHAPES.get(name, (False,) * n_shapes)) + [False, True]
    mask = np.array(logs, dtype=bool)
    phi = np.array(params, dtype=np.float64)
    phi[mask] = np.log(phi[mask])
    return phi, mask


def _unchart(phi: FloatArray, mask: NDArray[np.bool_]) -> FloatArray:
    theta = np.array(phi, dtype=np.float64, copy=True)
    with np.errstate(over="ignore"):
        theta[..., mask] = np.exp(theta[..., mask])
    return theta


def _chart_scores(
    name: str, z: FloatArray, params: tuple[float, ...], mask: NDArray[np.bool_]
) -> tuple[FloatArray, FloatArray] | None:
    """Per-sample scores and the mean Hessian of log f in the chart φ (log of the positive
    parameters), from their closed forms over θ (:func:`newton.scores_and_hessian`):
    ∂/∂φ_j = θ_j ∂/∂θ_j and ∂²/∂φ_i∂φ_j = θ_i θ_j ∂²/∂θ_i∂θ_j + δ_ij θ_j ∂/∂θ_j for the
    logged ones."""
    out = newton.scores_and_hessian(name, z, params)
    if out is None:
        return None
    s_theta, h_theta = out
    jac = np.where(mask, np.asarray(params, dtype=np.float64), 1.0)
    s0 = s_theta * jac
    hess = h_theta * np.outer(jac, jac) + np.diag(np.where(mask, s0.mean(0), 0.0))
    return s0, hess


def _one_step_replicates(
    name: str,
    z: FloatArray,
    params: tuple[float, ...],
    layout: list[tuple[int, int, NDArray[np.int64]]],
    n_boot: int,
    rng: np.random.Generator,
) -> FloatArray | None:
    """Linearised bootstrap parameter replicates ``(n_boot, k)``, or None if not regular."""
    dist = getattr(stats, name)
    phi0, mask = _chart(name, params)
    k = phi0.size

    def loglik(phi: FloatArray) -> FloatArray:
        theta = _unchart(phi, mask)
        fast = compiled.logpdf(name, z, theta)
        return dist.logpdf(z, *theta) if fast is None else fast

    def scores(phi: FloatArray, h: float = 1e-5) -> FloatArray:
        out = np.empty((z.size, k))
        for j in range(k):
            e = np.zeros(k)
            e[j] = h
            out[:, j] = (loglik(phi + e) - loglik(phi - e)) / (2.0 * h)
        return out

    if name in NEWTON_LAWS:
        analytic = _chart_scores(name, z, params, mask)
        if analytic is None:
            return None
        s0, hess = analytic
    else:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            s0 = scores(phi0)
            if not np.isfinite(s0).all():
                return None
            hess = np.empty((k, k))
            h2 = 1e-4
            for j in range(k):
                e = np.zeros(k)
                e[j] = h2
                hess[:, j] = (scores(phi0 + e).mean(0) - scores(phi0 - e).mean(0)) / (2.0 * h2)
    if not np.isfinite(hess).all():
        return None
    hess = 0.5 * (hess + hess.T)
    if not np.all(np.linalg.eigvalsh(hess) < 0.0):
        return None
    g0 = s0.mean(0)
    cum = np.vstack([np.zeros((1, k)), np.cumsum(s0, axis=0)])
    g_b = _block_sum_replicates(cum, layout, n_boot, rng) / z.size
    delta = np.linalg.solve(hess, (g_b - g0).T).T
    return _unchart(phi0[None, :] - delta, mask)


def _bootstrap_fit_p(
    name: str,
    z: FloatArray,
    params: tuple[float, ...],
    lengths: Sequence[int],
    block: int,
    z_hi: float,
    z_lo: float,
    n_boot: int,
    max_fit_samples: int,
    rng: np.random.Generator,
) -> tuple[FloatArray, str]:
    """Bootstrap replicates of the fitted P(unsteady) and a description of the method."""
    layout = _block_layout(lengths, block)
    mbb = f"moving-block bootstrap (L={block}, percentile {CONFIDENCE:.0%})"
    if name == "norm":
        cum = np.vstack([np.zeros((1, 2)), np.cumsum(np.column_stack([z, z * z]), axis=0)])
        sums = _block_sum_replicates(cum, layout, n_boot, rng) / z.size
        mu = sums[:, 0]
        sd = np.sqrt(np.maximum(sums[:, 1] - mu * mu, 0.0))
        with np.errstate(all="ignore"):
            p = stats.norm.sf((z_hi - mu) / sd) + stats.norm.cdf((z_lo - mu) / sd)
        degenerate = (mu >= z_hi) | (mu <= z_lo)
        p = np.where(sd > 0.0, p, degenerate.astype(np.float64))
        return p, f"{mbb}, exact normal refit"
    theta_b = None
    method = ""
    if name not in _CLOSED_FORM_REFIT:
        theta_b = _one_step_replicates(name, z, params, layout, n_boot, rng)
        method = f"{mbb}, one-step linearised MLE refit"
    if theta_b is None:
        n_rep = n_boot if name in _CLOSED_FORM_REFIT else min(n_boot, _REFIT_FALLBACK_MAX)
        method = f"{mbb}, full MLE refit of {n_rep} replicates"
        n = z.size
        sub = None
        if n > max_fit_samples:
            sub = np.linspace(0, n - 1, max_fit_samples).round().astype(np.int64)
        rows = []
        for size in _chunks(n_rep, n if sub is None else sub.size):
            idx = _replicate_indices(layout, size, rng)
            if sub is not None:
                idx = idx[:, sub]
            for r in range(size):
                fitted = _fit(name, z[idx[r]], params)
                rows.append(fitted if fitted is not None else (math.nan,) * len(params))
        theta_b = np.array(rows, dtype=np.float64).reshape(-1, len(params))
    p = _law_p_unsteady(name, tuple(theta_b.T), z_hi, z_lo)
    return np.asarray(p, dtype=np.float64), method
