"""The skew-normal CDF / SF with the compiled left-tail integration against
``scipy.stats.skewnorm`` (hyperloop_env/sts/tails.py: relative 1e-12), including the points
where scipy integrates the density (CDF < 1e-6 with a > 0), the edges (±inf, NaN, invalid
parameters), broadcasting over parameter arrays (the bootstrap's replicates), and the KS
statistic and P(unsteady) of a fitted law that meet the tail."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import stats

from hyperloop_env.sts import tails
from hyperloop_env.sts.estimators import _ks_statistic, _law_p_unsteady

X = np.concatenate([np.linspace(-12.0, 12.0, 97), [-40.0, -7.3, 0.0, 5.1]])


def _scipy(fn: str, *args):
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        return getattr(stats.skewnorm, fn)(*args)


@pytest.mark.parametrize("a", [0.0, 0.4, 3.0, 8.0, -2.5, -9.0])
def test_cdf_and_sf_are_scipys(a: float) -> None:
    for fn, ours in (("cdf", tails.skewnorm_cdf), ("sf", tails.skewnorm_sf)):
        want = _scipy(fn, X, a, 0.3, 1.7)
        got = ours(X, a, 0.3, 1.7)
        # atol: below the smallest normal double (2.2e-308) a subnormal is rounding
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-300, err_msg=fn)


def test_the_tail_branch_is_taken_and_integrated() -> None:
    # Boost's value at y = -6, a = 2 is below 1e-6: scipy (and we) integrate the density;
    # an independent value: 2·∫φ(t)Φ(2t)dt over (-inf, -6] by the trapezoid rule
    t = np.linspace(-14.0, -6.0, 200_001)
    f = 2.0 * stats.norm.pdf(t) * stats.norm.cdf(2.0 * t)
    trapezoid = float(np.sum((f[1:] + f[:-1]) / 2.0 * np.diff(t)))
    got = float(tails.skewnorm_cdf(-6.0, 2.0))
    assert got < tails._TAIL
    assert got == pytest.approx(trapezoid, rel=1e-8)
    assert got == pytest.approx(float(_scipy("cdf", -6.0, 2.0)), rel=1e-12)


def test_edges_and_shapes() -> None:
    assert np.isnan(tails.skewnorm_cdf(np.nan, 2.0)) and np.isnan(tails.skewnorm_sf(np.nan, 2.0))
    assert np.isnan(tails.skewnorm_cdf(1.0, np.inf)) and np.isnan(
        tails.skewnorm_cdf(1.0, 2.0, 0, -1)
    )
    assert tails.skewnorm_cdf(np.inf, 2.0) == 1.0 and tails.skewnorm_cdf(-np.inf, 2.0) == 0.0
    assert isinstance(tails.skewnorm_cdf(0.5, 1.0), np.float64)
    a, scale = np.array([1.0, 3.0, 5.0, 0.0]), np.array([1.0, 1.2, 0.9, 1.1])
    for z in (3.0, -4.5):  # scalar x against replicate arrays of parameters
        np.testing.assert_allclose(
            tails.skewnorm_sf(z, a, 0.1, scale), _scipy("sf", z, a, 0.1, scale), rtol=1e-12
        )
        np.testing.assert_allclose(
            tails.skewnorm_cdf(z, a, 0.1, scale), _scipy("cdf", z, a, 0.1, scale), rtol=1e-12
        )
    assert tails.law_cdf("norm", 0.0, 0.0, 1.0) == 0.5


def test_ks_statistic_and_p_unsteady_meet_the_tail_as_scipy() -> None:
    params = (4.0, -1.2, 1.5)  # a > 0: the left tail integrated
    z = np.sort(stats.skewnorm.rvs(*params, size=4000, random_state=np.random.default_rng(3)))
    z = np.concatenate([[-4.5, -3.9], z])  # two samples deep in the integrated tail
    assert (_scipy("cdf", z[:2], *params) < tails._TAIL).all()
    want = stats.ks_1samp(z, stats.skewnorm(*params).cdf, method="asymp").statistic
    assert _ks_statistic(z, "skewnorm", params) == pytest.approx(want, rel=1e-12)
    want_p = _scipy("sf", 3.0, *params) + _scipy("cdf", -5.0, *params)
    assert _law_p_unsteady("skewnorm", params, 3.0, -5.0) == pytest.approx(want_p, rel=1e-12)
