"""Stochastic technical stability (STS) of the magnetic suspension.

Background
----------
The STS criterion treats the gap excursion ``s(t)`` [m] of each magnet unit ("FL", "FR",
"RL", "RR"), after a settling time, as one realisation of a stationary ergodic process.  A
distribution is fitted to the samples and checked with the one-sample Kolmogorov-Smirnov (KS)
test at ``alpha = 0.05``; the unit is *steady* while ``|s| < Omega`` with the clearance
``Omega = 8 mm``.  ``P(steady) = P(|s| < Omega)`` under the fitted law and
``P(unsteady) = 1 - P(steady)``.

Method implemented here (all lengths in metres, times in seconds)
-------------------------------------------------------------------
1. **Settling**: the first ``ceil(settle_s / dt_s)`` samples of every episode are discarded for
   the fit (they still count for contacts).  Several episodes (seeds) are pooled per unit.
2. **Distribution**: the normal law (MLE: sample mean and ``ddof=0`` standard deviation) is
   tried first, as in the paper.  If it is rejected at ``alpha`` by the *selection test* (see
   below), every candidate in ``candidates`` is fitted by maximum likelihood (scipy
   ``rv_continuous.fit``, on data standardised by the sample mean/std for numerical robustness)
   and the law with the smallest full-sample KS statistic is chosen; the normal stays a
   candidate.  When more than ``max_fit_samples`` samples are pooled, candidate MLEs are computed
   on a deterministic, evenly spaced subsample (indices ``linspace(0, n - 1, max_fit_samples)``),
   which adds parameter noise of order ``1/sqrt(max_fit_samples)``; that is below the resolution
   of the thinned KS test whenever the effective sample size is smaller, but it can inflate the
   raw full-sample KS statistic of non-normal laws on very long signals.
3. **KS caveats**: (a) the parameters are estimated from the same data, so the textbook KS
   p-value is conservative (Lilliefors effect: it accepts too often); (b) the KS p-value assumes
   independent samples.  Gap signals sampled at 1 ms are strongly autocorrelated, and then the
   *raw* KS test rejects even the true law: on exactly Gaussian AR(1) signals with estimated
   parameters it rejected the normal law in 22 % of cases at tau ~ 39 samples (n = 2e4) and in
   90 % at tau ~ 200 (n = 1e5), and the longer the signal the closer to 100 %.  (Estimating mean
   and std removes much of the dependence effect; with known parameters it would be worse.)
   We therefore also report the integrated autocorrelation time ``tau`` (Geyer's initial
   monotone positive sequence estimator, pooled over episodes without crossing episode
   boundaries), the effective sample size
   ``ESS = n / tau`` (clipped to ``[1, n]``) and a *thinned* KS test on every
   ``round(tau)``-th sample (roughly independent points).  ``selection_test="thinned"`` (default)
   uses the thinned normal test to decide whether the normal law is rejected;
   ``selection_test="raw"`` reproduces the paper's procedure (raw KS on all samples).  For i.i.d.
   signals both are identical.
4. **P(unsteady) of the fitted law** ``p_unsteady_fit = sf(Omega) + cdf(-Omega)``, evaluated
   tail by tail (``sf`` for the upper tail) so tiny probabilities are not lost to cancellation.
5. **Confidence interval** ``p_unsteady_fit_ci`` (95 %): percentile interval of a moving-block
   bootstrap that respects the time-series correlation.  Block length
   ``L = ceil(3 * tau)`` samples (capped by the episode length); blocks are drawn within each
   episode (stratified: every episode is rebuilt from its own blocks, so blocks never straddle
   two episodes).  The fitted ``P(unsteady)`` is recomputed on every replicate:

   * normal law: exact re-estimation of mean and std from block sums;
   * Laplace: exact closed-form MLE (median, mean absolute deviation) on each replicate;
   * other laws: *one-step (linearised) bootstrap*: ``theta_b = theta - H^-1 (g_b - g)`` where
     ``g_b`` is the mean log-likelihood score over the replicate, ``g`` the full-sample mean
     score and ``H`` the Hessian of the mean log-likelihood (numerical derivatives in a chart
     with log-scale and log-df); asymptotically equivalent to refitting each replicate (on
     t, skew-normal and logistic fits the intervals agreed with 200 full refits within a few
     per cent) but orders of magnitude cheaper.  If ``H`` is not negative definite or the
     scores are not finite, the code falls back to full MLE refits of at most 50 replicates.

   The RNG is seeded (``rng=0`` by default) so the interval is reproducible.  Measured coverage
   of the 95 % interval (n = 2e4, 200 replications each): i.i.d. normal 0.95, Gaussian AR(1)
   with tau ~ 39 0.96, Student t(4) 0.95, Laplace 0.955; with only ~100 effective samples
   (AR(1), tau ~ 200) it undercovers slightly (0.895), as block bootstraps do with few blocks.
   ``empirical_exceedance_ci`` is a Wilson interval on the fraction of samples with
   ``|s| >= Omega`` using ``n_eff = n / max(tau_signal, tau_indicator)``.  The KS test is
   insensitive to the tails, so a law can pass it and still extrapolate the tail badly (e.g. a
   logistic fit to filtered Student-t noise predicted 7e-06 where 6e-04 of the samples were
   beyond Omega).  ``tail_consistent`` is False when the fitted-law interval and the empirical
   interval are disjoint; the Markdown table marks such units with a dagger.
6. **Contacts and failed episodes** (statistical honesty): a contact event is an entry into
   ``|s| >= Omega`` (counted over the *whole* episode, settling included; ``n_contacts_settling``
   says how many fell in the settling window).  An episode that terminated in contact is never
   dropped: its pre-contact samples enter the pool and its terminal contact is counted (once, if
   the last recorded sample is not already ``>= Omega``).  The fit describes the process
   *conditioned on survival*; since a contact is absorbing (the episode ends, the magnet clamps)
   the long-run fraction of time spent unsteady in a failed realisation is 1.  With ``f`` the
   fraction of episodes that terminated in contact (vehicle level: the units are rigidly coupled
   and no unit is observed after termination, so ``f`` applies to every unit) we report

   ``p_unsteady = f + (1 - f) * p_unsteady_fit``  (>= f), and
   ``p_unsteady_ci = (f + (1 - f) * lo, f + (1 - f) * hi)``

   i.e. inference *conditional on the simulated episodes* (a single failed episode gives
   ``p_unsteady = 1`` with CI ``(1, 1)``).  The uncertainty of the failure rate for *new* seeds
   is reported separately as ``episode_failure_rate_ci`` (Clopper-Pearson, 95 %).  If too few
   samples remain to fit a law (fewer than ``min_samples``), ``distribution = "none"``, test
   statistics are NaN, ``p_unsteady = f`` if ``f > 0`` (a lower bound) else NaN, and
   ``p_unsteady_ci = (f, 1)``.  A constant signal gives the degenerate law: ``p_unsteady_fit``
   is 1 if ``|value| >= Omega`` else 0.

Discrepancy with the paper
--------------------------
The paper's own numbers cannot be recomputed from its normal parameters: a normal law with mean
0.643564 mm and std 1.500849 mm gives ``P(|s| >= 8 mm) = normal_p_unsteady(0.643564e-3,
1.500849e-3) ~= 4.8e-07`` (upper tail 4.75e-07, lower tail 4.2e-09), whereas the paper reports
P(unsteady) = 0.00356.  Reproducing 0.00356 with that mean would need std ~= 2.67 mm.  This
module reports what the fitted law actually implies and never rounds small probabilities to 0
(see :func:`format_probability`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import fft as sp_fft
from scipy import stats

__all__ = [
    "DEFAULT_CANDIDATES",
    "DEFAULT_CLEARANCE_M",
    "UNIT_NAMES",
    "EpisodeSignal",
    "STSReport",
    "UnitSTS",
    "analyse_episodes",
    "analyse_unit",
    "count_contacts",
    "effective_sample_size",
    "format_probability",
    "integrated_autocorrelation_time",
    "normal_p_unsteady",
    "paper_table_markdown",
    "wilson_interval",
]

UNIT_NAMES: tuple[str, str, str, str] = ("FL", "FR", "RL", "RR")
DEFAULT_CLEARANCE_M: float = 0.008
DEFAULT_CANDIDATES: tuple[str, ...] = ("norm", "t", "logistic", "laplace", "genextreme", "skewnorm")
CONFIDENCE: float = 0.95
"""Confidence level of every interval reported by this module."""

_BLOCK_TAU_FACTOR = 3.0  # moving-block length in units of the integrated autocorrelation time
_REFIT_FALLBACK_MAX = 50  # replicates refitted by full MLE when the one-step bootstrap fails
_CLOSED_FORM_REFIT = frozenset({"laplace"})  # laws whose MLE is cheap enough to refit exactly
_POSITIVE_SHAPES: dict[str, tuple[bool, ...]] = {"t": (True,), "genextreme": (False,)}
_DEGENERATE_RTOL = 1e-12
_MAX_GATHER = 2_000_000  # max block draws materialised at once in the bootstrap

FloatArray = NDArray[np.float64]


# --------------------------------------------------------------------------------------------
# Small public helpers
# --------------------------------------------------------------------------------------------


def normal_p_unsteady(
    mean_m: float, std_m: float, clearance_m: float = DEFAULT_CLEARANCE_M
) -> float:
    """P(|s| >= clearance) for ``s ~ N(mean, std^2)``.

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


