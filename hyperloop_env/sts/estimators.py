"""Estimators: the fitted law and its KS tests, P(unsteady) of a law, autocorrelation time,
effective sample size, Wilson interval, contact counting."""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy import fft as sp_fft
from scipy import stats

from hyperloop_env.sts.common import (
    CONFIDENCE,
    DEFAULT_CLEARANCE_M,
    FloatArray,
    _as_finite_1d,
    _as_segments,
    _check_positive,
)
from hyperloop_env.sts.compiled import COMPILED_LAWS
from hyperloop_env.sts.compiled import logpdf as compiled_logpdf
from hyperloop_env.sts.ks import ks_statistic, kstwo_sf
from hyperloop_env.sts.newton import fit_optimizer, newton_fit
from hyperloop_env.sts.tails import law_cdf, law_sf


def normal_p_unsteady(
    mean_m: float, std_m: float, clearance_m: float = DEFAULT_CLEARANCE_M
) -> float:
    """``P(|s| >= clearance)`` for ``s ~ N(mean, std^2)``.

    Computes ``1 - (Phi((Omega - mean)/std) - Phi((-Omega - mean)/std))`` as
    ``norm.sf((Omega - mean)/std) + norm.cdf((-Omega - mean)/std)`` so that tiny tail
    probabilities (e.g. 1e-12) are not lost to cancellation.

    Args:
        mean_m: mean of the gap excursion [m].
        std_m: standard deviation [m], ``>= 0``; 0 gives the degenerate law.
        clearance_m: clearance Omega [m], ``> 0``.

    Returns:
        Probability in [0, 1].
    """
    mean_m = float(mean_m)
    std_m = float(std_m)
    _check_positive("clearance_m", clearance_m)
    if not math.isfinite(mean_m):
        raise ValueError(f"mean_m must be finite, got {mean_m!r}")
    if not math.isfinite(std_m) or std_m < 0.0:
        raise ValueError(f"std_m must be finite and >= 0, got {std_m!r}")
    if std_m == 0.0:
        return 1.0 if abs(mean_m) >= clearance_m else 0.0
    upper = float(stats.norm.sf((clearance_m - mean_m) / std_m))
    lower = float(stats.norm.cdf((-clearance_m - mean_m) / std_m))
    return min(1.0, upper + lower)


def count_contacts(
    signal: ArrayLike,
    clearance_m: float = DEFAULT_CLEARANCE_M,
    *,
    terminated_in_contact: bool = False,
) -> int:
    """Number of contact events: entries into ``|s| >= clearance`` [m].

    A signal that starts inside the contact region counts one entry.  If the episode
    ``terminated_in_contact`` and the last recorded sample is not already in contact (or the
    signal is empty), the terminal contact is counted as one more event.
    """
    x = _as_finite_1d(signal, "signal")
    _check_positive("clearance_m", clearance_m)
    return len(_contact_indices(x, float(clearance_m), terminated_in_contact))


def integrated_autocorrelation_time(signal: ArrayLike | Sequence[ArrayLike]) -> float:
    """Integrated autocorrelation time ``tau`` [samples] (Geyer's initial monotone sequence).

    ``tau = -1 + 2 * sum_k Gamma_k`` with ``Gamma_k = rho(2k) + rho(2k+1)``, summed up to the
    first non-positive ``Gamma_k`` and made monotone non-increasing.  A sequence of 1-D arrays is
    treated as independent segments (episodes) sharing a common mean; lags never cross a segment
    boundary.  ``tau`` is clipped to ``>= 1`` (conservative for anti-correlated signals).
    Returns NaN for a signal with zero variance.
    """
    segments = _as_segments(signal)
    n = sum(s.size for s in segments)
    if n < 2:
        return math.nan
    mean = float(np.concatenate(segments).mean())
    return _iat([s - mean for s in segments], n)


def effective_sample_size(signal: ArrayLike | Sequence[ArrayLike]) -> float:
    """Effective number of independent samples ``n / tau`` (see
    :func:`integrated_autocorrelation_time`); NaN for a constant signal."""
    segments = _as_segments(signal)
    n = sum(s.size for s in segments)
    tau = integrated_autocorrelation_time(segments)
    return n / tau if math.isfinite(tau) else math.nan


