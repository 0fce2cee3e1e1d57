"""Newton's maximum-likelihood fits (``hyperloop_env/sts/newton.py``) against independent
references: the per-sample derivatives against central differences of scipy's ``logpdf``,
the maximum against a tightly converged Nelder–Mead polish, and the fallback to scipy."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy import optimize, stats
from sts_samples import FIXTURES, sample  # tests/env/sts_samples.py, beside this file

from hyperloop_env.sts import compiled, newton
from hyperloop_env.sts.estimators import _fit_candidate


def fd_scores(name: str, x: np.ndarray, theta: np.ndarray, h: float = 1e-6) -> np.ndarray:
    dist = getattr(stats, name)
    out = np.empty((x.size, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = h * (1.0 + abs(theta[j]))
        out[:, j] = (dist.logpdf(x, *(theta + e)) - dist.logpdf(x, *(theta - e))) / (2 * e[j])
    return out


@pytest.mark.parametrize(
    ("name", "params"), FIXTURES + [("genextreme", (0.004, 0.1, 1.0))]
)  # the last: genextreme's central differences near c = 0
def test_scores_and_hessian_are_scipys_logpdf_derivatives(name, params) -> None:
    x = sample(name, params, n=3_000)
    theta = np.array(params) * np.array([1.1, 1.0, 0.95]) + np.array([0.0, 0.02, 0.0])
    got = newton.scores_and_hessian(name, x, tuple(theta))
    assert got is not None
    s0, hess = got
    ref = fd_scores(name, x, theta)
    np.testing.assert_allclose(s0, ref, rtol=1e-5, atol=1e-6 * np.abs(ref).max())
    ref_h = np.empty((3, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = 1e-4 * (1.0 + abs(theta[j]))
        up = fd_scores(name, x, theta + e).mean(0)
        down = fd_scores(name, x, theta - e).mean(0)
        ref_h[:, j] = (up - down) / (2 * e[j])
    np.testing.assert_allclose(hess, ref_h, rtol=1e-3, atol=1e-4 * np.abs(ref_h).max())


def scipy_start(name: str, z: np.ndarray) -> np.ndarray:
    """The start scipy's ``fit`` hands its optimizer."""
    seen = []

    def capture(func, x0, args=(), disp=0):
        seen.append(np.array(x0, dtype=float))
        return x0

    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        getattr(stats, name).fit(z, optimizer=capture)
    return seen[0]


def test_a_saddle_is_not_a_maximum() -> None:
    """skewnorm's likelihood is stationary at a = 0 (a saddle for skewed data): Newton does
    not stop there."""
    z = sample("skewnorm", (-4.0, 0.9, 1.4))
    theta = newton.newton_fit("skewnorm", z, np.array([0.0, 0.0, 1.0]))
    assert theta is None or theta[0] < -1.0


@pytest.mark.parametrize(("name", "params"), FIXTURES)
def test_newton_reaches_the_maximum_from_scipys_start(name, params) -> None:
    """Converged (not the fallback) and as likely as Nelder–Mead polished from it to 1e-10."""
    z = sample(name, params)
    start = scipy_start(name, z)
    if name == "genextreme" and params[0] < 0:  # scipy's start stalls here: the Gumbel start
        start = np.array([0.0, *stats.gumbel_r.fit(z)])
    theta = newton.newton_fit(name, z, start)
    assert theta is not None
    nll = compiled.penalised_nll(name, z)
    polish = optimize.minimize(
        nll,
        theta,
        method="Nelder-Mead",
        options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 4000, "initial_simplex": None},
    )
    assert nll(theta) <= polish.fun + 1e-7
    assert np.allclose(theta, polish.x, rtol=1e-4, atol=1e-5)


def test_law_derivatives_in_y_are_those_of_g() -> None:
    """g_y and g_yy of each law's closed form against central differences of g itself,
    including genextreme's c = 0 branch and its neighbours."""
    for law, s in ((0, 4.0), (0, 30.0), (1, 0.2), (1, -0.3), (1, 0.0), (1, 1e-9), (2, -3.0)):
        c0 = newton._t_const(s) if law == 0 else 0.0
        for y in (-2.5, -0.7, 0.0, 0.4, 1.9):
            g, gy, gyy = newton._g(law, y, s, c0)
            h = 1e-5
            gp, gyp, _ = newton._g(law, y + h, s, c0)
            gm, gym, _ = newton._g(law, y - h, s, c0)
            assert math.isfinite(g)
            assert gy == pytest.approx((gp - gm) / (2 * h), rel=1e-6, abs=1e-8)
            assert gyy == pytest.approx((gyp - gym) / (2 * h), rel=1e-6, abs=1e-8)
    assert newton._g(1, 6.0, 0.2, 0.0)[0] == -math.inf  # outside 1 − c y > 0


def test_a_start_newton_cannot_use_falls_back_to_scipys_nelder_mead() -> None:
    z = sample("t", (4.0, 0.1, 0.8), n=2_000)
    assert newton.newton_fit("t", z, np.array([-1.0, 0.0, 1.0])) is None
    run = newton.fit_optimizer("t", z)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        theta = run(None, np.array([-1.0, 0.0, 1.0]))
    ref = optimize.fmin(compiled.penalised_nll("t", z), np.array([-1.0, 0.0, 1.0]), disp=0)
    np.testing.assert_array_equal(theta, ref)


def test_t_on_light_tails_is_the_normal_limit() -> None:
    """Samples without excess kurtosis: scipy's own t fit runs ν off to the normal limit, and
    the estimator drops the candidate; heavy tails keep it."""
    rng = np.random.default_rng(11)
    light = rng.uniform(size=20_000) + rng.uniform(size=20_000)  # triangular: kurtosis 2.4
    light = (light - light.mean()) / light.std()
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        assert stats.t.fit(light)[0] > 1e4
    assert _fit_candidate("t", light) is None
    heavy = sample("t", (6.0, 0.0, 1.0))
    fitted = _fit_candidate("t", heavy)
    assert fitted is not None and 4.0 < fitted[0] < 9.0
