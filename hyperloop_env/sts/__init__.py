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

from hyperloop_env.sts.analysis import analyse_episodes, analyse_unit, worst_index
from hyperloop_env.sts.common import CONFIDENCE, DEFAULT_CANDIDATES, DEFAULT_CLEARANCE_M, UNIT_NAMES
from hyperloop_env.sts.estimators import (
    count_contacts,
    effective_sample_size,
    integrated_autocorrelation_time,
    normal_p_unsteady,
    wilson_interval,
)
from hyperloop_env.sts.report import format_probability, paper_table_markdown
from hyperloop_env.sts.results import EpisodeSignal, STSReport, UnitSTS

__all__ = [
    "CONFIDENCE",
    "DEFAULT_CANDIDATES",
    "DEFAULT_CLEARANCE_M",
    "UNIT_NAMES",
    "EpisodeSignal",
    "STSReport",
    "UnitSTS",
    "analyse_episodes",
    "worst_index",
    "analyse_unit",
    "count_contacts",
    "effective_sample_size",
    "format_probability",
    "integrated_autocorrelation_time",
    "normal_p_unsteady",
    "paper_table_markdown",
    "wilson_interval",
]