def wilson_interval(
    p_hat: float, n_eff: float, confidence: float = CONFIDENCE
) -> tuple[float, float]:
    """Wilson score interval for a proportion ``p_hat`` observed on ``n_eff`` (possibly
    non-integer, effective) independent trials."""
    if not (0.0 <= p_hat <= 1.0) or not n_eff > 0.0:
        return (math.nan, math.nan)
    z = float(stats.norm.isf((1.0 - confidence) / 2.0))
    z2n = z * z / n_eff
    denom = 1.0 + z2n
    centre = (p_hat + z2n / 2.0) / denom
    half = z * math.sqrt(p_hat * (1.0 - p_hat) / n_eff + z2n / (4.0 * n_eff)) / denom
    lo = 0.0 if p_hat == 0.0 else max(0.0, centre - half)
    hi = 1.0 if p_hat == 1.0 else min(1.0, centre + half)
    return (lo, hi)


def _contact_indices(x: FloatArray, clearance: float, terminated: bool) -> list[int]:
    """Sample indices of contact entries (``len(x)`` for an unrecorded terminal contact)."""
    inside = np.abs(x) >= clearance
    prev = np.concatenate(([False], inside[:-1]))
    idx = [int(i) for i in np.flatnonzero(inside & ~prev)]
    if terminated and (x.size == 0 or not inside[-1]):
        idx.append(int(x.size))
    return idx


def _iat(centred_segments: Sequence[FloatArray], n_total: int) -> float:
    """Geyer initial monotone sequence estimate of tau for centred segments."""
    max_len = max(s.size for s in centred_segments)
    acov = np.zeros(max_len)
    for y in centred_segments:
        m = y.size
        if m == 0:
            continue
        nfft = sp_fft.next_fast_len(2 * m)
        f = sp_fft.rfft(y, nfft)
        acov[:m] += sp_fft.irfft(f * np.conj(f), nfft)[:m]
    acov /= n_total
    if not acov[0] > 0.0:
        return math.nan
    rho = acov / acov[0]
    n_pairs = rho.size // 2
    if n_pairs == 0:
        return 1.0
    gamma = rho[0 : 2 * n_pairs : 2] + rho[1 : 2 * n_pairs : 2]
    nonpos = np.flatnonzero(gamma <= 0.0)
    k = int(nonpos[0]) if nonpos.size else n_pairs
    if k == 0:
        return 1.0
    gamma = np.minimum.accumulate(gamma[:k])
    tau = -1.0 + 2.0 * float(gamma.sum())
    return max(tau, 1.0)


def _ks_statistic(z_sorted: FloatArray, name: str, params: tuple[float, ...]) -> float:
    """The two-sided KS statistic D of sorted samples against a law, the float
    ``scipy.stats.ks_1samp`` computes (``max(i/n - F, F - (i-1)/n)``), without the
    p-value: a fitted candidate that is not chosen needs only D. The law's CDF is evaluated
    only where a block bound says the maximum can be (:func:`hyperloop_env.sts.ks.ks_statistic`)."""
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        return ks_statistic(z_sorted, lambda z: law_cdf(name, z, *params))


def _ks_pvalue(d: float, n: int) -> float:
    """The two-sided KS p-value of statistic ``d`` on ``n`` samples, as ``ks_1samp``'s
    default (exact) method gives it: ``scipy.stats.kstwo.sf`` clipped to [0, 1], its exact
    Smirnov sum compiled (:func:`hyperloop_env.sts.ks.kstwo_sf`); NaN for a non-finite D."""
    return kstwo_sf(d, n)


def _ks(z: FloatArray, name: str, params: tuple[float, ...]) -> tuple[float, float]:
    """(D, p) of the two-sided one-sample KS test (``scipy.stats.kstest``'s values)."""
    d = _ks_statistic(np.sort(z), name, params)
    return d, _ks_pvalue(d, z.size)


class _Start(Exception):
    """Carries the start scipy's ``fit`` hands its optimizer (:func:`_scipy_start`)."""

    def __init__(self, x0: FloatArray) -> None:
        super().__init__("scipy's start")
        self.x0 = x0


def _capture_start(func: Any, x0: Any, args: tuple = (), disp: int = 0) -> FloatArray:
    raise _Start(np.array(x0, dtype=np.float64))


