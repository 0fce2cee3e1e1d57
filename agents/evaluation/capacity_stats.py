"""Statistics of per-seed capacities: lognormal fit, empirical CDF, paired comparison.

The method is incremental dynamic analysis (IDA; Vamvatsikos & Cornell 2002, "Incremental
dynamic analysis", Earthquake Engineering and Structural Dynamics 31(3)): for one
controller, condition and disturbance family, every seed's disturbance record is scaled up
until a magnet touches, and a bisection finds the seed's *capacity* ``c_i > 0``, the
smallest severity at which that seed's run touches. The capacities of the seeds are a
sample of the capacity distribution; its CDF is the fragility function
``P(contact | s) = P(C <= s)``. A seed that still flies at the family's upper bound ``u``
is *right-censored*: its capacity is only known to exceed ``u``; it is stored as
``c_i = u`` with ``censored_i = True``. All censoring is at that single upper bound and
every touched capacity is ``<= u``.

* :func:`fit_capacity_lognormal` — the lognormal capacity model ``ln C ~ N(ln θ, β²)``
  (median θ, dispersion β) by maximum likelihood with right censoring::

      ℓ(μ, β) = Σ_touched [ln φ((ln c_i − μ)/β) − ln β] + Σ_censored ln(1 − Φ((ln u_j − μ)/β))

  (the log-likelihood of ``ln c``; θ = exp μ). In the coordinates ``m = μ/β, h = 1/β``
  ℓ is globally concave (Olsen 1978, Econometrica 46(5), for the Tobit model), so
  Newton's method with step halving finds the unique maximum whenever at least two
  touched capacities differ. With nothing censored the maximum is the closed form
  ``θ = exp(mean ln c)``, ``β = std(ln c)`` with ``ddof = 0`` (the MLE; the unbiased
  ``ddof = 1`` value is larger by ``sqrt(n/(n−1))``). Intervals: nonparametric bootstrap
  (seeds resampled with replacement), percentile intervals; the empirical median of the
  capacities with its bootstrap interval is reported next to the fit.
* :func:`empirical_cdf` — the empirical fragility (the ECDF of the capacities) with the
  Dvoretzky–Kiefer–Wolfowitz simultaneous band (Massart's constant).
* :func:`p_contact`, :func:`p_contact_empirical` — fitted and empirical fragility.
* :func:`compare_paired`, :func:`verdict_matrix`, :func:`decided_fraction` — two
  controllers on the same seeds: geometric mean of the per-seed capacity ratios, paired
  bootstrap interval, Wilcoxon signed-rank test and a verdict.
* :func:`binary_outcome_fit` — the cross-check: the capacities turned into touched / flew
  outcomes at fixed severity levels and fitted by the binary-outcome fragility MLE of
  Baker (2015, "Efficient analytical fragility function fitting using dynamic structural
  analysis data", Earthquake Spectra 31(1)), i.e.
  :func:`agents.evaluation.fragility_fit.fit_lognormal`.

Every function returns plain Python values (floats, ints, bools, strings, lists, None):
the results can be written with ``json.dumps(..., allow_nan=False)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from scipy import special, stats

from agents.evaluation.fragility_fit import fit_lognormal

CONFIDENCE = 0.95
EQUIVALENCE = 0.05

__all__ = [
    "binary_outcome_fit",
    "compare_paired",
    "decided_fraction",
    "empirical_cdf",
    "fit_capacity_lognormal",
    "p_contact",
    "p_contact_empirical",
    "verdict_matrix",
]


# --------------------------------------------------------------------------------------
# input checks and small helpers
# --------------------------------------------------------------------------------------


def _as_capacities(values: Any, name: str) -> np.ndarray:
    x = np.asarray(values, dtype=float)
    if x.ndim != 1 or x.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D array, got shape {x.shape}")
    if not np.all(np.isfinite(x)) or np.any(x <= 0):
        raise ValueError(f"{name} must be finite and > 0 (capacities are severities)")
    return x


def _as_censored(values: Any, n: int, name: str) -> np.ndarray:
    if values is None:
        return np.zeros(n, dtype=bool)
    c = np.asarray(values)
    if c.shape != (n,):
        raise ValueError(f"{name} must have one flag per capacity ({n}), got shape {c.shape}")
    if c.dtype != bool and not np.all((c == 0) | (c == 1)):
        raise ValueError(f"{name} must be booleans (or 0/1)")
    return c.astype(bool)


def _check_confidence(confidence: float) -> None:
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")


def _opt(x: float | None) -> float | None:
    return None if x is None or not math.isfinite(x) else float(x)


def _percentile_interval(
    v: np.ndarray, confidence: float, lower_if_unbounded: float | None = None
) -> list[float | None]:
    """Percentile interval of bootstrap replicates ``v`` (NaN dropped, +inf allowed: a
    replicate only known to be "above the bound"). An end that falls among the +inf
    replicates is unbounded: the upper end is then None, the lower end
    ``lower_if_unbounded`` (the bound the +inf replicates are known to exceed)."""
    v = v[~np.isnan(v)]
    if v.size < 2:
        return [None, None]
    finite = v[np.isfinite(v)]
    if finite.size == 0:
        return [_opt(lower_if_unbounded), None]
    top = float(finite.max())
    big = np.finfo(float).max / 4
    q = np.quantile(np.where(np.isfinite(v), v, big), [(1 - confidence) / 2, (1 + confidence) / 2])
    lo = float(q[0]) if q[0] <= top else _opt(lower_if_unbounded)
    hi = float(q[1]) if q[1] <= top else None
    return [lo, hi]


# --------------------------------------------------------------------------------------
# censored lognormal MLE (vectorised over bootstrap replicates)
# --------------------------------------------------------------------------------------


def _censored_normal_mle(
    s0: np.ndarray,
    s1: np.ndarray,
    s2: np.ndarray,
    ucens: np.ndarray,
    k: np.ndarray,
    max_iter: int = 100,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MLE (μ, σ) of a normal sample with right censoring, for B samples at once.

    Sample b is given by its touched sufficient statistics ``s0[b] = Σ w``, ``s1[b] = Σ w x``,
    ``s2[b] = Σ w x²`` and by ``k[b, j]``, the number of values censored at ``ucens[j]``.
    Every sample must have two different touched values. Newton's method with step halving
    in the concave coordinates ``(m, h) = (μ/σ, 1/σ)``; returns (μ, σ, converged)."""
    n_tot = s0 + k.sum(axis=1)
    t1 = s1 + k @ ucens
    t2 = s2 + k @ (ucens * ucens)
    mu0 = t1 / n_tot
    sd0 = np.sqrt(np.maximum(t2 / n_tot - mu0 * mu0, 0.0))
    sd0 = np.where(sd0 > 0, sd0, 1.0)
    m, h = mu0 / sd0, 1.0 / sd0

    cur = _loglik_rows(m, h, s0, s1, s2, k, ucens)
    active = np.ones(m.shape, dtype=bool)
    converged = np.zeros(m.shape, dtype=bool)
    for _ in range(max_iter):
        if not active.any():
            break
        a = np.flatnonzero(active)
        ma, ha, s0a, s1a, s2a, ka = m[a], h[a], s0[a], s1[a], s2[a], k[a]
        # touched part: s0 ln h − ½ Σ w (h x − m)²
        g_m = ha * s1a - ma * s0a
        g_h = s0a / ha - (ha * s2a - ma * s1a)
        h_mm = -s0a.copy()
        h_mh = s1a.copy()
        h_hh = -s0a / (ha * ha) - s2a
        # censored part: Σ k ln Φ(m − h u); d/dw ln Φ = λ, d²/dw² = −λ (w + λ)
        w = ma[:, None] - ha[:, None] * ucens[None, :]
        lam = np.exp(stats.norm.logpdf(w) - special.log_ndtr(w))
        d2 = -lam * (w + lam)
        g_m += np.sum(ka * lam, axis=1)
        g_h -= np.sum(ka * lam * ucens, axis=1)
        h_mm += np.sum(ka * d2, axis=1)
        h_mh -= np.sum(ka * d2 * ucens, axis=1)
        h_hh += np.sum(ka * d2 * ucens * ucens, axis=1)
        det = h_mm * h_hh - h_mh * h_mh
        step_m = -(h_hh * g_m - h_mh * g_h) / det
        step_h = -(-h_mh * g_m + h_mm * g_h) / det
        decrement = g_m * step_m + g_h * step_h  # Newton decrement², >= 0 (H negative definite)
        done = ~(decrement > 1e-22 * n_tot[a])
        converged[a[done]] = True
        active[a[done]] = False
        a, step_m, step_h = a[~done], step_m[~done], step_h[~done]
        if a.size == 0:
            break
        t = np.ones(a.size)
        accepted = np.zeros(a.size, dtype=bool)
        new_m, new_h = m[a].copy(), h[a].copy()
        for _halving in range(60):
            todo = ~accepted
            if not todo.any():
                break
            cm = m[a][todo] + t[todo] * step_m[todo]
            ch = h[a][todo] + t[todo] * step_h[todo]
            ll = np.full(cm.shape, -np.inf)
            pos = ch > 0
            if pos.any():
                sub = a[todo][pos]
                ll[pos] = _loglik_rows(cm[pos], ch[pos], s0[sub], s1[sub], s2[sub], k[sub], ucens)
            ok = np.isfinite(ll) & (ll >= cur[a][todo] - 1e-12 * (1.0 + np.abs(cur[a][todo])))
            idx = np.flatnonzero(todo)
            new_m[idx[ok]], new_h[idx[ok]] = cm[ok], ch[ok]
            cur[a[idx[ok]]] = ll[ok]
            accepted[idx[ok]] = True
            t[idx[~ok]] *= 0.5
        m[a], h[a] = new_m, new_h
        active[a[~accepted]] = False  # no ascent step found: at the maximum to rounding
        converged[a[~accepted]] = True
    return m / h, 1.0 / h, converged


