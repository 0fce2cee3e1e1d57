"""The KS statistic and p-value of hyperloop_env/sts/ks.py against the computations they
replace: D bit-identical to the CDF at every sample (every candidate law, fitted and
unfitted, sizes 3 to 100 000, ties, far tails, NaN), the p-value equal to
``scipy.stats.kstwo.sf`` (relative 1e-12 on the compiled Smirnov branch, identical off it)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy import stats

from hyperloop_env.sts import ks
from hyperloop_env.sts.common import DEFAULT_CANDIDATES
from hyperloop_env.sts.estimators import _fit_candidate, _ks_pvalue, _ks_statistic
from hyperloop_env.sts.tails import law_cdf

# ---------------------------------------------------------------------------- p-value

GRID_N = (141, 1000, 20_000, 86_000, 200_000)
GRID_NX2 = (2.2, 2.5, 3.0, 5.0, 10.0, 30.0, 100.0, 250.0, 350.0)


def _scipy_p(d: float, n: int) -> float:
    return float(np.clip(stats.kstwo.sf(d, n), 0.0, 1.0))


def _branch_points(n: int) -> list[float]:
    ds = [math.sqrt(v / n) for v in GRID_NX2]
    lo = math.sqrt(2.2 / n)
    ds += [lo, np.nextafter(lo, 1.0), 0.4999]
    return [d for d in ds if ks._on_smirnov_branch(d, n)]


@pytest.mark.parametrize("n", GRID_N)
def test_pvalue_on_the_smirnov_branch_is_scipys(n: int) -> None:
    points = _branch_points(n)
    assert len(points) >= 6
    for d in points:
        want = _scipy_p(d, n)
        got = _ks_pvalue(d, n)
        assert want > 0.0
        assert abs(got - want) <= 1e-12 * want, (n, d, got, want)
        half = want / 2.0  # scipy's 2 * smirnov(n, d) on this branch
        assert abs(ks.smirnov_sf(n, d) - half) <= 1e-12 * half
        assert got < 0.05  # the branch never decides a 0.05 acceptance


def test_pvalue_off_the_branch_is_scipys_exactly() -> None:
    cases = [
        (50, 0.3),  # n <= 140
        (140, 0.2),
        (1000, math.sqrt(2.19 / 1000)),  # n d^2 < 2.2: 1 - CDF
        (86_000, 0.001),
        (86_000, 1.5 / 86_000),  # n d <= 1
        (1000, 0.6),  # d >= 0.5
        (1000, 0.9995),  # n d >= n - 1
        (20_000, math.sqrt(360.0 / 20_000)),  # smirnov underflows: scipy's 0
        (200_000, math.sqrt(371.0 / 200_000)),  # n d^2 >= 370
        (1000, 1e-5),
        (1000, 0.0),
        (1000, 1.0),
        (1000, 2.0),
        (1000, -0.1),
        (2_000_000, 0.002),  # n > 1e6: xsf approximates
    ]
    for n, d in cases:
        assert not ks._on_smirnov_branch(d, n)
        assert _ks_pvalue(d, n) == _scipy_p(d, n), (n, d)


def test_pvalue_edges() -> None:
    for d in (math.nan, math.inf, -math.inf):
        assert math.isnan(_ks_pvalue(d, 1000))
    assert _ks_pvalue(0.0, 1000) == 1.0
    assert _ks_pvalue(1e-9, 86_000) == 1.0
    assert _ks_pvalue(1.0, 1000) == 0.0
    assert _ks_pvalue(0.9, 86_000) == 0.0
    for n in GRID_N:
        for d in _branch_points(n):
            assert 0.0 <= _ks_pvalue(d, n) <= 1.0
    # a result in the subnormal range is scipy's own rounding
    n = 5000
    d = math.sqrt(352.6 / n)
    assert ks._on_smirnov_branch(d, n)
    assert _ks_pvalue(d, n) == _scipy_p(d, n)


# ---------------------------------------------------------------------------- statistic

UNFITTED = {
    "norm": (0.3, 1.4),
    "t": (3.5, -0.2, 0.9),
    "logistic": (0.1, 0.7),
    "laplace": (-0.2, 1.1),
    "genextreme": (-0.15, 0.2, 1.3),
    "skewnorm": (4.0, -0.8, 1.5),
}


def _old_statistic(z_sorted: np.ndarray, name: str, params: tuple[float, ...]) -> float:
    """The computation ``_ks_statistic`` replaced: the law's CDF at every sample."""
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        cdf = law_cdf(name, z_sorted, *params)
    n = z_sorted.size
    d_plus = (np.arange(1.0, n + 1) / n - cdf).max()
    d_minus = (cdf - np.arange(0.0, n) / n).max()
    return float(d_plus if d_plus > d_minus else d_minus)


