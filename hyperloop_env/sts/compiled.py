"""Compiled log-likelihoods of the heavy candidate laws (``t``, ``genextreme``, ``skewnorm``).

scipy's maximum-likelihood ``fit`` of these laws minimises its penalised negative
log-likelihood (``rv_continuous._penalized_nnlf``) with Nelder–Mead, one ``logpdf`` of every
sample per function evaluation, and a few hundred evaluations per fit. Most of that time is
scipy's per-call overhead, not arithmetic. This module evaluates that objective with
numba and numpy's vectorised transcendental functions (:func:`law_terms`):

    nll(shapes, loc, scale) = -Σ_finite log f((x_i - loc)/scale; shapes)
                              + n_bad · log(DBL_MAX) · 100 + n · log(scale)

with ``n_bad`` the samples outside the support or with a non-finite ``log f``, exactly as
scipy defines it (same support bounds, same per-sample formulas, same pairwise sum over the
finite terms; tested to 1e-13 relative in ``tests/env/test_sts_compiled.py``). The fits
themselves are :mod:`hyperloop_env.sts.newton`'s (Newton's method, with scipy's Nelder–Mead
over this objective where Newton does not converge).

:func:`logpdf` is the compiled ``dist.logpdf(z, *params)`` (including ``-log(scale)``),
used by the bootstrap's linearised refits; ``None`` for a law without a compiled form.

The per-sample formulas follow scipy 1.17's ``_logpdf`` of each law:

* ``t``:  log Γ((ν+1)/2) − log Γ(ν/2) − ½(log ν + log π) − (ν+1)/2 · log1p(y²/ν)
  (the constant from ``scipy.special.poch`` as scipy computes it);
* ``genextreme`` (shape c, scipy's sign): −(1 − c y)^(1/c) + log1p(−c y)/c − log1p(−c y)
  for c ≠ 0, −exp(−y) − y for c = 0; support 1 − c y > 0;
* ``skewnorm`` (shape a): log 2 − y²/2 − log √(2π) + log Φ(a y), log Φ by scipy's own
  ``scipy.special.log_ndtr``.

log1p and exp are numpy's (vectorised: a few ulps from the C library's, well inside the
stated 1e-13), evaluated once per sample and kept in :func:`law_terms`' parts for the
derivatives of Newton's pass.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numba as nb
import numpy as np
from scipy import special

from hyperloop_env.sts.common import FloatArray

_LOGXMAX = float(np.log(np.finfo(float).max))
_XMIN = float(np.finfo(float).tiny)
_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)
_LOG2 = math.log(2.0)


@nb.njit(cache=True, error_model="numpy")
def _t_terms(lq: FloatArray, half: float, c0: float, out: FloatArray) -> int:
    """t's terms c(ν) − (ν+1)/2 · log1p(y²/ν), from ``lq`` = log1p(y²/ν)."""
    bad = 0
    for i in range(lq.size):
        v = c0 - half * lq[i]
        out[i] = v
        if not math.isfinite(v):
            bad += 1
    return bad


@nb.njit(cache=True, error_model="numpy")
def _genextreme_terms(
    y: FloatArray, c: float, lu: FloatArray, p: FloatArray, w: FloatArray, out: FloatArray
) -> int:
    """genextreme's terms −w + p − lu from its parts (:func:`gev_parts`), −inf outside the
    support as scipy bounds it."""
    lo = 1.0 / min(c, -_XMIN) if c < 0.0 else -np.inf
    hi = 1.0 / max(c, _XMIN) if c > 0.0 else np.inf
    bad = 0
    for i in range(y.size):
        yi = y[i]
        cx = c * yi
        if not (lo < yi < hi) or cx == 1.0 or cx == -np.inf:
            v = -np.inf
        else:
            v = -w[i] + p[i] - lu[i]
        out[i] = v
        if not math.isfinite(v):
            bad += 1
    return bad


@nb.njit(cache=True, error_model="numpy")
def _skewnorm_terms(y: FloatArray, a: float, lphi: FloatArray, out: FloatArray) -> int:
    """skewnorm's terms log 2 + (−y²/2 − log √(2π)) + log Φ(a y) from ``lphi`` = log Φ(a y),
    the normal's at a = 0."""
    bad = 0
    for i in range(y.size):
        yi = y[i]
        norm_logpdf = -(yi**2) / 2.0 - _LOG_SQRT_2PI
        v = norm_logpdf if a == 0.0 else _LOG2 + norm_logpdf + lphi[i]
        out[i] = v
        if not math.isfinite(v):
            bad += 1
    return bad


def t_const(nu: float) -> float:
    """t's log-density constant c(ν) = log Γ((ν+1)/2) − log Γ(ν/2) − ½(log ν + log π), as
    scipy computes it (``scipy.special.poch``)."""
    return float(np.log(special.poch(0.5 * nu, 0.5)) - 0.5 * (np.log(nu) + np.log(np.pi)))


