"""Compiled log-likelihoods of the heavy candidate laws (``t``, ``genextreme``, ``skewnorm``).

scipy's maximum-likelihood ``fit`` of these laws minimises its penalised negative
log-likelihood (``rv_continuous._penalized_nnlf``) with Nelder–Mead, one ``logpdf`` of every
sample per function evaluation, and a few hundred evaluations per fit. Most of that time is
scipy's per-call overhead, not arithmetic. This module compiles that objective with numba:

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
* ``skewnorm`` (shape a): log 2 − y²/2 − log √(2π) + log Φ(a y), log Φ by
  :func:`_log_ndtr` (erfc above −30, the asymptotic series below).
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


@nb.njit(cache=True)
def _log_ndtr(x: float) -> float:
    """log Φ(x): log1p(−erfc(x/√2)/2) above −1, log(erfc(−x/√2)/2) down to −30, and the
    asymptotic series −x²/2 − log(−x) − log√(2π) + log(Σ_k (−1)^k (2k−1)!!/x^{2k}) below
    (eight terms: relative error < 1e-16 at −30)."""
    if x > -1.0:
        return math.log1p(-0.5 * math.erfc(x / math.sqrt(2.0)))
    if x > -30.0:
        return math.log(0.5 * math.erfc(-x / math.sqrt(2.0)))
    x2 = 1.0 / (x * x)
    term = 1.0
    total = 1.0
    for k in range(1, 9):
        term *= -(2 * k - 1) * x2
        total += term
    return -0.5 * x * x - math.log(-x) - 0.5 * math.log(2.0 * math.pi) + math.log(total)


@nb.njit(cache=True)
def _t_terms(x: FloatArray, loc: float, scale: float, df: float, c0: float, out: FloatArray) -> int:
    half = (df + 1.0) / 2.0
    bad = 0
    for i in range(x.size):
        y = (x[i] - loc) / scale
        v = c0 - half * math.log1p(y * y / df)
        out[i] = v
        if not math.isfinite(v):
            bad += 1
    return bad


@nb.njit(cache=True)
def _genextreme_terms(x: FloatArray, loc: float, scale: float, c: float, out: FloatArray) -> int:
    lo = 1.0 / min(c, -_XMIN) if c < 0.0 else -np.inf
    hi = 1.0 / max(c, _XMIN) if c > 0.0 else np.inf
    bad = 0
    for i in range(x.size):
        y = (x[i] - loc) / scale
        if not (lo < y < hi):
            out[i] = -np.inf
            bad += 1
            continue
        if c != 0.0:
            cx = c * y
            logex2 = math.log1p(-cx)
            logpex2 = logex2 / c  # scipy's log1p(-c*y)/c: the same log1p(-cx)
        else:
            cx = 0.0
            logex2 = 0.0
            logpex2 = -y
        if cx == 1.0 or cx == -np.inf:
            v = -np.inf
        else:
            v = -math.exp(logpex2) + logpex2 - logex2
        out[i] = v
        if not math.isfinite(v):
            bad += 1
    return bad


@nb.njit(cache=True)
def _skewnorm_terms(x: FloatArray, loc: float, scale: float, a: float, out: FloatArray) -> int:
    bad = 0
    for i in range(x.size):
        y = (x[i] - loc) / scale
        norm_logpdf = -(y**2) / 2.0 - _LOG_SQRT_2PI
        v = norm_logpdf if a == 0.0 else _LOG2 + norm_logpdf + _log_ndtr(a * y)
        out[i] = v
        if not math.isfinite(v):
            bad += 1
    return bad


def t_const(nu: float) -> float:
    """t's log-density constant c(ν) = log Γ((ν+1)/2) − log Γ(ν/2) − ½(log ν + log π), as
    scipy computes it (``scipy.special.poch``)."""
    return float(np.log(special.poch(0.5 * nu, 0.5)) - 0.5 * (np.log(nu) + np.log(np.pi)))


def _terms(name: str, x: FloatArray, params: Any, out: FloatArray) -> int | None:
    """Per-sample log f((x − loc)/scale) into ``out``; the count of non-finite terms, or None
    if the shape is outside the law's domain (scipy's ``_argcheck``)."""
    *shapes, loc, scale = (float(p) for p in params)
    (s,) = shapes
    if name == "t":
        if not s > 0.0:
            return None
        return int(_t_terms(x, loc, scale, s, t_const(s), out))
    if name == "genextreme":
        if not math.isfinite(s):
            return None
        return int(_genextreme_terms(x, loc, scale, s, out))
    return int(_skewnorm_terms(x, loc, scale, s, out))


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

    def nll(theta: FloatArray, *_: Any) -> float:
        scale = float(theta[-1])
        if not scale > 0.0:
            return math.inf
        n_bad = _terms(name, x, theta, buf)
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
    if not scale > 0.0 or _terms(name, np.ascontiguousarray(z, np.float64), params, out) is None:
        return np.full(z.size, np.nan)
    return out - math.log(scale)