def _blocked(z_sorted: np.ndarray, name: str, params: tuple[float, ...], **kw) -> float:
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        return ks.ks_statistic(z_sorted, lambda z: law_cdf(name, z, *params), **kw)


def _samples(n: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    heavy = rng.standard_t(4.0, n)
    skewed = rng.gumbel(0.0, 1.0, n)
    ties = np.round(rng.normal(0.0, 1.0, n), 1)  # many ties
    tails = rng.normal(0.0, 1.0, n)
    tails[: max(1, n // 50)] *= 12.0  # samples far in both tails
    tails[0] = -40.0
    return [np.sort((s - s.mean()) / (s.std() or 1.0)) for s in (heavy, skewed, ties, tails)]


@pytest.fixture(scope="module")
def fitted() -> dict[str, tuple[float, ...]]:
    z = _samples(3000, 11)[0]
    out = {}
    for name in DEFAULT_CANDIDATES:
        params = _fit_candidate(name, z)
        assert params is not None
        out[name] = params
    return out


@pytest.mark.parametrize("name", DEFAULT_CANDIDATES)
def test_law_cdf_is_elementwise(name: str, fitted) -> None:
    z = _samples(5000, 3)[3]
    for params in (fitted[name], UNFITTED[name]):
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            full = law_cdf(name, z, *params)
            for idx in (np.arange(0, z.size, 7), np.arange(3, z.size, 256), np.array([17])):
                np.testing.assert_array_equal(law_cdf(name, z[idx], *params), full[idx])
            np.testing.assert_array_equal(law_cdf(name, z[101:1234], *params), full[101:1234])


def test_skewnorm_tail_branch_is_met() -> None:
    # Boost's CDF below 1e-6 with a > 0: the integrated tail, also for the blocked statistic
    z = _samples(5000, 3)[3]
    a, loc, scale = UNFITTED["skewnorm"]
    assert (stats.skewnorm.cdf(z, a, loc, scale) < 1e-6).sum() > 20


@pytest.mark.parametrize("name", DEFAULT_CANDIDATES)
@pytest.mark.parametrize("n", [3, 4, 17, 300, 2047, 2048, 5000, 30_000, 100_000])
def test_statistic_is_bit_identical(name: str, n: int, fitted) -> None:
    for k, z in enumerate(_samples(n, 1000 + n)):
        for params in (fitted[name], UNFITTED[name]):
            want = _old_statistic(z, name, params)
            assert math.isfinite(want)
            assert _ks_statistic(z, name, params) == want, (k, params)
            if n <= 5000:  # the block path at sizes the default sends to the full one
                got = _blocked(z, name, params, min_blocked=0)
                assert got == want, (k, params)
                got = _blocked(z, name, params, min_blocked=0, strides=(4, 1))
                assert got == want, (k, params)


def test_statistic_evaluates_a_small_part_of_the_cdf(fitted) -> None:
    z = _samples(100_000, 9)[0]
    for name in DEFAULT_CANDIDATES:
        seen: list[int] = []

        def cdf(x: np.ndarray, name: str = name, seen: list[int] = seen) -> np.ndarray:
            seen.append(x.size)
            return law_cdf(name, x, *fitted[name])

        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            assert ks.ks_statistic(z, cdf) == _old_statistic(z, name, fitted[name])
        assert sum(seen) < z.size // 5, (name, seen)


def test_statistic_at_the_maximum_of_a_misfit_law() -> None:
    # a law far from the sample: D near 1, the maximum at the first or last samples
    z = _samples(10_000, 5)[0]
    for params in ((8.0, 0.5), (-8.0, 0.5), (0.0, 1e-3), (0.0, 50.0)):
        assert _ks_statistic(z, "norm", params) == _old_statistic(z, "norm", params)


def test_statistic_nan() -> None:
    z = _samples(10_000, 7)[0]
    assert math.isnan(_ks_statistic(z, "norm", (0.0, -1.0)))  # invalid scale: NaN everywhere
    assert math.isnan(_ks_statistic(z, "t", (-2.0, 0.0, 1.0)))
    z_nan = np.sort(np.append(z, math.nan))  # NaN sorts last
    assert math.isnan(_ks_statistic(z_nan, "norm", (0.0, 1.0)))
    assert math.isnan(_old_statistic(z_nan, "norm", (0.0, 1.0)))
    z_inf = np.sort(np.concatenate([z, [-math.inf, math.inf]]))
    assert _ks_statistic(z_inf, "norm", (0.0, 1.0)) == _old_statistic(z_inf, "norm", (0.0, 1.0))


def test_strides_must_decrease_to_one() -> None:
    z = _samples(5000, 1)[0]
    with pytest.raises(ValueError):
        ks.ks_statistic(z, stats.norm.cdf, strides=(16, 4))
    with pytest.raises(ValueError):
        ks.ks_statistic(z, stats.norm.cdf, strides=(4, 16, 1))