def _scipy_start(name: str, z: FloatArray) -> FloatArray | None:
    """The start ``scipy.stats.<name>.fit(z)`` hands its optimizer (the law's own rule:
    the skew-normal's moments, genextreme's skewness), taken from the optimizer hook, so
    that scipy's evaluation of its slow objective at the result is skipped; None where
    scipy fails before it."""
    try:
        getattr(stats, name).fit(z, optimizer=_capture_start)
    except _Start as start:
        return start.x0
    except Exception:  # scipy's own failure: the scipy path reports it
        return None
    return None


def _fit(
    name: str, z: FloatArray, start: tuple[float, ...] | None = None
) -> tuple[float, ...] | None:
    """Maximum-likelihood parameters of law ``name`` (scipy's ``fit``; from ``start`` if
    given), or None where the fit fails or leaves the law's domain. A compiled law is
    fitted by :func:`newton_fit` from ``start`` or scipy's own start (what scipy's ``fit``
    returns with Newton as its optimizer), by scipy where Newton does not converge."""
    dist = getattr(stats, name)
    if name in COMPILED_LAWS:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            x0 = _scipy_start(name, z) if start is None else np.asarray(start, np.float64)
            theta = None if x0 is None else newton_fit(name, z, x0)
        if theta is not None:
            params = tuple(float(p) for p in theta)
            ok = bool(np.all(dist._argcheck(*params[:-2])))
            return params if ok and all(map(math.isfinite, params)) and params[-1] > 0 else None
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            kw = {"optimizer": fit_optimizer(name, z)} if name in COMPILED_LAWS else {}
            if start is None:
                params = dist.fit(z, **kw)
            else:
                params = dist.fit(z, *start[:-2], loc=start[-2], scale=start[-1], **kw)
    except Exception:  # any optimiser failure just disqualifies the candidate
        return None
    params = tuple(float(p) for p in params)
    if not all(math.isfinite(p) for p in params) or params[-1] <= 0.0:
        return None
    return params


def _normal_limit(z: FloatArray) -> bool:
    """Whether t's likelihood is maximised at ν = ∞, the normal law (already tested): with y
    the samples standardised by their mean and standard deviation (the normal maximum),
    log t_ν(y) = log φ(y) + (y⁴ − 2y² − 1)/(4ν) + O(ν⁻²), so the log-likelihood's slope in
    1/ν at 0 is n (m₄ − 3)/4 with m₄ the sample kurtosis: not positive means no finite ν
    does better near the normal."""
    y = (z - z.mean()) / z.std()
    y2 = y * y  # y⁴ as (y²)²: numpy's power with exponent 4 is a slow pow
    return float(np.mean(y2 * y2)) <= 3.0


def _fit_candidate(name: str, z: FloatArray) -> tuple[float, ...] | None:
    """MLE of a candidate on standardised data, multi-started where scipy's default start is
    known to stall (genextreme: also started from the Gumbel fit); the start with the largest
    log-likelihood wins. None for ``t`` on samples without excess kurtosis: its maximum is
    the normal limit ν = ∞ (:func:`_normal_limit`)."""
    if name == "t" and _normal_limit(z):
        return None
    fits = [_fit(name, z)]
    if name == "genextreme":
        gumbel = _fit("gumbel_r", z)
        if gumbel is not None:
            fits.append(_fit(name, z, (0.0, *gumbel)))
    best, best_ll = None, -math.inf
    dist = getattr(stats, name)
    for params in fits:
        if params is None:
            continue
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            fast = compiled_logpdf(name, z, params)
            ll = float(np.sum(dist.logpdf(z, *params) if fast is None else fast))
        if math.isfinite(ll) and ll > best_ll:
            best, best_ll = params, ll
    return best


def _law_p_unsteady(name: str, params: Any, z_hi: float, z_lo: float) -> Any:
    """P(Z >= z_hi) + P(Z <= z_lo); ``params`` may be arrays (vectorised over replicates)."""
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        p = law_sf(name, z_hi, *params) + law_cdf(name, z_lo, *params)
    return np.clip(p, 0.0, 1.0)


def _to_metres(params: tuple[float, ...], mean: float, std: float) -> tuple[float, ...]:
    return (*params[:-2], mean + std * params[-2], std * params[-1])
