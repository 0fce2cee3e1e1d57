"""Binomial and Poisson intervals, the lognormal fragility MLE and its degenerate cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, stats

from agents.evaluation.fragility_fit import (
    clopper_pearson,
    fit_fragility,
    fit_lognormal,
    log_likelihood,
    poisson_rate_interval,
    wilson,
)


@pytest.mark.parametrize(("k", "n"), [(0, 1), (0, 20), (1, 20), (7, 20), (20, 20), (13, 137)])
def test_binomial_intervals_match_scipy_binomtest(k: int, n: int) -> None:
    res = stats.binomtest(k, n)
    ref = res.proportion_ci(0.95, method="exact")
    assert clopper_pearson(k, n) == pytest.approx((ref.low, ref.high), abs=1e-12)
    ref_w = res.proportion_ci(0.95, method="wilson")
    assert wilson(k, n) == pytest.approx((ref_w.low, ref_w.high), abs=1e-12)


@pytest.mark.parametrize("k", [0, 1, 4, 30])
def test_poisson_interval_is_garwood(k: int) -> None:
    exposure = 3.7  # e.g. 370 km in units of 100 km
    rate, lo, hi = poisson_rate_interval(k, exposure)
    assert rate == k / exposure
    # the upper bound is the mean whose P(X <= k) is 2.5 %, the lower the one whose P(X >= k) is
    assert stats.poisson.cdf(k, hi * exposure) == pytest.approx(0.025, abs=1e-9)
    if k == 0:
        assert lo == 0.0
    else:
        assert stats.poisson.sf(k - 1, lo * exposure) == pytest.approx(0.025, abs=1e-9)


def _simulate(theta: float, beta: float, seed: int, n_per: int = 60):
    s = np.geomspace(0.08, 1.2, 8)
    n = np.full(s.size, n_per)
    z = np.random.default_rng(seed).binomial(n, stats.norm.cdf(np.log(s / theta) / beta))
    return s, n, z


def test_mle_is_the_maximum_of_the_likelihood() -> None:
    s, n, z = _simulate(0.3, 0.45, seed=3)
    fit = fit_lognormal(s, n, z)
    assert fit["status"] == "fit"
    # independent: Nelder–Mead on the negative log-likelihood in (ln θ, ln β)
    res = optimize.minimize(
        lambda v: -log_likelihood(math.exp(v[0]), math.exp(v[1]), s, n, z),
        x0=[math.log(0.5), math.log(1.0)],
        method="Nelder-Mead",
        options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 4000},
    )
    assert fit["theta"] == pytest.approx(math.exp(res.x[0]), rel=1e-5)
    assert fit["beta"] == pytest.approx(math.exp(res.x[1]), rel=1e-5)
    assert fit["log_likelihood"] >= -res.fun - 1e-9


@pytest.mark.parametrize(("theta", "beta", "seed"), [(0.3, 0.4, 0), (0.5, 0.25, 1), (0.2, 0.6, 2)])
def test_mle_recovers_known_parameters_within_bootstrap_error(theta, beta, seed) -> None:  # type: ignore[no-untyped-def]
    s, n, z = _simulate(theta, beta, seed)
    f = fit_fragility(s, n, z, n_boot=200, rng=seed)
    assert f.status == "fit" and f.n_boot == 200
    # within 4 bootstrap standard errors (se from the 95 % percentile interval's width;
    # over 300 simulated data sets the MLE of ln θ was unbiased to 1e-3 with sd 0.038)
    se_t = (math.log(f.theta_ci[1]) - math.log(f.theta_ci[0])) / (2 * 1.96)
    se_b = (f.beta_ci[1] - f.beta_ci[0]) / (2 * 1.96)
    assert abs(math.log(f.theta / theta)) < 4 * se_t, f.summary()
    assert abs(f.beta - beta) < 4 * se_b, f.summary()
    assert 0.01 < se_t < 0.1 and 0.01 < se_b < 0.2  # the bootstrap is not degenerate
    np.testing.assert_allclose(f.probability([f.theta]), [0.5])


def test_degenerate_data_give_bounds_not_fits() -> None:
    s = np.array([0.1, 0.2, 0.4])
    n = np.array([10, 10, 10])
    cases = {
        "no_contact": ([0, 0, 0], {"theta_lower": 0.4}),
        "all_contact": ([10, 10, 10], {"theta_upper": 0.1}),
        "separated": ([0, 10, 10], {"theta_lower": 0.1, "theta_upper": 0.2}),
        "quasi_separated": ([0, 4, 10], {"theta_limit": 0.2}),
        "decreasing": ([8, 5, 1], {}),
    }
    for status, (z, bounds) in cases.items():
        f = fit_fragility(s, n, np.array(z), n_boot=50)
        assert f.status == status, (status, f)
        assert math.isnan(f.theta) and math.isnan(f.beta)
        assert f.bounds == bounds
        assert np.isnan(f.probability([0.3])).all()
        assert "θ =" not in f.summary()
    single = fit_fragility([0.3, 0.3], [10, 10], [3, 5], n_boot=10)
    assert single.status == "single_level"
    zero = fit_fragility([0.0, 0.1, 0.2, 0.4], [5, 10, 10, 10], [0, 1, 4, 9], n_boot=20)
    assert zero.status == "fit" and "left out" in zero.note and zero.levels == [0.1, 0.2, 0.4]
    with pytest.raises(ValueError, match="z <= n"):
        fit_lognormal([0.1], [3], [4])


def test_bootstrap_counts_degenerate_replicates() -> None:
    # barely overlapping data: many replicates are separated; they are counted and enter
    # the β interval at 0
    s, n, z = np.array([0.1, 0.2, 0.3, 0.5]), np.array([5, 5, 5, 5]), np.array([0, 1, 4, 5])
    f = fit_fragility(s, n, z, n_boot=300, rng=0)
    assert f.status == "fit"
    assert f.n_boot == 300 == f.n_boot_fit + f.n_degenerate + f.n_excluded
    assert f.n_degenerate > 0 and f.beta_ci[0] == 0.0
    again = fit_fragility(s, n, z, n_boot=300, rng=0)
    assert again.theta_ci == f.theta_ci  # seeded