def _loglik_rows(
    m: np.ndarray,
    h: np.ndarray,
    s0: np.ndarray,
    s1: np.ndarray,
    s2: np.ndarray,
    k: np.ndarray,
    ucens: np.ndarray,
) -> np.ndarray:
    """Log-likelihood (up to a constant) in (m, h) coordinates, row by row."""
    unc = s0 * np.log(h) - 0.5 * (h * h * s2 - 2 * h * m * s1 + m * m * s0)
    w = m[:, None] - h[:, None] * ucens[None, :]
    return unc + np.sum(k * special.log_ndtr(w), axis=1)


def _log_likelihood(mu: float, beta: float, x: np.ndarray, cens: np.ndarray) -> float:
    """ℓ(μ, β) of the module docstring for ``x = ln c`` (normal density of ln c)."""
    zu = (x[~cens] - mu) / beta
    zc = (x[cens] - mu) / beta
    return float(np.sum(stats.norm.logpdf(zu) - math.log(beta)) + np.sum(stats.norm.logsf(zc)))


def _fit_batch(
    x: np.ndarray, cens: np.ndarray, idx: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(θ, β, degenerate, all_censored) for the samples ``x[idx[b]]`` (rows of ``idx``).

    Degenerate rows (one distinct touched value) get their limit θ = that value, β = 0;
    rows with nothing touched get θ = +inf (above the bound), β = NaN."""
    loc = float(np.mean(x))
    scale = float(np.std(x)) or 1.0
    xs = (x - loc) / scale
    unc = ~cens
    ucens, code = np.unique(xs[cens], return_inverse=True)
    code_full = np.full(x.size, -1)
    code_full[cens] = code
    n_b = idx.shape[0]
    wu = unc[idx]
    xu = np.where(wu, xs[idx], 0.0)
    s0 = wu.sum(axis=1).astype(float)
    s1 = xu.sum(axis=1)
    s2 = (xu * xu).sum(axis=1)
    kc = np.zeros((n_b, ucens.size))
    if ucens.size:
        cc = code_full[idx]
        rows = np.broadcast_to(np.arange(n_b)[:, None], cc.shape)
        sel = cc >= 0
        flat = rows[sel] * ucens.size + cc[sel]
        kc = np.bincount(flat, minlength=n_b * ucens.size).reshape(n_b, ucens.size)
        kc = kc.astype(float)
    lo = np.where(wu, xs[idx], np.inf).min(axis=1)
    hi = np.where(wu, xs[idx], -np.inf).max(axis=1)
    all_cens = s0 == 0
    degenerate = ~all_cens & (lo == hi)
    theta = np.full(n_b, np.inf)
    beta = np.full(n_b, np.nan)
    theta[degenerate] = np.exp(loc + scale * lo[degenerate])
    beta[degenerate] = 0.0
    ok = ~all_cens & ~degenerate
    if ok.any():
        mu, sd, _conv = _censored_normal_mle(s0[ok], s1[ok], s2[ok], ucens, kc[ok])
        theta[ok] = np.exp(loc + scale * mu)
        beta[ok] = scale * sd
    return theta, beta, degenerate, all_cens


def _median_with_bound(values: np.ndarray, cens: np.ndarray) -> tuple[float | None, bool]:
    """Sample median with censored values at their bound, and whether it is only a lower
    bound (a censored value enters the median: half or more of the seeds censored)."""
    med = float(np.median(values))
    n = values.size
    upper_middle = n // 2  # 0-based index of the upper middle order statistic
    order = np.lexsort((cens, values))  # ties: touched before censored
    return med, bool(cens[order][upper_middle])


def fit_capacity_lognormal(
    capacities: Any,
    censored: Any,
    *,
    n_boot: int = 1000,
    seed: int = 0,
    confidence: float = CONFIDENCE,
) -> dict[str, Any]:
    """Lognormal fit of capacities with right censoring, bootstrap intervals.

    ``capacities`` (> 0) and ``censored`` (one bool per seed; a censored seed's capacity is
    its bound ``u``). The fit is the censored maximum likelihood of the module docstring;
    with nothing censored it equals the closed form ``θ = exp(mean ln c)`` and
    ``β = std(ln c, ddof=0)``. Intervals are percentile intervals of ``n_boot`` bootstrap
    replicates (seeds resampled with replacement, ``numpy.random.default_rng(seed)``: the
    same seed gives the same intervals).

    Returns (all floats are plain floats or None):

    * ``status`` — ``"fit"``; ``"all_censored"`` (no seed touched: θ is only bounded below,
      ``theta_lower_bound = u``, θ and β None); ``"too_few_uncensored"`` (one touched seed:
      θ and β are not identifiable, None); ``"zero_dispersion"`` (all touched capacities
      equal: the likelihood's supremum is the limit β → 0, θ = that capacity; no interval).
    * ``theta``, ``beta``, ``mu`` (= ln θ), ``log_likelihood`` (of ln c, as in the module
      docstring), ``theta_ci``, ``beta_ci`` (``[lo, hi]``), ``theta_above_bound`` (θ > u:
      the median is extrapolated beyond the largest tested severity).
    * ``theta_lower_bound`` — u when all seeds are censored, else None.
    * ``median_empirical``, ``median_empirical_ci``, ``median_is_lower_bound`` — the sample
      median with censored capacities at u; it is only a lower bound when half or more of
      the seeds are censored. In its bootstrap censored capacities count as +inf, so an
      upper end that falls among them is None (unbounded).
    * ``n``, ``n_censored``, ``censoring_bound`` (largest censored value, None if none),
      ``n_boot``, ``n_boot_degenerate`` (replicates with one distinct touched value; they
      enter the intervals at β = 0, θ = that value), ``n_boot_all_censored`` (replicates
      with no touched seed: θ enters as +inf, β is left out), ``confidence``.
    """
    c = _as_capacities(capacities, "capacities")
    cens = _as_censored(censored, c.size, "censored")
    _check_confidence(confidence)
    if n_boot < 0:
        raise ValueError(f"n_boot must be >= 0, got {n_boot}")
    x = np.log(c)
    n, n_cens = int(c.size), int(cens.sum())
    u = float(c[cens].max()) if n_cens else None
    out: dict[str, Any] = {
        "status": "fit",
        "theta": None,
        "beta": None,
        "mu": None,
        "log_likelihood": None,
        "theta_ci": [None, None],
        "beta_ci": [None, None],
        "theta_above_bound": None,
        "theta_lower_bound": None,
        "median_empirical": None,
        "median_empirical_ci": [None, None],
        "median_is_lower_bound": None,
        "n": n,
        "n_censored": n_cens,
        "censoring_bound": u,
        "n_boot": 0,
        "n_boot_degenerate": 0,
        "n_boot_all_censored": 0,
        "confidence": confidence,
    }
    med, med_is_bound = _median_with_bound(c, cens)
    out["median_empirical"], out["median_is_lower_bound"] = med, med_is_bound
    touched = np.unique(c[~cens])
    if touched.size == 0:
        out["status"] = "all_censored"
        out["theta_lower_bound"] = float(c[cens].min())
    elif (~cens).sum() < 2:
        out["status"] = "too_few_uncensored"
    elif touched.size == 1:
        out["status"] = "zero_dispersion"
        out["theta"], out["beta"], out["mu"] = float(touched[0]), 0.0, float(np.log(touched[0]))
    else:
        theta, beta, _, _ = _fit_batch(x, cens, np.arange(n)[None, :])
        out["theta"], out["beta"] = float(theta[0]), float(beta[0])
        out["mu"] = float(np.log(theta[0]))
        out["log_likelihood"] = _log_likelihood(out["mu"], out["beta"], x, cens)
    if out["theta"] is not None:
        out["theta_above_bound"] = bool(u is not None and out["theta"] > u)
    if n_boot == 0 or n < 2:
        return out
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, n, size=(int(n_boot), n))
    out["n_boot"] = int(n_boot)
    med_b = np.median(np.where(cens, np.inf, c)[idx], axis=1)
    out["median_empirical_ci"] = _percentile_interval(med_b, confidence, u)
    if out["status"] == "fit":
        th_b, be_b, deg, allc = _fit_batch(x, cens, idx)
        out["theta_ci"] = _percentile_interval(th_b, confidence, u)
        out["beta_ci"] = _percentile_interval(be_b, confidence)
        out["n_boot_degenerate"] = int(deg.sum())
        out["n_boot_all_censored"] = int(allc.sum())
    return out


# --------------------------------------------------------------------------------------
# empirical fragility
# --------------------------------------------------------------------------------------


def empirical_cdf(capacities: Any, censored: Any, confidence: float = CONFIDENCE) -> dict[str, Any]:
    """The empirical capacity distribution (empirical fragility) with a DKW band.

    ``F(x) = #{touched seeds with c_i <= x} / n`` over all ``n`` seeds. With all censoring
    at the single upper bound u (every censored value >= every touched capacity) the
    Kaplan–Meier estimator is exactly this ECDF for ``x < u``: every seed is at risk until
    u, so the product-limit factors telescope to ``1 − k/n``. Beyond u the CDF is unknown
    (censored seeds touch somewhere above u). Censoring below a touched capacity is
    rejected (ValueError): that would need the general Kaplan–Meier estimator, for which the
    DKW band does not hold.

    The band is the Dvoretzky–Kiefer–Wolfowitz inequality with Massart's constant:
    ``P(sup |F_n − F| > ε) <= 2 exp(−2 n ε²)``, so ``ε = sqrt(ln(2/α) / (2n))``,
    ``α = 1 − confidence``, holds simultaneously for all x (clipped to [0, 1]).

    Returns ``x`` (sorted distinct touched capacities, the steps), ``F`` (the ECDF at and
    right after each step), ``lower``, ``upper`` (the band), ``epsilon``, ``n``,
    ``n_censored`` and ``defined_below`` (u, the severity up to which F is known; None
    without censoring: F is then known everywhere).
    """
    c = _as_capacities(capacities, "capacities")
    cens = _as_censored(censored, c.size, "censored")
    _check_confidence(confidence)
    n = c.size
    if cens.any() and (~cens).any() and c[cens].min() < c[~cens].max():
        raise ValueError(
            "a censored capacity lies below a touched one: censoring is not at a single "
            "upper bound (the ECDF is then not the Kaplan–Meier estimate)"
        )
    xs, counts = np.unique(c[~cens], return_counts=True)
    f = np.cumsum(counts) / n
    eps = math.sqrt(math.log(2.0 / (1.0 - confidence)) / (2.0 * n))
    return {
        "x": xs.tolist(),
        "F": f.tolist(),
        "lower": np.clip(f - eps, 0.0, 1.0).tolist(),
        "upper": np.clip(f + eps, 0.0, 1.0).tolist(),
        "epsilon": eps,
        "n": int(n),
        "n_censored": int(cens.sum()),
        "defined_below": float(c[cens].min()) if cens.any() else None,
        "confidence": confidence,
    }


def p_contact(severity: Any, theta: float, beta: float) -> Any:
    """Lognormal fragility ``Φ(ln(s/θ)/β)`` (vectorised; a float for a scalar ``severity``).

    ``s <= 0`` gives 0; ``β = 0`` is the step function ``[s >= θ]``."""
    if not (theta > 0 and math.isfinite(theta)) or not (beta >= 0 and math.isfinite(beta)):
        raise ValueError(f"need θ > 0 and β >= 0 finite, got θ={theta}, β={beta}")
    s = np.asarray(severity, dtype=float)
    with np.errstate(divide="ignore"):
        if beta == 0:
            p = (s >= theta).astype(float)
        else:
            p = stats.norm.cdf(np.log(np.where(s > 0, s, 0.0) / theta) / beta)
    p = np.where(s > 0, p, 0.0)
    return float(p) if p.ndim == 0 else p


def p_contact_empirical(severity: Any, capacities: Any, censored: Any) -> Any:
    """Fraction of seeds whose capacity is ``<= severity`` (vectorised; float for a scalar).

    Censored seeds count as not touched at every severity. That is exact up to their bound
    u; above u it makes the fraction a lower bound (they touch somewhere above u)."""
    c = _as_capacities(capacities, "capacities")
    cens = _as_censored(censored, c.size, "censored")
    touched = np.sort(c[~cens])
    s = np.asarray(severity, dtype=float)
    p = np.searchsorted(touched, s, side="right") / c.size
    return float(p) if p.ndim == 0 else p


# --------------------------------------------------------------------------------------
# paired comparison
# --------------------------------------------------------------------------------------


def _wilcoxon_p(d: np.ndarray, alternative: str = "two-sided") -> float:
    if d.size == 0 or np.all(d == 0):
        return 1.0
    return float(stats.wilcoxon(d, zero_method="zsplit", alternative=alternative).pvalue)


def compare_paired(
    cap_a: Any,
    cens_a: Any,
    cap_b: Any,
    cens_b: Any,
    *,
    n_boot: int = 2000,
    seed: int = 0,
    confidence: float = CONFIDENCE,
    equivalence: float = EQUIVALENCE,
) -> dict[str, Any]:
    """Paired comparison of two controllers' capacities on the same seeds (same order).

    Per seed ``d_i = ln a_i − ln b_i``; the ratio of median capacities A/B is estimated by
    ``exp(mean d)``, the geometric mean of the per-seed ratios (under the lognormal model
    with a common β it is exactly θ_A/θ_B). Its interval is the percentile interval of a
    paired bootstrap (seed indices resampled, the same for A and B; ``default_rng(seed)``).
    The test is the two-sided Wilcoxon signed-rank test of ``d`` (``scipy.stats.wilcoxon``,
    ``zero_method="zsplit"``: exact ties ``d_i = 0`` stay in and split their ranks between
    the signs, which can only make a difference harder to show). ``α = 1 − confidence``.

    Censoring (a censored capacity is its bound u, the true one is larger):

    * both censored: the seed carries no information (both fly at u); it is left out of the
      ratio, the bootstrap and the test (``n_used`` seeds remain). If more than half of the
      seeds are censored for both the verdict is ``"undecided"``.
    * one censored: ``d_i`` is a bound that understates the censored side's advantage. A
      win *for* the censored side is therefore conservative. A win *against* it must also
      hold in the worst case: the opponent's one-sided censored seeds are moved to the
      largest ranks in the opponent's favour (their true ``|d_i|`` can be arbitrarily large)
      and the one-sided Wilcoxon p-value of the claim, doubled, must stay below α
      (``p_value_worst_case``). Equivalence is never claimed when a seed is censored on
      exactly one side (its ratio is only bounded, it may be far from 1).

    Verdict: ``"equivalent"`` if the interval lies inside ``[1/(1+eq), 1+eq]``;
    ``"A above B"`` if its lower end is > 1 and p < α; ``"B above A"`` if its upper end is
    < 1 and p < α; otherwise (or when a censoring rule above blocks it) ``"undecided"``.

    Returns ``ratio``, ``lo``, ``hi``, ``p_value``, ``p_value_worst_case`` (None unless a
    win is claimed against a side with one-sided censored seeds), ``verdict``, ``reason``
    (short text), ``n`` (seeds), ``n_used``, ``n_censored_a``, ``n_censored_b``,
    ``n_both_censored``, ``confidence``, ``equivalence``, ``n_boot``. ``ratio``, ``lo``,
    ``hi`` are None when no seed is usable.
    """
    a, b, ca, cb = _paired_inputs(
        cap_a, cens_a, cap_b, cens_b, n_boot=n_boot, confidence=confidence, equivalence=equivalence
    )
    alpha = 1.0 - confidence
    n = int(a.size)
    both = ca & cb
    only_a, only_b = ca & ~cb, cb & ~ca
    out: dict[str, Any] = {
        "ratio": None,
        "lo": None,
        "hi": None,
        "p_value": None,
        "p_value_worst_case": None,
        "verdict": "undecided",
        "reason": "",
        "n": n,
        "n_used": int((~both).sum()),
        "n_censored_a": int(ca.sum()),
        "n_censored_b": int(cb.sum()),
        "n_both_censored": int(both.sum()),
        "confidence": confidence,
        "equivalence": equivalence,
        "n_boot": int(n_boot),
    }
    use = ~both
    d = np.log(a[use]) - np.log(b[use])
    if d.size == 0:
        out["reason"] = "every seed censored for both"
        return out
    out["ratio"] = float(np.exp(np.mean(d)))
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, d.size, size=(int(n_boot), d.size))
    lo, hi = np.quantile(np.exp(d[idx].mean(axis=1)), [alpha / 2, 1 - alpha / 2])
    out["lo"], out["hi"] = float(lo), float(hi)
    p = _wilcoxon_p(d)
    out["p_value"] = p
    if 2 * int(both.sum()) > n:
        out["reason"] = f"{int(both.sum())} of {n} seeds censored for both"
        return out
    return _paired_verdict(
        out, d, p, lo, hi, only_a[use], only_b[use], alpha=alpha, equivalence=equivalence
    )


def _paired_inputs(
    cap_a: Any,
    cens_a: Any,
    cap_b: Any,
    cens_b: Any,
    *,
    n_boot: int,
    confidence: float,
    equivalence: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`compare_paired`'s arguments checked (ValueError naming the argument): the two
    sides' capacities and censoring flags on the same number of seeds."""
    a = _as_capacities(cap_a, "cap_a")
    b = _as_capacities(cap_b, "cap_b")
    if b.size != a.size:
        raise ValueError(f"cap_b has {b.size} seeds, cap_a has {a.size}: need the same seeds")
    ca = _as_censored(cens_a, a.size, "cens_a")
    cb = _as_censored(cens_b, b.size, "cens_b")
    _check_confidence(confidence)
    if not equivalence > 0:
        raise ValueError(f"equivalence must be > 0, got {equivalence}")
    if n_boot < 1:
        raise ValueError(f"n_boot must be >= 1, got {n_boot}")
    return a, b, ca, cb


def _paired_verdict(
    out: dict[str, Any],
    d: np.ndarray,
    p: float,
    lo: float,
    hi: float,
    oa: np.ndarray,
    ob: np.ndarray,
    *,
    alpha: float,
    equivalence: float,
) -> dict[str, Any]:
    """:func:`compare_paired`'s verdict and reason written into ``out`` (returned) from the
    used seeds' log-ratios ``d``, the test's ``p``, the interval [lo, hi] and which used
    seeds are censored on A's side only (``oa``) or B's only (``ob``)."""
    if 1.0 / (1.0 + equivalence) <= lo and hi <= 1.0 + equivalence:
        if oa.any() or ob.any():
            out["reason"] = (
                f"interval within ±{equivalence:g} but {int(oa.sum() + ob.sum())} "
                "seeds censored on one side only"
            )
        else:
            out["verdict"], out["reason"] = "equivalent", f"interval within ±{equivalence:g}"
        return out
    if lo > 1.0 and p < alpha:
        claim, against = "A above B", ob
    elif hi < 1.0 and p < alpha:
        claim, against = "B above A", oa
    else:
        out["reason"] = "interval includes 1" if lo <= 1.0 <= hi else f"p >= {alpha:g}"
        return out
    if against.any():
        sign = 1.0 if claim == "A above B" else -1.0
        worst = d.copy()
        # above every |d|, in their observed order (ties only where d ties)
        worst[against] = -sign * (2.0 * np.max(np.abs(d)) + 1.0 + np.abs(d[against]))
        p_w = min(1.0, 2.0 * _wilcoxon_p(worst, "greater" if sign > 0 else "less"))
        out["p_value_worst_case"] = p_w
        if p_w >= alpha:
            out["reason"] = (
                f"{claim} not robust to {int(against.sum())} seeds censored for "
                f"the other side (worst-case p = {p_w:.3g})"
            )
            return out
    out["verdict"] = claim
    out["reason"] = f"interval excludes 1, p = {p:.3g}"
    return out


def verdict_matrix(entrants: Mapping[str, tuple[Any, ...]], **kw: Any) -> list[dict[str, Any]]:
    """:func:`compare_paired` for every pair (a, b) with a before b in ``entrants``' order.

    ``entrants`` maps a name to ``(capacities, censored)`` on the same seeds, or to
    ``(capacities, censored, seeds)``: then each pair is compared on the seeds the two have
    in common (in a's order; an entrant flown on fewer seeds is paired on those). Keyword
    arguments go to :func:`compare_paired` (every pair gets the same bootstrap ``seed``).
    Returns one dict per pair: ``a``, ``b`` (names), ``winner`` (the name of the side
    above, None unless the verdict is a win) and the keys of :func:`compare_paired`."""
    names = list(entrants)
    rows = []
    for i, na in enumerate(names):
        for nb in names[i + 1 :]:
            res = compare_paired(*on_common_seeds(entrants[na], entrants[nb], na, nb), **kw)
            winner = {"A above B": na, "B above A": nb}.get(res["verdict"])
            rows.append({"a": na, "b": nb, "winner": winner, **res})
    return rows


def on_common_seeds(
    a: tuple[Any, ...], b: tuple[Any, ...], na: str, nb: str
) -> tuple[Any, Any, Any, Any]:
    """(cap_a, cens_a, cap_b, cens_b) on the seeds both have (``a``/``b``: (capacities,
    censored[, seeds])); without seeds on either side, as they are."""
    if len(a) == 2 and len(b) == 2:
        return a[0], a[1], b[0], b[1]
    if len(a) != 3 or len(b) != 3:
        raise ValueError(f"{na!r}, {nb!r}: give seeds for every entrant or for none")
    pos_b = {int(sd): k for k, sd in enumerate(b[2])}
    ia = [k for k, sd in enumerate(a[2]) if int(sd) in pos_b]
    ib = [pos_b[int(a[2][k])] for k in ia]
    if len(ia) < 2:
        raise ValueError(f"{na!r} and {nb!r} share {len(ia)} seeds: a paired comparison needs 2")
    ca, sa, cb, sb = (np.asarray(x) for x in (a[0], a[1], b[0], b[1]))
    return ca[ia], sa[ia], cb[ib], sb[ib]


def decided_fraction(matrix: Sequence[Mapping[str, Any]] | Mapping[Any, Any]) -> float | None:
    """Fraction of the pairs of a :func:`verdict_matrix` whose verdict is not
    ``"undecided"`` (None for no pairs). Accepts the list or a dict of results."""
    rows = list(matrix.values()) if isinstance(matrix, Mapping) else list(matrix)
    if not rows:
        return None
    return sum(r["verdict"] != "undecided" for r in rows) / len(rows)


# --------------------------------------------------------------------------------------
# binary-outcome cross-check
# --------------------------------------------------------------------------------------


def binary_outcome_fit(capacities: Any, censored: Any, levels: Any) -> dict[str, Any]:
    """The capacities as touched / flew outcomes at ``levels``, fitted by the binary MLE.

    A seed touches at level s iff it is not censored and ``c_i <= s`` (IDA assumes a seed
    that touches at s touches at every larger severity); a censored seed flies at every
    level up to its bound u. Above u a censored seed's outcome is unknown, and leaving
    those seeds out would bias the level towards contact (the seeds left are the ones that
    touched below u), so levels above the smallest censoring bound are dropped (reported
    in ``levels_dropped``): every seed has a known outcome at every level kept. The fit is
    :func:`agents.evaluation.fragility_fit.fit_lognormal` (Baker 2015) of ``z`` contacts
    in ``n`` runs per level; its keys (``status``, ``theta``, ``beta``, bounds for
    degenerate data, ``log_likelihood``) are returned with NaN as None, plus ``levels``,
    ``n_runs``, ``n_contacts`` and ``levels_dropped``. The outcomes at different levels
    come from the same seeds, so they are not independent binomial counts: the point fit is
    a valid cross-check, a binomial bootstrap of it would give too narrow intervals (none
    is returned).
    """
    c = _as_capacities(capacities, "capacities")
    cens = _as_censored(censored, c.size, "censored")
    s = np.asarray(levels, dtype=float)
    if s.ndim != 1 or s.size == 0 or not np.all(np.isfinite(s)) or np.any(s <= 0):
        raise ValueError("levels must be a non-empty 1-D array of finite severities > 0")
    s = np.unique(s)
    bound = float(c[cens].min()) if cens.any() else math.inf
    dropped = s[s > bound]
    s = s[s <= bound]
    if s.size == 0:
        raise ValueError(f"every level is above the censoring bound {bound:g}")
    n_runs = np.full(s.size, c.size)
    n_hit = ((~cens)[None, :] & (c[None, :] <= s[:, None])).sum(axis=1)
    fit = fit_lognormal(s, n_runs, n_hit)
    out = {k: (_opt(v) if isinstance(v, float) else v) for k, v in fit.items()}
    out.update(
        levels=s.tolist(),
        n_runs=n_runs.tolist(),
        n_contacts=n_hit.tolist(),
        levels_dropped=dropped.tolist(),
    )
    return out