PARTS = 4  # rows of law_terms' scratch: y, and the law's parts lu, p, w


def scratch(n: int, rows: int = PARTS) -> FloatArray:
    """Room for :func:`law_terms`' parts of ``n`` samples (``rows`` ≥ :data:`PARTS`)."""
    return np.empty((rows, n))


def gev_parts(y: FloatArray, c: float, lu: FloatArray, p: FloatArray, w: FloatArray) -> None:
    """genextreme's transcendental parts at shape ``c``, by numpy's vectorised log1p and exp:
    lu = log1p(−c y), p = lu/c, w = e^p; at c = 0 (the Gumbel law) lu = 0, p = −y, so that
    −w + p − lu is −e^(−y) − y."""
    with np.errstate(all="ignore"):
        if c != 0.0:
            np.multiply(y, -c, out=p)  # −(c y): IEEE multiplication is sign-symmetric
            np.log1p(p, out=lu)
            np.divide(lu, c, out=p)
        else:
            lu.fill(0.0)
            np.negative(y, out=p)
        np.exp(p, out=w)


def law_terms(
    name: str, x: FloatArray, params: Any, parts: FloatArray, out: FloatArray
) -> int | None:
    """Per-sample log f((x − loc)/scale) + log scale into ``out``: the count of non-finite
    terms, or None if the shape is outside the law's domain (scipy's ``_argcheck``).

    ``parts`` (:func:`scratch`) receives y = (x − loc)/scale and the law's transcendental
    parts, evaluated once per sample by numpy's vectorised functions or scipy's ufuncs:
    ``t`` log1p(y²/ν); ``genextreme`` lu, p, w (:func:`gev_parts`); ``skewnorm`` log Φ(a y)
    (``scipy.special.log_ndtr``, as scipy's own skew-normal) and a y. Newton's pass
    (:mod:`hyperloop_env.sts.newton`) reads them for the derivatives."""
    *shapes, loc, scale = (float(p) for p in params)
    (s,) = shapes
    if (name == "t" and not s > 0.0) or (name == "genextreme" and not math.isfinite(s)):
        return None
    y, lu, p, w = parts[0], parts[1], parts[2], parts[3]
    with np.errstate(all="ignore"):
        np.subtract(x, loc, out=y)
        np.divide(y, scale, out=y)
        if name == "t":
            np.multiply(y, y, out=p)
            np.divide(p, s, out=p)
            np.log1p(p, out=lu)
            return int(_t_terms(lu, (s + 1.0) / 2.0, t_const(s), out))
        if name == "skewnorm":
            np.multiply(y, s, out=p)
            special.log_ndtr(p, out=lu)
            return int(_skewnorm_terms(y, s, lu, out))
    gev_parts(y, s, lu, p, w)
    return int(_genextreme_terms(y, s, lu, p, w, out))


COMPILED_LAWS = frozenset({"t", "genextreme", "skewnorm"})


def penalised_value(terms: FloatArray, n_bad: int, scale: float) -> float:
    """scipy's penalised negative log-likelihood from the per-sample ``terms`` (log f + log
    scale, −inf outside the support) of which ``n_bad`` are not finite: −Σ_finite (numpy's
    pairwise sum) + n_bad · log(DBL_MAX) · 100 + n · log(scale). Shared by
    :func:`penalised_nll` and Newton's pass (:mod:`hyperloop_env.sts.newton`), which computes
    the same terms: the same value bit for bit."""
    total = np.sum(terms) if n_bad == 0 else np.sum(terms[np.isfinite(terms)])
    return float(-total + n_bad * _LOGXMAX * 100 + terms.size * math.log(scale))


def penalised_nll(name: str, x: FloatArray) -> Callable[[FloatArray], float]:
    """scipy's ``_penalized_nnlf`` of law ``name`` on the data ``x``, compiled."""
    buf = np.empty_like(x)
    parts = scratch(x.size)

    def nll(theta: FloatArray, *_: Any) -> float:
        scale = float(theta[-1])
        if not scale > 0.0:
            return math.inf
        n_bad = law_terms(name, x, theta, parts, buf)
        if n_bad is None:
            return math.inf
        return penalised_value(buf, n_bad, scale)

    return nll


def logpdf(name: str, z: FloatArray, params: Any) -> FloatArray | None:
    """``scipy.stats.<name>.logpdf(z, *params)`` compiled (−inf outside the support, NaN for
    parameters outside the law's domain); None for a law without a compiled form."""
    if name not in COMPILED_LAWS:
        return None
    out = np.empty(z.size)
    scale = float(params[-1])
    z = np.ascontiguousarray(z, np.float64)
    if not scale > 0.0 or law_terms(name, z, params, scratch(z.size), out) is None:
        return np.full(z.size, np.nan)
    return out - math.log(scale)
