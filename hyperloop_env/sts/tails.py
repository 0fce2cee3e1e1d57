"""The skew-normal law's CDF and survival function as ``scipy.stats.skewnorm`` computes
them, with its slow branch compiled.

scipy 1.17's ``skewnorm._cdf(x, a)`` takes Boost's ``skewnorm_cdf`` (Owen's T), and where
that is below 1e-6 with a > 0 (Boost is inaccurate in that left tail) integrates the
density instead: ``quad(pdf, −∞, x)``, with the density called from Python at every
quadrature node (about 50 ms a point). The KS statistic and P(unsteady) of a fitted
skew-normal law meet such points often. :func:`skewnorm_cdf` runs the same branch rule and
the same QUADPACK integration (``scipy.integrate.quad``, its default tolerances) of the same
density,

    f(y; a) = 2·φ(y)·Φ(a·y),   φ(y) = exp(−y²/2)/√(2π),   Φ = scipy.special.ndtr

compiled with numba as a ``LowLevelCallable`` (Φ by scipy's ``ndtr`` rule over libm's erf
and erfc, :func:`_ndtr`; cached on disk like the other kernels). It equals scipy's values to
rounding (relative 1e-12, tested in ``tests/env/test_sts_tails.py``; the density's ``exp``
is libm's instead of NumPy's).
``skewnorm_sf(x, a) = skewnorm_cdf(−x, −a)``, as scipy defines it. Other laws go to scipy
(:func:`law_cdf`, :func:`law_sf`).
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numba as nb
import numpy as np
from numba import types
from scipy import LowLevelCallable, integrate, stats
from scipy.special import _ufuncs as scu

_SQRT_2PI = float(np.sqrt(2 * np.pi))  # scipy's _norm_pdf_C
_SQRT1_2 = math.sqrt(0.5)
_TAIL = 1e-6  # scipy 1.17's threshold below which Boost's left tail is not used (a > 0)


@nb.njit(cache=True, error_model="numpy")
def _ndtr(v: float) -> float:
    """Φ(v) by scipy's (Cephes') ``ndtr`` rule: ½ + ½ erf(v/√2) where |v/√2| < 1/√2, else
    ½ erfc(|v|/√2), reflected for v > 0 (libm's erf and erfc: scipy's ``ndtr`` to
    rounding)."""
    x = v * _SQRT1_2
    z = abs(x)
    if z < _SQRT1_2:
        return 0.5 + 0.5 * math.erf(x)
    y = 0.5 * math.erfc(z)
    return 1.0 - y if x > 0.0 else y


def _make_density() -> LowLevelCallable:
    """f(y; a) = 2·φ(y)·Φ(a·y) at ``xx = (y, a)`` (scipy's ``skewnorm._pdf``), compiled
    (on the first tail point; from numba's disk cache after the first run)."""

    @nb.cfunc(types.double(types.intc, types.CPointer(types.double)), cache=True)
    def density(n, xx):  # pragma: no cover - compiled
        y = xx[0]
        return 2.0 * (math.exp(-(y * y) / 2.0) / _SQRT_2PI) * _ndtr(xx[1] * y)

    return LowLevelCallable(density.ctypes)


@functools.cache
def _density() -> LowLevelCallable:
    return _make_density()


def _std_cdf(y: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The standard law's CDF (scipy's ``skewnorm._cdf``) at broadcast ``y``, ``a``."""
    shape = np.broadcast_shapes(np.shape(y), np.shape(a))
    y, a = (np.atleast_1d(np.broadcast_to(v, shape)).astype(float) for v in (y, a))
    cdf = np.asarray(scu._skewnorm_cdf(y, 0.0, 1.0, a), dtype=float)
    tail = (cdf < _TAIL) & (a > 0)
    if tail.any():
        cdf = cdf.copy()
        f = _density()
        for i in zip(*np.nonzero(tail), strict=True):
            cdf[i] = integrate.quad(f, -np.inf, float(y[i]), args=(float(a[i]),))[0]
    return np.clip(cdf, 0.0, 1.0).reshape(shape)


def skewnorm_cdf(x: Any, a: Any, loc: Any = 0.0, scale: Any = 1.0) -> np.ndarray:
    """``scipy.stats.skewnorm.cdf(x, a, loc, scale)`` (module docstring); NaN where the
    parameters are invalid (a not finite, scale ≤ 0) or x is NaN."""
    x, a, loc, scale = (np.asarray(v, dtype=float) for v in (x, a, loc, scale))
    with np.errstate(all="ignore"):
        y = (x - loc) / scale
        ok = np.isfinite(a) & (scale > 0) & ~np.isnan(y)
        out = np.where(ok, _std_cdf(y, np.where(ok, a, 0.0)), np.nan)
    return out[()] if out.ndim == 0 else out


def skewnorm_sf(x: Any, a: Any, loc: Any = 0.0, scale: Any = 1.0) -> np.ndarray:
    """``scipy.stats.skewnorm.sf(x, a, loc, scale)`` = the CDF at −y with shape −a."""
    x, a, loc, scale = (np.asarray(v, dtype=float) for v in (x, a, loc, scale))
    with np.errstate(all="ignore"):
        y = (x - loc) / scale
        ok = np.isfinite(a) & (scale > 0) & ~np.isnan(y)
        out = np.where(ok, _std_cdf(-y, np.where(ok, -a, 0.0)), np.nan)
    return out[()] if out.ndim == 0 else out


def _scalar_cdf(dist: Any, x: Any, params: tuple[Any, ...]) -> np.ndarray | None:
    """``dist.cdf(x, *params)`` for scalar, valid parameters and a 1-D ``x`` without NaN, as
    ``rv_continuous.cdf`` forms it (``_cdf`` of (x − loc)/scale inside the open support, 1
    at or above its upper end, 0 below), without its per-call argument handling (the KS
    statistic calls it a few times per candidate); None otherwise (the caller asks scipy)."""
    if not all(np.ndim(p) == 0 for p in params):
        return None
    *shapes, loc, scale = (float(p) for p in params)
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or not (scale > 0.0 and np.all(dist._argcheck(*shapes))):
        return None
    y = (x - loc) / scale
    if np.isnan(y).any():
        return None
    lo, hi = dist._get_support(*shapes)
    out = (y >= hi).astype(float)
    inside = (y > lo) & (y < hi)
    if inside.any():
        out[inside] = dist._cdf(y[inside], *shapes)
    return out


def law_cdf(name: str, x: Any, *params: Any) -> Any:
    """``getattr(scipy.stats, name).cdf(x, *params)``, skewnorm's compiled."""
    if name == "skewnorm":
        return skewnorm_cdf(x, *params)
    dist = getattr(stats, name)
    fast = _scalar_cdf(dist, x, params)
    return dist.cdf(x, *params) if fast is None else fast


def law_sf(name: str, x: Any, *params: Any) -> Any:
    """``getattr(scipy.stats, name).sf(x, *params)``, skewnorm's compiled."""
    if name == "skewnorm":
        return skewnorm_sf(x, *params)
    return getattr(stats, name).sf(x, *params)