def format_probability(p: float, *, complement_of: float | None = None) -> str:
    """Format a probability for tables without ever rounding small values to zero.

    Values below 1e-3 use scientific notation (``5.1e-07``); exact 0 and 1 print as ``0`` and
    ``1``; NaN prints as ``n/a``.  If ``complement_of`` is given (``p = 1 - complement_of``) and
    that complement is below 1e-3, the value is printed as ``1 - 5.1e-07`` instead of a
    misleading ``1.0000``.
    """
    if p is None or not math.isfinite(p):
        return "n/a"
    if complement_of is not None and math.isfinite(complement_of) and 0.0 < complement_of < 1e-3:
        return f"1 - {complement_of:.1e}"
    if p == 0.0:
        return "0"
    if p == 1.0:
        return "1"
    if p < 1e-3:
        return f"{p:.1e}"
    return f"{p:#.4g}"


# --------------------------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------------------------


def _json_value(value: Any) -> Any:
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, (tuple, list)):
        return [_json_value(v) for v in value]
    return value


@dataclass(frozen=True)
class UnitSTS:
    """STS result of one magnet unit (pooled over the analysed episodes).

    Lengths in metres, times in seconds, probabilities in [0, 1]; NaN means "not available"
    (``to_dict`` turns NaN into ``None``).
    """

    name: str
    n_samples: int
    """Post-settling samples analysed (pooled over episodes)."""
    n_episodes: int
    mean_m: float
    std_m: float
    """Sample standard deviation (``ddof=0``, the normal MLE) [m]."""
    distribution: str
    """Chosen law: a scipy.stats name, ``"degenerate"`` (constant signal) or ``"none"``."""
    distribution_params: tuple[float, ...]
    """scipy parameter order (shapes..., loc [m], scale [m]); ``(value,)`` if degenerate."""
    ks_statistic: float
    """Raw KS statistic of the chosen law on all pooled samples."""
    ks_pvalue: float
    ks_accepted: bool
    """``ks_pvalue >= alpha`` (raw test, as in the paper)."""
    normal_ks_statistic: float
    normal_ks_pvalue: float
    normal_accepted: bool
    """Raw KS test of the normal fit, always reported as the paper does."""
    effective_sample_size: float
    autocorrelation_time: float
    """Integrated autocorrelation time tau [samples]."""
    thinning_stride: int
    thinned_n_samples: int
    thinned_ks_pvalue: float
    """KS p-value of the chosen law on the sample thinned with stride ``round(tau)``."""
    thinned_ks_accepted: bool
    thinned_normal_ks_pvalue: float
    selection_test: str
    """``"thinned"`` or ``"raw"``: the test that decided whether the normal was rejected."""
    p_unsteady_fit: float
    """P(|s| >= Omega) under the fitted law (conditioned on survival)."""
    p_unsteady_fit_ci: tuple[float, float]
    ci_method: str
    block_length: int
    """Moving-block bootstrap block length [samples]."""
    n_boot: int
    """Number of valid bootstrap replicates behind ``p_unsteady_fit_ci``."""
    p_steady: float
    p_unsteady: float
    """``f + (1 - f) * p_unsteady_fit`` with ``f`` the episode failure rate (>= ``f``)."""
    p_unsteady_ci: tuple[float, float]
    empirical_exceedance: float
    """Fraction of post-settling samples with ``|s| >= Omega``."""
    empirical_exceedance_ci: tuple[float, float]
    tail_consistent: bool | None
    """False if ``p_unsteady_fit_ci`` and ``empirical_exceedance_ci`` are disjoint (the fitted
    tail contradicts the observed exceedance); None if not assessable."""
    n_contacts: int
    """Entries into ``|s| >= Omega`` over whole episodes, terminal contacts included."""
    n_contacts_settling: int
    n_failed_episodes: int
    """Episodes (vehicle level) that terminated in contact."""
    episode_failure_rate: float
    n_terminal_contacts: int
    """Terminal contacts attributed to this unit."""
    terminated_in_contact: bool
    """True if at least one episode terminated by a contact of this unit."""
    time_to_contact_s: float | None
    """Earliest contact time from the start of an episode [s], None if no contact."""
    clearance_m: float
    alpha: float

    @property
    def p_unsteady_ci_width(self) -> float:
        """Width of ``p_unsteady_ci``."""
        return self.p_unsteady_ci[1] - self.p_unsteady_ci[0]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (NaN/inf -> None, tuples -> lists)."""
        return {f.name: _json_value(getattr(self, f.name)) for f in fields(self)}


@dataclass(frozen=True)
class STSReport:
    """STS of all units over a set of episodes (seeds)."""

    units: tuple[UnitSTS, ...]
    dt_s: float
    clearance_m: float
    settle_s: float
    alpha: float
    n_episodes: int
    n_failed_episodes: int
    episode_failure_rate: float
    episode_failure_rate_ci: tuple[float, float]
    """Clopper-Pearson 95 % interval of the per-episode failure probability (new seeds)."""
    any_contact: bool
    """True if any unit had any contact in any episode (settling included)."""

    @property
    def worst_p_unsteady(self) -> float:
        """Largest ``p_unsteady`` over units (NaN if any unit's value is undetermined)."""
        values = [u.p_unsteady for u in self.units]
        if not values or any(not math.isfinite(v) for v in values):
            return math.nan
        return max(values)

    @property
    def worst_unit(self) -> str | None:
        """Name of the unit with the largest ``p_unsteady`` (None if undetermined)."""
        if not math.isfinite(self.worst_p_unsteady):
            return None
        return max(self.units, key=lambda u: u.p_unsteady).name

    def unit(self, name: str) -> UnitSTS:
        """Result of the unit called ``name``."""
        for u in self.units:
            if u.name == name:
                return u
        raise KeyError(name)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict of the whole report."""
        out: dict[str, Any] = {
            f.name: _json_value(getattr(self, f.name)) for f in fields(self) if f.name != "units"
        }
        out["worst_p_unsteady"] = _json_value(self.worst_p_unsteady)
        out["worst_unit"] = self.worst_unit
        out["units"] = [u.to_dict() for u in self.units]
        return out

    def to_rows(self) -> list[dict[str, Any]]:
        """One flat dict per unit, for CSV (non-finite values -> None)."""
        rows = []
        for u in self.units:
            row = {
                "unit": u.name,
                "n_samples": u.n_samples,
                "n_episodes": u.n_episodes,
                "mean_mm": u.mean_m * 1e3,
                "std_mm": u.std_m * 1e3,
                "distribution": u.distribution,
                "ks_statistic": u.ks_statistic,
                "ks_pvalue": u.ks_pvalue,
                "ks_accepted": u.ks_accepted,
                "thinned_ks_pvalue": u.thinned_ks_pvalue,
                "normal_ks_pvalue": u.normal_ks_pvalue,
                "effective_sample_size": u.effective_sample_size,
                "p_steady": u.p_steady,
                "p_unsteady": u.p_unsteady,
                "p_unsteady_ci_lo": u.p_unsteady_ci[0],
                "p_unsteady_ci_hi": u.p_unsteady_ci[1],
                "p_unsteady_fit": u.p_unsteady_fit,
                "empirical_exceedance": u.empirical_exceedance,
                "tail_consistent": u.tail_consistent,
                "n_contacts": u.n_contacts,
                "n_failed_episodes": u.n_failed_episodes,
                "episode_failure_rate": u.episode_failure_rate,
            }
            rows.append({k: _json_value(v) for k, v in row.items()})
        return rows


@dataclass(frozen=True)
class EpisodeSignal:
    """Gap excursions of one episode.

    Attributes:
        signal: array ``(T, n_units)`` of gap excursions [m] sampled every ``dt_s``.
        terminated_in_contact: the episode ended because a magnet touched.
        contact_units: names (or column indices) of the unit(s) that touched.  If None and the
            episode terminated in contact, the contact is attributed to the units whose last
            sample has ``|s| >= Omega``, else to the unit(s) with the largest ``|s|`` in the last
            sample (all units for an empty signal).
    """

    signal: ArrayLike
    terminated_in_contact: bool = False
    contact_units: tuple[str | int, ...] | None = None


# --------------------------------------------------------------------------------------------
# Validation helpers
# --------------------------------------------------------------------------------------------


def _check_positive(name: str, value: float) -> None:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}") from None
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")


def _validate_common(
    dt_s: float,
    clearance_m: float,
    settle_s: float,
    alpha: float,
    n_boot: int,
    min_samples: int,
    max_fit_samples: int,
    selection_test: str,
    candidates: Sequence[str],
) -> None:
    _check_positive("dt_s", dt_s)
    _check_positive("clearance_m", clearance_m)
    if not (isinstance(settle_s, (int, float)) and math.isfinite(settle_s) and settle_s >= 0):
        raise ValueError(f"settle_s must be a finite number >= 0, got {settle_s!r}")
    if not (isinstance(alpha, (int, float)) and 0.0 < alpha < 1.0):
        raise ValueError(f"alpha must be in (0, 1), got {alpha!r}")
    if not isinstance(n_boot, (int, np.integer)) or n_boot < 0:
        raise ValueError(f"n_boot must be an int >= 0, got {n_boot!r}")
    if not isinstance(min_samples, (int, np.integer)) or min_samples < 3:
        raise ValueError(f"min_samples must be an int >= 3, got {min_samples!r}")
    if not isinstance(max_fit_samples, (int, np.integer)) or max_fit_samples < 100:
        raise ValueError(f"max_fit_samples must be an int >= 100, got {max_fit_samples!r}")
    if selection_test not in ("thinned", "raw"):
        raise ValueError(f"selection_test must be 'thinned' or 'raw', got {selection_test!r}")
    if isinstance(candidates, str) or len(candidates) == 0:
        raise ValueError(f"candidates must be a non-empty sequence of names, got {candidates!r}")
    for name in candidates:
        if not isinstance(getattr(stats, str(name), None), stats.rv_continuous):
            raise ValueError(
                f"candidates: {name!r} is not a continuous distribution of scipy.stats"
            )


def _as_finite_1d(signal: ArrayLike, what: str) -> FloatArray:
    try:
        x = np.asarray(signal, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{what} must be numeric: {exc}") from None
    if x.ndim != 1:
        raise ValueError(f"{what} must be one-dimensional, got shape {x.shape}")
    _check_finite(x, what)
    return x


def _check_finite(x: FloatArray, what: str) -> None:
    bad = ~np.isfinite(x)
    if bad.any():
        first = np.argwhere(bad)[0]
        kind = "NaN" if np.isnan(x[tuple(first)]) else "inf"
        raise ValueError(
            f"{what} contains {int(bad.sum())} non-finite value(s) ({kind} at index "
            f"{tuple(int(i) for i in first) if first.size > 1 else int(first[0])})"
        )


def _as_segments(signal: ArrayLike | Sequence[ArrayLike]) -> list[FloatArray]:
    if isinstance(signal, np.ndarray) and signal.ndim == 1:
        return [_as_finite_1d(signal, "signal")]
    if isinstance(signal, (list, tuple)) and signal and all(np.ndim(s) == 1 for s in signal):
        return [_as_finite_1d(s, f"signal[{i}]") for i, s in enumerate(signal)]
    return [_as_finite_1d(signal, "signal")]


def _to_generator(rng: int | np.random.Generator | None) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or isinstance(rng, (int, np.integer)):
        return np.random.default_rng(rng)
    raise ValueError(f"rng must be None, an int seed or a numpy Generator, got {rng!r}")


# --------------------------------------------------------------------------------------------
# Statistics internals
# --------------------------------------------------------------------------------------------


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


def _ks(z: FloatArray, name: str, params: tuple[float, ...]) -> tuple[float, float]:
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        res = stats.kstest(z, name, args=params)
    return float(res.statistic), float(res.pvalue)


def _fit(
    name: str, z: FloatArray, start: tuple[float, ...] | None = None
) -> tuple[float, ...] | None:
    dist = getattr(stats, name)
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            if start is None:
                params = dist.fit(z)
            else:
                params = dist.fit(z, *start[:-2], loc=start[-2], scale=start[-1])
    except Exception:  # any optimiser failure just disqualifies the candidate
        return None
    params = tuple(float(p) for p in params)
    if not all(math.isfinite(p) for p in params) or params[-1] <= 0.0:
        return None
    return params


def _fit_candidate(name: str, z: FloatArray) -> tuple[float, ...] | None:
    """MLE of a candidate on standardised data, multi-started where scipy's default start is
    known to stall (genextreme: also started from the Gumbel fit); the start with the largest
    log-likelihood wins."""
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
            ll = float(np.sum(dist.logpdf(z, *params)))
        if math.isfinite(ll) and ll > best_ll:
            best, best_ll = params, ll
    return best


def _law_p_unsteady(name: str, params: Any, z_hi: float, z_lo: float) -> Any:
    """P(Z >= z_hi) + P(Z <= z_lo); ``params`` may be arrays (vectorised over replicates)."""
    dist = getattr(stats, name)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        p = dist.sf(z_hi, *params) + dist.cdf(z_lo, *params)
    return np.clip(p, 0.0, 1.0)


def _to_metres(params: tuple[float, ...], mean: float, std: float) -> tuple[float, ...]:
    return (*params[:-2], mean + std * params[-2], std * params[-1])


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
    """Sums over moving-block bootstrap replicates; ``cum`` has a leading zero row."""
    n_blocks = sum(lens.size for _, _, lens in layout)
    out = []
    for size in _chunks(n_boot, n_blocks):
        total = np.zeros((size, *cum.shape[1:]))
        for off, b, lens in layout:
            m = int(lens.sum())
            starts = off + rng.integers(0, m - b + 1, size=(size, lens.size))
            total += (cum[starts + lens] - cum[starts]).sum(axis=1)
        out.append(total)
    return np.concatenate(out, axis=0)


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
        return dist.logpdf(z, *_unchart(phi, mask))

    def scores(phi: FloatArray, h: float = 1e-5) -> FloatArray:
        out = np.empty((z.size, k))
        for j in range(k):
            e = np.zeros(k)
            e[j] = h
            out[:, j] = (loglik(phi + e) - loglik(phi - e)) / (2.0 * h)
        return out

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


# --------------------------------------------------------------------------------------------
# Core analysis
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _ContactInfo:
    n_contacts: int
    n_contacts_settling: int
    n_terminal_contacts: int
    time_to_contact_s: float | None


def _nan_pair() -> tuple[float, float]:
    return (math.nan, math.nan)


def _analyse_pooled(
    name: str,
    segments: Sequence[FloatArray],
    contacts: _ContactInfo,
    n_episodes: int,
    n_failed: int,
    *,
    clearance_m: float,
    alpha: float,
    candidates: Sequence[str],
    rng: np.random.Generator,
    n_boot: int,
    selection_test: str,
    min_samples: int,
    max_fit_samples: int,
) -> UnitSTS:
    segments = [s for s in segments if s.size > 0]
    x = np.concatenate(segments) if segments else np.zeros(0)
    n = int(x.size)
    om = float(clearance_m)
    f = n_failed / n_episodes
    nan = math.nan

    mean = float(x.mean()) if n else nan
    std = float(x.std()) if n >= 2 else nan
    exceed = float(np.mean(np.abs(x) >= om)) if n else nan

    base: dict[str, Any] = {
        "name": name,
        "n_samples": n,
        "n_episodes": n_episodes,
        "mean_m": mean,
        "std_m": std,
        "empirical_exceedance": exceed,
        "n_contacts": contacts.n_contacts,
        "n_contacts_settling": contacts.n_contacts_settling,
        "n_failed_episodes": n_failed,
        "episode_failure_rate": f,
        "n_terminal_contacts": contacts.n_terminal_contacts,
        "terminated_in_contact": contacts.n_terminal_contacts > 0,
        "time_to_contact_s": contacts.time_to_contact_s,
        "clearance_m": om,
        "alpha": float(alpha),
        "selection_test": selection_test,
    }
    no_tests: dict[str, Any] = {
        "ks_statistic": nan,
        "ks_pvalue": nan,
        "ks_accepted": False,
        "normal_ks_statistic": nan,
        "normal_ks_pvalue": nan,
        "normal_accepted": False,
        "effective_sample_size": nan,
        "autocorrelation_time": nan,
        "thinning_stride": 0,
        "thinned_n_samples": 0,
        "thinned_ks_pvalue": nan,
        "thinned_ks_accepted": False,
        "thinned_normal_ks_pvalue": nan,
        "block_length": 0,
        "n_boot": 0,
    }

    def finish(p_fit: float, fit_ci: tuple[float, float], **kw: Any) -> UnitSTS:
        if math.isfinite(p_fit):
            p_un = f + (1.0 - f) * p_fit
            if f == 1.0:
                ci = (1.0, 1.0)
            elif all(math.isfinite(c) for c in fit_ci):
                ci = (f + (1.0 - f) * fit_ci[0], f + (1.0 - f) * fit_ci[1])
            else:
                ci = _nan_pair()
        else:
            p_un = f if f > 0.0 else nan
            ci = (f, 1.0)
        return UnitSTS(
            **base,
            **kw,
            p_unsteady_fit=p_fit,
            p_unsteady_fit_ci=fit_ci,
            p_unsteady=p_un,
            p_steady=1.0 - p_un,
            p_unsteady_ci=ci,
        )

    # -- too few samples: report, never drop ---------------------------------------------------
    if n < min_samples:
        return finish(
            nan,
            _nan_pair(),
            **no_tests,
            distribution="none",
            distribution_params=(),
            ci_method=f"none: fewer than min_samples={min_samples} post-settling samples",
            empirical_exceedance_ci=_nan_pair(),
            tail_consistent=None,
        )

    # -- constant signal: degenerate law ---------------------------------------------------------
    if std <= _DEGENERATE_RTOL * max(om, abs(mean)):
        p_deg = 1.0 if abs(mean) >= om else 0.0
        return finish(
            p_deg,
            (p_deg, p_deg),
            **no_tests,
            distribution="degenerate",
            distribution_params=(mean,),
            ci_method="degenerate law (constant signal)",
            empirical_exceedance_ci=(exceed, exceed),
            tail_consistent=True,
        )

    # -- standardise, autocorrelation, thinning ------------------------------------------------
    z = (x - mean) / std
    z_segments = [(s - mean) / std for s in segments]
    lengths = [s.size for s in segments]
    tau = _iat(z_segments, n)
    ess = n / tau
    stride = max(1, int(round(tau)))
    z_thin = np.concatenate([s[::stride] for s in z_segments])
    z_hi = (om - mean) / std
    z_lo = (-om - mean) / std

    # -- distribution: normal first, then candidates ---------------------------------------------
    norm_params = (0.0, 1.0)
    normal_d, normal_p = _ks(z, "norm", norm_params)
    _, thin_normal_p = _ks(z_thin, "norm", norm_params)
    decide_p = thin_normal_p if selection_test == "thinned" else normal_p
    chosen, chosen_params, chosen_d, chosen_p = "norm", norm_params, normal_d, normal_p
    if not decide_p >= alpha:
        z_fit = z
        if n > max_fit_samples:
            z_fit = z[np.linspace(0, n - 1, max_fit_samples).round().astype(np.int64)]
        for cand in dict.fromkeys(str(c) for c in candidates):
            if cand == "norm":
                continue
            params = _fit_candidate(cand, z_fit)
            if params is None:
                continue
            d, p = _ks(z, cand, params)
            if math.isfinite(d) and d < chosen_d:
                chosen, chosen_params, chosen_d, chosen_p = cand, params, d, p
    _, thin_p = (None, thin_normal_p) if chosen == "norm" else _ks(z_thin, chosen, chosen_params)

    p_fit = float(_law_p_unsteady(chosen, chosen_params, z_hi, z_lo))

    # -- bootstrap CI of the fitted P(unsteady) ------------------------------------------------
    block = max(1, min(int(math.ceil(_BLOCK_TAU_FACTOR * tau)), max(lengths)))
    if n_boot > 0:
        p_b, ci_method = _bootstrap_fit_p(
            chosen, z, chosen_params, lengths, block, z_hi, z_lo, n_boot, max_fit_samples, rng
        )
        n_tried = int(p_b.size)
        p_b = p_b[np.isfinite(p_b)]
        n_valid = int(p_b.size)
        if n_valid >= max(2, n_tried // 2):
            lo, hi = np.quantile(p_b, [(1 - CONFIDENCE) / 2, (1 + CONFIDENCE) / 2])
            fit_ci = (float(lo), float(hi))
        else:
            fit_ci = _nan_pair()
    else:
        n_valid, ci_method, fit_ci = 0, "none (n_boot=0)", _nan_pair()

    # -- Wilson interval of the empirical exceedance with the effective sample size ----------
    tau_ind = nan
    if 0.0 < exceed < 1.0:
        tau_ind = _iat([(np.abs(s) >= om) - exceed for s in segments], n)
    tau_exc = max(tau, tau_ind) if math.isfinite(tau_ind) else tau
    exc_ci = wilson_interval(exceed, n / tau_exc)
    tail_ok: bool | None = None
    if all(math.isfinite(c) for c in (*fit_ci, *exc_ci)):
        tail_ok = not (fit_ci[1] < exc_ci[0] or fit_ci[0] > exc_ci[1])

    return finish(
        p_fit,
        fit_ci,
        distribution=chosen,
        distribution_params=_to_metres(chosen_params, mean, std),
        ks_statistic=chosen_d,
        ks_pvalue=chosen_p,
        ks_accepted=bool(chosen_p >= alpha),
        normal_ks_statistic=normal_d,
        normal_ks_pvalue=normal_p,
        normal_accepted=bool(normal_p >= alpha),
        effective_sample_size=ess,
        autocorrelation_time=tau,
        thinning_stride=stride,
        thinned_n_samples=int(z_thin.size),
        thinned_ks_pvalue=float(thin_p),
        thinned_ks_accepted=bool(thin_p >= alpha),
        thinned_normal_ks_pvalue=thin_normal_p,
        block_length=block,
        n_boot=n_valid,
        ci_method=ci_method,
        empirical_exceedance_ci=exc_ci,
        tail_consistent=tail_ok,
    )


def _settle_samples(settle_s: float, dt_s: float) -> int:
    return int(math.ceil(settle_s / dt_s - 1e-9)) if settle_s > 0 else 0


# --------------------------------------------------------------------------------------------
# Public analysis API
# --------------------------------------------------------------------------------------------


def analyse_unit(
    signal: ArrayLike,
    dt_s: float,
    *,
    clearance_m: float = DEFAULT_CLEARANCE_M,
    settle_s: float = 0.0,
    alpha: float = 0.05,
    name: str = "",
    terminated_in_contact: bool = False,
    candidates: Sequence[str] = DEFAULT_CANDIDATES,
    rng: int | np.random.Generator | None = 0,
    n_boot: int = 1000,
    selection_test: Literal["thinned", "raw"] = "thinned",
    min_samples: int = 20,
    max_fit_samples: int = 20_000,
) -> UnitSTS:
    """STS of one unit from one episode.

    Args:
        signal: gap excursion s(t) [m], 1-D, sampled every ``dt_s``; must be finite.
        dt_s: sampling period [s], ``> 0``.
        clearance_m: clearance Omega [m], ``> 0``.
        settle_s: settling time [s] discarded before the fit (contacts are still counted).
        alpha: KS significance level in (0, 1).
        name: unit name.
        terminated_in_contact: the episode ended by a contact of this unit.  Then
            ``p_unsteady = 1`` with CI ``(1, 1)`` (contact is absorbing, see module docstring)
            while ``p_unsteady_fit`` still describes the pre-contact samples.
        candidates: scipy.stats continuous laws tried when the normal is rejected.
        rng: seed or Generator of the bootstrap (default 0: reproducible; None: OS entropy).
        n_boot: bootstrap replicates (0 disables the bootstrap CI).
        selection_test: ``"thinned"`` (default) or ``"raw"`` KS test deciding normal rejection.
        min_samples: fewer post-settling samples than this -> ``distribution = "none"``.
        max_fit_samples: cap on the samples used by the candidate MLE fits.

    Raises:
        ValueError: non-finite signal values or invalid arguments (the message names them).
    """
    _validate_common(
        dt_s,
        clearance_m,
        settle_s,
        alpha,
        n_boot,
        min_samples,
        max_fit_samples,
        selection_test,
        candidates,
    )
    x = _as_finite_1d(signal, "signal")
    gen = _to_generator(rng)
    n_settle = _settle_samples(settle_s, dt_s)
    idx = _contact_indices(x, float(clearance_m), bool(terminated_in_contact))
    contacts = _ContactInfo(
        n_contacts=len(idx),
        n_contacts_settling=sum(i < n_settle for i in idx),
        n_terminal_contacts=int(bool(terminated_in_contact)),
        time_to_contact_s=idx[0] * float(dt_s) if idx else None,
    )
    return _analyse_pooled(
        name,
        [x[n_settle:]],
        contacts,
        1,
        int(bool(terminated_in_contact)),
        clearance_m=float(clearance_m),
        alpha=float(alpha),
        candidates=candidates,
        rng=gen,
        n_boot=int(n_boot),
        selection_test=selection_test,
        min_samples=int(min_samples),
        max_fit_samples=int(max_fit_samples),
    )


EpisodeLike = EpisodeSignal | tuple[ArrayLike, bool] | ArrayLike


def _normalise_episode(
    ep: EpisodeLike, i: int, unit_names: Sequence[str]
) -> tuple[FloatArray, bool, tuple[str | int, ...] | None]:
    if isinstance(ep, EpisodeSignal):
        sig, term, who = ep.signal, bool(ep.terminated_in_contact), ep.contact_units
    elif isinstance(ep, tuple) and len(ep) == 2 and isinstance(ep[1], (bool, np.bool_)):
        sig, term, who = ep[0], bool(ep[1]), None
    else:
        sig, term, who = ep, False, None
    try:
        arr = np.asarray(sig, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"episodes[{i}] signal must be numeric: {exc}") from None
    n_units = len(unit_names)
    if arr.ndim == 1 and n_units == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[1] != n_units:
        raise ValueError(
            f"episodes[{i}] signal must have shape (T, {n_units}) to match unit_names "
            f"{tuple(unit_names)}, got {arr.shape}"
        )
    _check_finite(arr, f"episodes[{i}] signal")
    if who is not None and not term:
        raise ValueError(f"episodes[{i}]: contact_units given but terminated_in_contact is False")
    return arr, term, who


def _attribute_contact(
    arr: FloatArray, who: tuple[str | int, ...] | None, unit_names: Sequence[str], om: float, i: int
) -> set[int]:
    if who is not None:
        out = set()
        for u in who:
            if isinstance(u, (int, np.integer)) and 0 <= int(u) < len(unit_names):
                out.add(int(u))
            elif u in unit_names:
                out.add(list(unit_names).index(u))
            else:
                raise ValueError(f"episodes[{i}]: unknown contact unit {u!r}")
        return out
    if arr.shape[0] == 0:
        return set(range(len(unit_names)))
    last = np.abs(arr[-1])
    hit = set(np.flatnonzero(last >= om).tolist())
    return hit if hit else set(np.flatnonzero(last == last.max()).tolist())


def _spawn(rng: int | np.random.Generator | None, n: int) -> list[np.random.Generator]:
    if isinstance(rng, np.random.Generator):
        return list(rng.spawn(n))
    if rng is None or isinstance(rng, (int, np.integer)):
        return [np.random.default_rng(s) for s in np.random.SeedSequence(rng).spawn(n)]
    raise ValueError(f"rng must be None, an int seed or a numpy Generator, got {rng!r}")


def analyse_episodes(
    episodes: Sequence[EpisodeLike],
    dt_s: float,
    *,
    unit_names: Sequence[str] = UNIT_NAMES,
    clearance_m: float = DEFAULT_CLEARANCE_M,
    settle_s: float = 0.0,
    alpha: float = 0.05,
    candidates: Sequence[str] = DEFAULT_CANDIDATES,
    rng: int | np.random.Generator | None = 0,
    n_boot: int = 1000,
    selection_test: Literal["thinned", "raw"] = "thinned",
    min_samples: int = 20,
    max_fit_samples: int = 20_000,
) -> STSReport:
    """STS of every unit, pooling the post-settling samples of several episodes (seeds).

    Args:
        episodes: each an :class:`EpisodeSignal`, a tuple ``(signal (T, n_units) [m],
            terminated_in_contact)`` or a bare ``(T, n_units)`` array (not terminated).
            Episodes that terminated in contact are never dropped (see module docstring).
        dt_s, clearance_m, settle_s, alpha, candidates, n_boot, selection_test, min_samples,
            max_fit_samples: as in :func:`analyse_unit`.
        unit_names: names of the signal columns.
        rng: seed or Generator; independent child streams are spawned per unit.

    Returns:
        :class:`STSReport` with one :class:`UnitSTS` per unit.
    """
    _validate_common(
        dt_s,
        clearance_m,
        settle_s,
        alpha,
        n_boot,
        min_samples,
        max_fit_samples,
        selection_test,
        candidates,
    )
    if isinstance(unit_names, str) or len(unit_names) == 0:
        raise ValueError(f"unit_names must be a non-empty sequence of names, got {unit_names!r}")
    if len(set(unit_names)) != len(unit_names):
        raise ValueError(f"unit_names must be unique, got {tuple(unit_names)}")
    if isinstance(episodes, np.ndarray) or len(episodes) == 0:
        raise ValueError("episodes must be a non-empty sequence of episodes")
    om = float(clearance_m)
    n_units = len(unit_names)
    n_settle = _settle_samples(settle_s, dt_s)

    segments: list[list[FloatArray]] = [[] for _ in range(n_units)]
    n_contacts = [0] * n_units
    n_settling = [0] * n_units
    n_terminal = [0] * n_units
    first_contact: list[float | None] = [None] * n_units
    n_failed = 0
    any_contact = False
    for i, ep in enumerate(episodes):
        arr, term, who = _normalise_episode(ep, i, unit_names)
        culprits = _attribute_contact(arr, who, unit_names, om, i) if term else set()
        n_failed += int(term)
        for u in range(n_units):
            col = arr[:, u]
            segments[u].append(col[n_settle:])
            idx = _contact_indices(col, om, u in culprits)
            n_contacts[u] += len(idx)
            n_settling[u] += sum(j < n_settle for j in idx)
            n_terminal[u] += int(u in culprits)
            if idx:
                any_contact = True
                t = idx[0] * float(dt_s)
                first_contact[u] = t if first_contact[u] is None else min(first_contact[u], t)

    n_ep = len(episodes)
    gens = _spawn(rng, n_units)
    units = tuple(
        _analyse_pooled(
            str(unit_names[u]),
            segments[u],
            _ContactInfo(n_contacts[u], n_settling[u], n_terminal[u], first_contact[u]),
            n_ep,
            n_failed,
            clearance_m=om,
            alpha=float(alpha),
            candidates=candidates,
            rng=gens[u],
            n_boot=int(n_boot),
            selection_test=selection_test,
            min_samples=int(min_samples),
            max_fit_samples=int(max_fit_samples),
        )
        for u in range(n_units)
    )
    ci = stats.binomtest(n_failed, n_ep).proportion_ci(CONFIDENCE, method="exact")
    return STSReport(
        units=units,
        dt_s=float(dt_s),
        clearance_m=om,
        settle_s=float(settle_s),
        alpha=float(alpha),
        n_episodes=n_ep,
        n_failed_episodes=n_failed,
        episode_failure_rate=n_failed / n_ep,
        episode_failure_rate_ci=(float(ci.low), float(ci.high)),
        any_contact=any_contact or n_failed > 0,
    )


# --------------------------------------------------------------------------------------------
# Presentation
# --------------------------------------------------------------------------------------------


def _fmt_p(p: float) -> str:
    if not math.isfinite(p):
        return "n/a"
    if p == 0.0:
        return "0"
    return f"{p:.1e}" if p < 1e-3 else f"{p:.3g}"


def _law_label(u: UnitSTS) -> str:
    if u.distribution in ("none", "degenerate"):
        return u.distribution
    shapes = getattr(stats, u.distribution).shapes
    if not shapes:
        return u.distribution
    names = [s.strip() for s in shapes.split(",")]
    vals = ", ".join(f"{k}={v:.3g}" for k, v in zip(names, u.distribution_params, strict=False))
    return f"{u.distribution}({vals})"


def _p_unsteady_cell(u: UnitSTS) -> str:
    cell = format_probability(u.p_unsteady)
    if u.episode_failure_rate > 0.0 and math.isfinite(u.p_unsteady_fit):
        cell += f" (fit {format_probability(u.p_unsteady_fit)})"
    if u.tail_consistent is False:
        cell += " \u2020"
    return cell


def paper_table_markdown(report: STSReport, title: str = "") -> str:
    """Markdown table in the form of the paper's Tables 2-3, one row per unit.

    Small probabilities are printed in scientific notation (never rounded to 0.0000) and
    ``P(steady)`` close to one as ``1 - 5.1e-07``.
    """
    lines = []
    if title:
        lines += [f"**{title}**", ""]
    lines += [
        "| Unit | mean [mm] | std [mm] | distribution | KS p (accepted?) | P(steady) "
        "| P(unsteady) | 95 % CI | empirical exceedance | contacts |",
        "|---|---:|---:|---|---|---:|---:|---|---:|---:|",
    ]
    for u in report.units:
        mean = f"{u.mean_m * 1e3:.4f}" if math.isfinite(u.mean_m) else "n/a"
        std = f"{u.std_m * 1e3:.4f}" if math.isfinite(u.std_m) else "n/a"
        if math.isfinite(u.ks_pvalue):
            ks = f"{_fmt_p(u.ks_pvalue)} ({'yes' if u.ks_accepted else 'no'})"
            ks += f"; thinned {_fmt_p(u.thinned_ks_pvalue)}"
        else:
            ks = "n/a"
        ci = f"[{format_probability(u.p_unsteady_ci[0])}, {format_probability(u.p_unsteady_ci[1])}]"
        lines.append(
            f"| {u.name} | {mean} | {std} | {_law_label(u)} | {ks} "
            f"| {format_probability(u.p_steady, complement_of=u.p_unsteady)} "
            f"| {_p_unsteady_cell(u)} | {ci} "
            f"| {format_probability(u.empirical_exceedance)} | {u.n_contacts} |"
        )
    lines += [
        "",
        f"Clearance {report.clearance_m * 1e3:g} mm, settling {report.settle_s:g} s, "
        f"alpha {report.alpha:g}; {report.n_episodes} episode(s), "
        f"{report.n_failed_episodes} terminated in contact (failure rate "
        f"{format_probability(report.episode_failure_rate)}, 95 % CI "
        f"[{format_probability(report.episode_failure_rate_ci[0])}, "
        f"{format_probability(report.episode_failure_rate_ci[1])}]).",
        "KS p-values use parameters fitted on the same data (conservative, Lilliefors); the "
        "raw test assumes independent samples, the thinned one uses every round(tau)-th sample. "
        "P(unsteady) = f + (1 - f) * P_fit with f the episode failure rate (P_fit shown as "
        "'fit' when f > 0).",
    ]
    if any(u.tail_consistent is False for u in report.units):
        lines.append(
            "\u2020 The fitted law's tail contradicts the empirical exceedance (disjoint 95 % "
            "intervals): its P(unsteady) extrapolation is unreliable for this unit."
        )
    return "\n".join(lines) + "\n"
