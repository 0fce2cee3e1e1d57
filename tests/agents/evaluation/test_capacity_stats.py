"""Capacity statistics: censored lognormal MLE, ECDF with DKW band, paired comparison."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import optimize, stats

from agents.evaluation.capacity_stats import (
    binary_outcome_fit,
    compare_paired,
    decided_fraction,
    empirical_cdf,
    fit_capacity_lognormal,
    p_contact,
    p_contact_empirical,
    verdict_matrix,
)

THETA, BETA, U = 0.4, 0.3, 0.5


def _population(n: int, seed: int, u: float | None = U) -> tuple[np.ndarray, np.ndarray]:
    """Lognormal capacities (θ = 0.4, β = 0.3), right-censored at ``u`` as the benchmark
    stores them (c = u, censored = True)."""
    c = np.exp(np.random.default_rng(seed).normal(math.log(THETA), BETA, n))
    if u is None:
        return c, np.zeros(n, dtype=bool)
    cens = c > u
    return np.where(cens, u, c), cens


# --------------------------------------------------------------------------------------
# lognormal fit
# --------------------------------------------------------------------------------------


def test_uncensored_mle_is_the_closed_form() -> None:
    c, cens = _population(300, seed=11, u=None)
    fit = fit_capacity_lognormal(c, cens, n_boot=0)
    assert fit["status"] == "fit"
    assert fit["theta"] == pytest.approx(math.exp(np.mean(np.log(c))), rel=1e-9, abs=0)
    assert fit["beta"] == pytest.approx(float(np.std(np.log(c), ddof=0)), rel=1e-9, abs=0)
    # ddof=0 (MLE), not the unbiased ddof=1 value
    assert fit["beta"] != pytest.approx(float(np.std(np.log(c), ddof=1)), rel=1e-4)


def test_censored_mle_maximises_the_censored_likelihood() -> None:
    c, cens = _population(150, seed=5)
    assert 20 < cens.sum() < 60
    fit = fit_capacity_lognormal(c, cens, n_boot=0)
    x = np.log(c)

    def nll(v: np.ndarray) -> float:  # independent: −ℓ(μ, ln β) written out with scipy
        mu, beta = v[0], math.exp(v[1])
        return -float(
            np.sum(stats.norm.logpdf(x[~cens], mu, beta))
            + np.sum(stats.norm.logsf(x[cens], mu, beta))
        )

    res = optimize.minimize(
        nll,
        x0=[0.0, 0.0],
        method="Nelder-Mead",
        options={"xatol": 1e-11, "fatol": 1e-13, "maxiter": 5000},
    )
    assert fit["theta"] == pytest.approx(math.exp(res.x[0]), rel=1e-6)
    assert fit["beta"] == pytest.approx(math.exp(res.x[1]), rel=1e-6)
    assert fit["log_likelihood"] == pytest.approx(-res.fun, abs=1e-8)


def test_large_population_recovered_with_and_without_censoring() -> None:
    c, _ = _population(2000, seed=1, u=None)
    full = fit_capacity_lognormal(c, None, n_boot=200)
    assert full["theta"] == pytest.approx(THETA, rel=0.02)
    assert full["beta"] == pytest.approx(BETA, rel=0.03)

    cc, cens = _population(2000, seed=1)  # the same capacities, censored at u = 0.5
    assert 0.18 < cens.mean() < 0.28  # P(c > 0.5) = 1 − Φ(ln 1.25 / 0.3) = 0.228
    fit = fit_capacity_lognormal(cc, cens, n_boot=200)
    assert fit["n_censored"] == int(cens.sum()) and fit["censoring_bound"] == U
    assert fit["theta"] == pytest.approx(THETA, rel=0.02)
    assert fit["beta"] == pytest.approx(BETA, rel=0.03)
    assert fit["theta_above_bound"] is False
    # naive: the censored seeds taken as touching at u -> β far too small, θ biased low
    naive = fit_capacity_lognormal(cc, None, n_boot=0)
    assert naive["beta"] < 0.85 * BETA
    assert naive["theta"] < 0.97 * THETA
    assert abs(fit["beta"] - BETA) < 0.25 * abs(naive["beta"] - BETA)


def test_bootstrap_interval_width_and_coverage() -> None:
    # one moderate sample: the interval covers the truth and has the asymptotic width
    c, cens = _population(100, seed=7)
    fit = fit_capacity_lognormal(c, cens, n_boot=1000, seed=3)
    lo, hi = fit["theta_ci"]
    assert lo < THETA < hi
    assert fit["beta_ci"][0] < BETA < fit["beta_ci"][1]
    # the width of ln θ's interval: 2·1.96·SE(μ̂), SE from the observed information of the
    # censored likelihood (numerical Hessian of the log-likelihood written out with scipy)
    x = np.log(c)

    def ll(mu: float, beta: float) -> float:
        return float(
            np.sum(stats.norm.logpdf(x[~cens], mu, beta))
            + np.sum(stats.norm.logsf(x[cens], mu, beta))
        )

    mu, b, h = fit["mu"], fit["beta"], 1e-4
    d_mm = (ll(mu + h, b) - 2 * ll(mu, b) + ll(mu - h, b)) / h**2
    d_bb = (ll(mu, b + h) - 2 * ll(mu, b) + ll(mu, b - h)) / h**2
    d_mb = (ll(mu + h, b + h) - ll(mu + h, b - h) - ll(mu - h, b + h) + ll(mu - h, b - h)) / (
        4 * h * h
    )
    hess = np.array([[d_mm, d_mb], [d_mb, d_bb]])
    se_mu = math.sqrt(np.linalg.inv(-hess)[0, 0])
    assert se_mu > b / 10  # censoring costs information
    assert math.log(hi / lo) == pytest.approx(2 * 1.96 * se_mu, rel=0.15)
    # coverage over many samples near the nominal 95 %
    hits = 0
    for k in range(100):
        ck, sk = _population(60, seed=1000 + k)
        f = fit_capacity_lognormal(ck, sk, n_boot=400, seed=k)
        hits += f["theta_ci"][0] < THETA < f["theta_ci"][1]
    assert 0.88 <= hits / 100 <= 1.0


def test_bootstrap_is_deterministic_in_the_seed() -> None:
    c, cens = _population(80, seed=9)
    a = fit_capacity_lognormal(c, cens, n_boot=300, seed=4)
    b = fit_capacity_lognormal(c, cens, n_boot=300, seed=4)
    other = fit_capacity_lognormal(c, cens, n_boot=300, seed=5)
    assert a == b
    assert a["theta_ci"] != other["theta_ci"]
    assert a["theta"] == other["theta"]


def test_empirical_median_and_its_bound() -> None:
    fit = fit_capacity_lognormal([0.1, 0.3, 0.2, 0.5, 0.5], [0, 0, 0, 1, 1], n_boot=0)
    assert fit["median_empirical"] == 0.3 and fit["median_is_lower_bound"] is False
    fit = fit_capacity_lognormal([0.1, 0.2, 0.5, 0.5], [0, 0, 1, 1], n_boot=0)
    assert fit["median_empirical"] == pytest.approx(0.35)  # (0.2 + u)/2: only a lower bound
    assert fit["median_is_lower_bound"] is True


def test_edge_cases_all_censored_and_too_few_touched() -> None:
    allc = fit_capacity_lognormal([U] * 6, [True] * 6, n_boot=100)
    assert allc["status"] == "all_censored"
    assert allc["theta"] is None and allc["beta"] is None
    assert allc["theta_lower_bound"] == U
    assert allc["median_empirical_ci"] == [U, None]  # median > u, no upper end
    one = fit_capacity_lognormal([0.3, U, U], [False, True, True], n_boot=100)
    assert one["status"] == "too_few_uncensored"
    assert one["theta"] is None and one["beta"] is None
    zero = fit_capacity_lognormal([0.3, 0.3, U], [False, False, True], n_boot=0)
    assert zero["status"] == "zero_dispersion"
    assert (zero["theta"], zero["beta"]) == (0.3, 0.0)
    for res in (allc, one, zero):
        json.dumps(res, allow_nan=False)


def test_fit_input_validation() -> None:
    with pytest.raises(ValueError, match="capacities"):
        fit_capacity_lognormal([0.3, -0.1], [False, False])
    with pytest.raises(ValueError, match="capacities"):
        fit_capacity_lognormal([0.3, float("nan")], [False, False])
    with pytest.raises(ValueError, match="censored"):
        fit_capacity_lognormal([0.3, 0.4], [False])


# --------------------------------------------------------------------------------------
# empirical CDF, fragility
# --------------------------------------------------------------------------------------


def test_ecdf_values_and_dkw_band_width() -> None:
    e = empirical_cdf([0.3, 0.1, 0.2, 0.2, U, U], [0, 0, 0, 0, 1, 1])
    assert e["x"] == [0.1, 0.2, 0.3]
    assert e["F"] == pytest.approx([1 / 6, 3 / 6, 4 / 6])
    eps = math.sqrt(math.log(2 / 0.05) / (2 * 6))
    assert e["epsilon"] == pytest.approx(eps, rel=1e-12)
    assert e["lower"] == pytest.approx([max(f - eps, 0) for f in e["F"]])
    assert e["upper"] == pytest.approx([min(f + eps, 1) for f in e["F"]])
    assert e["defined_below"] == U

    c, cens = _population(400, seed=2)
    e = empirical_cdf(c, cens, confidence=0.9)
    f, lo, hi = map(np.asarray, (e["F"], e["lower"], e["upper"]))
    eps = math.sqrt(math.log(2 / 0.1) / (2 * 400))
    inner = (f > eps) & (f < 1 - eps)
    assert inner.sum() > 100
    assert np.allclose(hi[inner] - f[inner], eps, rtol=0, atol=1e-12)
    assert np.allclose(f[inner] - lo[inner], eps, rtol=0, atol=1e-12)


def test_ecdf_is_kaplan_meier_with_censoring_at_the_bound() -> None:
    c, cens = _population(200, seed=4)
    e = empirical_cdf(c, cens)
    # product-limit estimator written out: S(t) = Π_{t_i <= t} (1 − d_i / r_i)
    surv, km = 1.0, []
    for t in e["x"]:
        at_risk = np.sum(c >= t)
        deaths = np.sum((c == t) & ~cens)
        surv *= 1.0 - deaths / at_risk
        km.append(1.0 - surv)
    assert e["F"] == pytest.approx(km, abs=1e-12)
    with pytest.raises(ValueError, match="single"):
        empirical_cdf([0.1, 0.3, 0.4], [False, True, False])


def test_dkw_band_covers_the_true_cdf() -> None:
    rng = np.random.default_rng(0)
    n, reps, misses = 50, 2000, 0
    for _ in range(reps):
        c = np.exp(rng.normal(math.log(THETA), BETA, n))
        e = empirical_cdf(c, None)
        true = stats.norm.cdf(np.log(np.asarray(e["x"]) / THETA) / BETA)
        lo, hi = np.asarray(e["lower"]), np.asarray(e["upper"])
        # at each step and just before it (the band of the previous step; [0, ε] before the
        # first): the band holds everywhere iff it holds at these points (F is continuous)
        lo_prev = np.r_[0.0, lo[:-1]]
        hi_prev = np.r_[e["epsilon"], hi[:-1]]
        misses += bool(np.any((true < lo) | (true > hi) | (true < lo_prev) | (true > hi_prev)))
    # a miss is exactly a Kolmogorov–Smirnov statistic above ε: P = kstwo.sf(ε, n) <= 5 %
    p_miss = stats.kstwo.sf(math.sqrt(math.log(2 / 0.05) / (2 * n)), n)
    assert p_miss < 0.05
    assert misses / reps == pytest.approx(p_miss, abs=4 * math.sqrt(p_miss / reps))


def test_p_contact_lognormal_and_empirical() -> None:
    assert p_contact(THETA, THETA, BETA) == pytest.approx(0.5, abs=1e-15)
    assert p_contact(THETA * math.exp(BETA), THETA, BETA) == pytest.approx(stats.norm.cdf(1.0))
    s = np.array([0.0, 0.2, 0.4, 0.8])
    p = p_contact(s, THETA, BETA)
    assert p.shape == s.shape and p[0] == 0.0
    assert p[1:] == pytest.approx(stats.norm.cdf(np.log(s[1:] / THETA) / BETA))
    assert list(p_contact(s, THETA, 0.0)) == [0.0, 0.0, 1.0, 1.0]

    caps, cens = [0.1, 0.3, 0.2, U, U], [0, 0, 0, 1, 1]
    assert p_contact_empirical(0.2, caps, cens) == pytest.approx(2 / 5)
    pe = p_contact_empirical([0.05, 0.1, 0.25, 0.3, 0.6], caps, cens)
    assert list(pe) == pytest.approx([0, 1 / 5, 2 / 5, 3 / 5, 3 / 5])


# --------------------------------------------------------------------------------------
# paired comparison
# --------------------------------------------------------------------------------------


def _seeds(n: int, seed: int = 3) -> np.ndarray:
    return np.exp(np.random.default_rng(seed).normal(math.log(THETA), BETA, n))


def test_b_is_a_times_1_2() -> None:
    a = _seeds(20)
    r = compare_paired(a, None, a * 1.2, None)
    assert r["ratio"] == pytest.approx(1 / 1.2, rel=1e-12)
    assert r["lo"] == pytest.approx(1 / 1.2, rel=1e-12)
    assert r["hi"] == pytest.approx(1 / 1.2, rel=1e-12)
    # every d_i < 0: two-sided exact signed-rank p = 2 / 2**20 (normal approx. with ties)
    assert r["p_value"] < 1e-3
    assert r["verdict"] == "B above A" and r["n"] == 20
    json.dumps(r, allow_nan=False)
    assert compare_paired(a * 1.2, None, a, None)["verdict"] == "A above B"


def test_ratio_is_the_geometric_mean_of_per_seed_ratios() -> None:
    a = _seeds(30)
    b = a * np.random.default_rng(1).uniform(0.7, 1.1, 30)
    r = compare_paired(a, None, b, None)
    assert r["ratio"] == pytest.approx(stats.gmean(a / b), rel=1e-12)
    assert r["p_value"] == pytest.approx(stats.wilcoxon(np.log(a / b)).pvalue, rel=1e-9)
    assert r["lo"] < r["ratio"] < r["hi"]


def test_equal_with_tiny_noise_is_equivalent() -> None:
    a = _seeds(20)
    b = a * np.random.default_rng(5).uniform(0.99, 1.01, 20)
    r = compare_paired(a, None, b, None)
    assert r["verdict"] == "equivalent"
    assert 1 / 1.05 <= r["lo"] and r["hi"] <= 1.05


def test_small_noisy_sample_is_undecided() -> None:
    a = _seeds(4)
    b = a * np.array([0.8, 1.25, 0.9, 1.3])
    r = compare_paired(a, None, b, None)
    assert r["verdict"] == "undecided"
    # n = 4: the smallest two-sided exact signed-rank p-value is 2/16
    assert r["p_value"] >= 0.125


def test_paired_argument_validation() -> None:
    a = _seeds(5)
    with pytest.raises(ValueError, match="cap_b"):
        compare_paired(a, None, a[:4], None)
    with pytest.raises(ValueError, match="cap_a"):
        compare_paired(np.r_[a[:4], -1.0], None, a, None)
    with pytest.raises(ValueError, match="cap_b"):
        compare_paired(a, None, np.r_[a[:4], np.inf], None)
    with pytest.raises(ValueError, match="cens_a"):
        compare_paired(a, [False] * 4, a, None)
    with pytest.raises(ValueError, match="cens_b"):
        compare_paired(a, None, a, [0, 1, 2, 0, 0])


def test_both_censored_on_most_seeds_is_undecided() -> None:
    a = _seeds(10)
    a_c, b_c = a.copy(), a * 1.2
    both = np.arange(10) < 6
    a_c[both] = b_c[both] = U
    r = compare_paired(a_c, both, b_c, both)
    assert r["n_both_censored"] == 6 and r["n_used"] == 4
    assert r["verdict"] == "undecided" and "both" in r["reason"]


def test_win_for_the_censored_side_stands() -> None:
    a = _seeds(20)
    b = a / 1.3 * np.random.default_rng(2).uniform(0.97, 1.03, 20)
    u = 0.42
    ca, cb = a > u, b > u  # A flies at u on its strongest seeds; B only on a few of those
    a, b = np.minimum(a, u), np.minimum(b, u)
    assert np.sum(ca & ~cb) >= 3 and not np.any(cb & ~ca)
    r = compare_paired(a, ca, b, cb)
    assert (r["n_censored_a"], r["n_censored_b"]) == (int(ca.sum()), int(cb.sum()))
    assert r["n_both_censored"] == int(np.sum(ca & cb)) and r["n_used"] == 20 - int(cb.sum())
    # the censored seeds' ratios are understated (u / b < a / b): still a clear win for A
    assert r["ratio"] < 1.3
    assert r["verdict"] == "A above B" and r["p_value_worst_case"] is None


def test_win_against_the_censored_side_must_survive_the_worst_case() -> None:
    # B better by ~10 % on 9 seeds; on 3 seeds A flies at u where B touched at 0.95 u
    rng = np.random.default_rng(8)
    b = np.r_[rng.uniform(0.2, 0.4, 9), [0.95 * U] * 3] * np.r_[np.ones(9), [1.0, 0.99, 0.98]]
    a = np.r_[b[:9] / 1.1 * rng.uniform(0.99, 1.01, 9), [U] * 3]
    ca = np.r_[np.zeros(9, bool), np.ones(3, bool)]
    naive = compare_paired(a, None, b, None)  # the flags ignored: a clear win for B
    assert naive["verdict"] == "B above A"
    r = compare_paired(a, ca, b, None)
    assert r["hi"] < 1 and r["p_value"] < 0.05  # would be a win ...
    # ... but with A's three seeds at the top ranks W+ = 10 + 11 + 12 = 33 of 78
    expected = min(
        1.0, 2 * stats.wilcoxon(np.r_[-np.arange(1, 10), [10, 11, 12]], alternative="less").pvalue
    )
    assert r["p_value_worst_case"] == pytest.approx(expected, rel=1e-12)
    assert r["verdict"] == "undecided" and "not robust" in r["reason"]


def test_equivalence_needs_no_one_sided_censoring() -> None:
    a = _seeds(20)
    b = a * np.random.default_rng(5).uniform(0.99, 1.01, 20)
    ca = np.zeros(20, bool)
    ca[int(np.argmax(a))] = True
    a_c = np.where(ca, a.max() * 1.001, a)  # A censored just above where B touched
    b = np.minimum(b, a.max())
    r = compare_paired(a_c, ca, b, None)
    assert 1 / 1.05 <= r["lo"] and r["hi"] <= 1.05
    assert r["verdict"] == "undecided" and "one side" in r["reason"]


def test_verdict_matrix_and_decided_fraction() -> None:
    a = _seeds(20)
    rng = np.random.default_rng(6)
    entrants = {
        "A": (a, None),
        "B": (a * 1.2, None),
        "C": (a * rng.uniform(0.99, 1.01, 20), None),
        "D": (a * rng.uniform(0.6, 1.6, 20), None),
    }
    m = verdict_matrix(entrants, n_boot=500, seed=1)
    pairs = [(r["a"], r["b"]) for r in m]
    assert pairs == [("A", "B"), ("A", "C"), ("A", "D"), ("B", "C"), ("B", "D"), ("C", "D")]
    v = {(r["a"], r["b"]): r for r in m}
    assert v[("A", "B")]["verdict"] == "B above A" and v[("A", "B")]["winner"] == "B"
    assert v[("A", "C")]["verdict"] == "equivalent" and v[("A", "C")]["winner"] is None
    assert v[("B", "C")]["verdict"] == "A above B" and v[("B", "C")]["winner"] == "B"
    direct = compare_paired(a, None, entrants["D"][0], None, n_boot=500, seed=1)
    assert {k: v[("A", "D")][k] for k in direct} == direct
    undecided = sum(r["verdict"] == "undecided" for r in m)
    assert 1 <= undecided <= 3
    assert decided_fraction(m) == pytest.approx((6 - undecided) / 6)
    assert decided_fraction(v) == decided_fraction(m)
    assert decided_fraction([]) is None
    json.dumps(m, allow_nan=False)


# --------------------------------------------------------------------------------------
# binary-outcome cross-check
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("u", [None, U])
def test_binary_outcome_fit_agrees_with_the_capacity_fit(u: float | None) -> None:
    c, cens = _population(400, seed=21, u=u)
    levels = np.geomspace(0.2, 0.8, 13)
    cap = fit_capacity_lognormal(c, cens, n_boot=0)
    bin_ = binary_outcome_fit(c, cens, levels)
    assert bin_["status"] == "fit"
    assert bin_["theta"] == pytest.approx(cap["theta"], rel=0.1)
    assert bin_["theta"] == pytest.approx(THETA, rel=0.1)
    assert bin_["beta"] == pytest.approx(cap["beta"], rel=0.25)
    # the counts: every seed at every kept level, contacts = touched capacities <= level
    for s, n, z in zip(bin_["levels"], bin_["n_runs"], bin_["n_contacts"], strict=True):
        assert n == 400 and z == int(np.sum((c <= s) & ~cens))
    if u is None:
        assert bin_["levels_dropped"] == []
    else:  # above u a censored seed's outcome is unknown: those levels are not used
        assert bin_["levels_dropped"] == [s for s in levels.tolist() if s > u]
    json.dumps(bin_, allow_nan=False)
