"""The one-sample Kolmogorov–Smirnov statistic and p-value as ``scipy.stats.ks_1samp``
gives them (two-sided, its default exact method), computed faster.

**Statistic.** D = max_i max((i+1)/n − F(z_i), F(z_i) − i/n) over the sorted samples
z_0 ≤ … ≤ z_{n−1} (0-based i). F is non-decreasing and z is sorted, so on a block of
indices [a, e] every interior i (a < i < e) has

    (i+1)/n − F(z_i) ≤ e/n − F(z_a),        F(z_i) − i/n ≤ F(z_e) − (a+1)/n.

:func:`ks_statistic` evaluates F at every 256th sample (and the last), bounds each block
from its ends, evaluates every 16th sample of the blocks whose bound exceeds the largest
value found so far, bounds those sub-blocks the same way, and finally evaluates the
interiors of the sub-blocks that can still exceed it. The maximum is taken over the same
per-index values, formed the same way, as the full computation (:func:`ks_statistic_full`,
the code it replaces), so D is the same float; that needs F elementwise (a sample's value
does not depend on the other samples passed with it). The bounds are widened by
``_MARGIN`` = 1e-9 against a floating-point CDF that is not exactly monotone (scipy's
laws: a few ulps; the compiled skew-normal's switch between Boost and the integrated tail:
about 3e-14). A NaN among the evaluated values (invalid parameters make every value NaN,
NaN samples sort to the end, whose value is always evaluated) falls back to the full
computation, which propagates it.

**p-value.** ``scipy.stats.kstwo.sf(d, n)`` (scipy 1.17's ``_kolmogn``, Simard & L'Ecuyer
2011) takes, for n > 140 and 2.2 ≤ n d² < 370, twice the one-sided Smirnov survival
function, ``2 * scipy.special.smirnov(n, d)``, whose exact sum has O(n) terms, each in
double-double arithmetic (xsf's ``cephes/kolmogorov.h``): 15–80 ms at n = 20 000–90 000.
:func:`smirnov_sf` computes the same Birnbaum–Tingey sum (Birnbaum & Tingey 1951, the lower
sum xsf uses on this branch),

    P(D+_n ≥ x) = x Σ_{j=0}^{⌊n(1−x)⌋} C(n,j) (1−x−j/n)^{n−j} (x+j/n)^{j−1}
                = Σ_j  n x / (n x + j) · b(j; n, x + j/n),

with b(j; n, p) = C(n,j) p^j (1−p)^{n−j} the binomial probability, computed in Loader's
saddle-point form (Loader 2000, "Fast and accurate computation of binomial
probabilities", as R's ``dbinom_raw``):

    b(j; n, p) = √(n / (2π j (n−j))) · exp(δ(n) − δ(j) − δ(n−j) − bd0(j, np) − bd0(n−j, nq)),

δ(k) = log k! − (k+½) log k + k − ½ log 2π (tabulated to k = 15, its Stirling series above),
bd0(x, m) = x log(x/m) + m − x, with x − m = ∓n x passed exactly rather than recomputed
(its series in v = (x−m)/(x+m) for |v| < ½, x log1p((x−m)/m) − (x−m) otherwise). n x is
carried as an exact two-term product. The terms are summed, scaled by exp(2 n x²), in
ascending j with Kahan compensation and xsf's stopping rule (stop once 4·(terms left)·term <
ε·sum). Relative difference from scipy's values: at most 1e-12 over the branch (tested in
``tests/env/test_sts_ks.py``; measured on 487 points with n = 141 … 200 000: at most 3.3e-15
where p ≥ 1e-10, 1.3e-13 below). On the branch the p-value is below about 2·e^{−4.4} ≈ 0.025,
so a 0.05 acceptance threshold is never decided there. :func:`kstwo_sf` uses it only on
that branch, where scipy's own smirnov is neither an approximation (n ≤ 10⁶) nor 0
(−2 n x² ≥ its MINLOG + 1), and only for a result in the normal range; everywhere else
it is scipy's ``kstwo.sf``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numba as nb
import numpy as np
from scipy import stats

from hyperloop_env.sts.common import FloatArray

# ---------------------------------------------------------------------------- p-value

_STIRLERR_TABLE = np.array(
    [  # δ(k) = log k! − (k+½) log k + k − ½ log 2π, k = 0..15 (40-digit values, rounded)
        0.0,
        0.08106146679532726,
        0.0413406959554093,
        0.02767792568499834,
        0.020790672103765093,
        0.016644691189821193,
        0.013876128823070748,
        0.01189670994589177,
        0.010411265261972096,
        0.009255462182712733,
        0.00833056343336287,
        0.007573675487951841,
        0.00694284010720953,
        0.006408994188004207,
        0.0059513701127588475,
        0.005554733551962801,
    ]
)
_S0 = 1.0 / 12.0
_S1 = 1.0 / 360.0
_S2 = 1.0 / 1260.0
_S3 = 1.0 / 1680.0
_S4 = 1.0 / 1188.0
_EPS = float(np.finfo(float).eps)
_LOG_2PI = math.log(2.0 * math.pi)
_SPLIT = 134217729.0  # 2^27 + 1, Dekker's splitter
_MINLOG = -7.08396418532264106224e2  # cephes' MINLOG = log(DBL_MIN)
_SMIRNOV_MAX_COMPUTE_N = 1_000_000  # above it xsf's smirnov approximates
_TINY = float(np.finfo(float).tiny)


@nb.njit(cache=True)
def _stirlerr(k: int) -> float:
    """δ(k) = log k! − (k+½) log k + k − ½ log 2π (R's ``stirlerr`` at integers)."""
    if k <= 15:
        return _STIRLERR_TABLE[k]
    x = float(k)
    xx = x * x
    if k > 500:
        return (_S0 - _S1 / xx) / x
    if k > 80:
        return (_S0 - (_S1 - _S2 / xx) / xx) / x
    if k > 35:
        return (_S0 - (_S1 - (_S2 - _S3 / xx) / xx) / xx) / x
    return (_S0 - (_S1 - (_S2 - (_S3 - _S4 / xx) / xx) / xx) / xx) / x


@nb.njit(cache=True)
def _bd0(x: float, d: float) -> float:
    """x log(x/m) + m − x with m = x − d (Loader's bd0, taking the difference d exactly)."""
    s_xm = 2.0 * x - d  # x + m
    if abs(d) < 0.5 * s_xm:
        v = d / s_xm
        s = d * v
        ej = 2.0 * x * v
        v2 = v * v
        for k in range(1, 1000):
            ej *= v2
            s1 = s + ej / (2 * k + 1)
            if s1 == s:
                return s1
            s = s1
        return s
    return x * math.log1p(d / (x - d)) - d


@nb.njit(cache=True)
def smirnov_sf(n: int, x: float) -> float:
    """P(D+_n ≥ x), the one-sided Smirnov survival function (``scipy.special.smirnov``), by
    the Birnbaum–Tingey sum in Loader's binomial form (module docstring). For 1/n < x < ½,
    n ≤ 10⁶ and a result above the underflow range; other arguments are left to scipy."""
    fn = float(n)
    # n·x = nx + nx_lo exactly (n < 2^26: both partial products are exact)
    c = _SPLIT * x
    x_hi = c - (c - x)
    x_lo = x - x_hi
    p_hi = fn * x_hi
    p_lo = fn * x_lo
    nx = p_hi + p_lo
    nx_lo = p_lo - (nx - p_hi)
    shift = 2.0 * nx * x  # ≈ −log of the sum's size: the terms are summed scaled by e^shift
    half_log = 0.5 * (math.log(fn) - _LOG_2PI)
    d_n = _stirlerr(n)
    jmax = int(math.floor(fn - nx))
    if float(jmax) >= fn - nx:  # the j = n(1 − x) term is 0
        jmax -= 1
    total = math.exp(fn * math.log1p(-x) + shift)  # j = 0: (1 − x)^n
    comp = 0.0
    for j in range(1, jmax + 1):
        k = n - j
        fj = float(j)
        fk = float(k)
        lc = d_n - _stirlerr(j) - _stirlerr(k) - _bd0(fj, -nx) - _bd0(fk, nx)
        lc -= nx_lo * nx * (1.0 / (fj + nx) + 1.0 / (fk - nx))  # bd0's slope times nx_lo
        term = math.exp(lc + shift + half_log - 0.5 * math.log(fj * fk)) * (nx / (nx + fj))
        y = term - comp
        s = total + y
        comp = (s - total) - y
        total = s
        if term != 0.0 and j != jmax and 4.0 * (jmax - j) * term < _EPS * total:
            break
    return math.exp(math.log(total) - shift)


def _on_smirnov_branch(d: float, n: int) -> bool:
    """Whether scipy 1.17's ``kstwo.sf(d, n)`` is ``2 * smirnov(n, d)`` computed by its exact
    sum (``_kolmogn``'s tests in its order, with its arithmetic: t = n·d, t·d)."""
    if not (n > 140 and 0.5 / n < d < 0.5):
        return False
    t = n * d
    if t <= 1.0 or t >= n - 1:
        return False
    nxsquared = t * d
    if not (2.2 <= nxsquared < 370.0):
        return False
    return n <= _SMIRNOV_MAX_COMPUTE_N and -2.0 * n * d * d >= _MINLOG + 1.0


def kstwo_sf(d: float, n: int) -> float:
    """``scipy.stats.kstwo.sf(d, n)`` clipped to [0, 1]; NaN for a non-finite ``d``. On the
    exact-Smirnov branch (n > 140, 2.2 ≤ n d² < 370), 2·:func:`smirnov_sf` (module
    docstring: relative 1e-12 of scipy's value)."""
    d = float(d)
    if not math.isfinite(d):
        return math.nan
    if int(n) == n and _on_smirnov_branch(d, int(n)):
        p = 2.0 * smirnov_sf(int(n), d)
        if p >= _TINY:  # a subnormal result is left to scipy's rounding
            return min(p, 1.0)
    return float(np.clip(stats.kstwo.sf(d, n), 0.0, 1.0))


# ---------------------------------------------------------------------------- statistic

_MARGIN = 1e-9  # widening of the block bounds (module docstring)
_STRIDES = (256, 16, 1)  # evaluation strides of the successive refinements
_MIN_BLOCKED = 2048  # below it the full evaluation is as quick


def ks_statistic_full(z_sorted: FloatArray, cdf: Callable[[FloatArray], FloatArray]) -> float:
    """D = max(max((i+1)/n − F(z_i)), max(F(z_i) − i/n)) with F at every sample, as
    ``scipy.stats.ks_1samp`` computes it (NaN if any F value is NaN)."""
    f = cdf(z_sorted)
    n = z_sorted.size
    d_plus = (np.arange(1.0, n + 1) / n - f).max()
    d_minus = (f - np.arange(0.0, n) / n).max()
    return float(d_plus if d_plus > d_minus else d_minus)


def _largest(idx: np.ndarray, f: FloatArray, n: int) -> float:
    """max over ``idx`` of (i+1)/n − F_i and F_i − i/n, formed as the full computation
    forms them (``np.arange(1.0, n + 1) / n`` holds (i+1)/n as float(i+1)/n)."""
    return float(max(((idx + 1) / n - f).max(), (f - idx / n).max()))


def ks_statistic(
    z_sorted: FloatArray,
    cdf: Callable[[FloatArray], FloatArray],
    *,
    strides: tuple[int, ...] = _STRIDES,
    min_blocked: int = _MIN_BLOCKED,
) -> float:
    """The two-sided KS statistic of sorted samples against the elementwise CDF ``cdf``: the
    same float as :func:`ks_statistic_full`, with F evaluated only where a block bound
    (module docstring) says the maximum can be. ``strides`` must decrease to 1."""
    if strides[-1] != 1 or any(s <= t for s, t in zip(strides, strides[1:], strict=False)):
        raise ValueError(f"strides must decrease to 1, got {strides}")
    n = z_sorted.size
    if n < max(min_blocked, 2):
        return ks_statistic_full(z_sorted, cdf)
    idx = np.arange(0, n, strides[0])
    if idx[-1] != n - 1:
        idx = np.append(idx, n - 1)
    f = np.empty(n)
    vals = np.asarray(cdf(z_sorted[idx]), dtype=float)
    if np.isnan(vals).any():
        return ks_statistic_full(z_sorted, cdf)
    f[idx] = vals
    best = _largest(idx, vals, n)
    a, e = idx[:-1], idx[1:]
    for s in strides[1:]:
        bound = np.maximum(e / n - f[a], f[e] - (a + 1) / n) + _MARGIN
        keep = (bound > best) & (e - a > 1)
        if not keep.any():
            break
        a, e = a[keep], e[keep]
        count = (e - a - 1) // s  # points a + s, a + 2s, … strictly inside (a, e)
        first = np.cumsum(count) - count
        new = np.repeat(a, count) + s * (np.arange(int(count.sum())) - np.repeat(first, count) + 1)
        if new.size == 0:
            continue
        vals = np.asarray(cdf(z_sorted[new]), dtype=float)
        if np.isnan(vals).any():
            return ks_statistic_full(z_sorted, cdf)
        f[new] = vals
        best = max(best, _largest(new, vals, n))
        # the sub-blocks: blocks are disjoint but for shared ends, so sorting the starts
        # (a and the new points) and the ends (the new points and e) pairs them up
        a = np.sort(np.concatenate([a, new]))
        e = np.sort(np.concatenate([new, e]))
    return best
