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
from hyperloop_env.sts.estimators import _fit, _fit_candidate


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
    including genextreme's c = 0 branch and its neighbours (central differences in c), and
    g against the objective's own terms."""
    y = np.array([-2.5, -0.7, 0.0, 0.4, 1.9])
    h = 1e-5
    for name, s in (
        ("t", 4.0),
        ("t", 30.0),
        ("genextreme", 0.2),
        ("genextreme", -0.3),
        ("genextreme", 0.0),
        ("genextreme", 1e-9),
        ("skewnorm", -3.0),
    ):
        d = newton.per_sample(name, y, (s, 0.0, 1.0))
        up = newton.per_sample(name, y + h, (s, 0.0, 1.0))
        down = newton.per_sample(name, y - h, (s, 0.0, 1.0))
        assert np.isfinite(d).all()
        np.testing.assert_allclose(d[:, 1], (up[:, 0] - down[:, 0]) / (2 * h), rtol=1e-6, atol=1e-8)
        np.testing.assert_allclose(d[:, 2], (up[:, 1] - down[:, 1]) / (2 * h), rtol=1e-6, atol=1e-8)
        terms = np.empty_like(y)
        assert compiled.law_terms(name, y, (s, 0.0, 1.0), compiled.scratch(y.size), terms) == 0
        np.testing.assert_array_equal(d[:, 0], terms)
    outside = newton.per_sample("genextreme", np.array([6.0]), (0.2, 0.0, 1.0))
    assert not np.isfinite(outside).all()  # outside 1 − c y > 0


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


def reference_fit(name: str, x: np.ndarray, x0: np.ndarray) -> np.ndarray | None:
    """:func:`newton.newton_fit` as first written: ``penalised_nll`` at every trial of the line
    search and a fresh pass (gradient, Hessian) at the top of every iteration."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    nll = newton.penalised_nll(name, x)
    theta = newton._feasible(name, x, np.asarray(x0, dtype=np.float64).copy())
    f = nll(theta)
    for _ in range(newton._MAX_ITER):
        if not (math.isfinite(f) and theta[2] > 0.0):
            return None
        if name == "t" and not 0.0 < theta[0] < newton._T_DF_MAX:
            return None
        h = newton._H * (1.0 + abs(theta[0]))
        if name == "t" and not theta[0] - h > 0.0:
            return None
        consts = newton._step_consts(name, theta[0], h)
        parts = compiled.scratch(x.size, newton._ROWS)
        prep = newton._prepare(name, x, theta, h, parts, np.empty_like(x))
        if prep is None:
            return None
        _, grad, hess, ok = newton._sums(
            prep[0], parts, theta[0], theta[2], h, consts[1], consts[3], consts[4]
        )
        if not ok:
            return None
        step = newton._direction(grad, hess)
        if step is None:
            return None
        d, definite = step
        decrement = -float(grad @ d)
        if definite and decrement < 2.0 * newton._DECREMENT_TOL:
            return theta
        t = 1.0
        for _ in range(newton._MAX_BACKTRACK):
            trial = theta + t * d
            f_trial = nll(trial)
            if f_trial <= f - 1e-4 * t * decrement:
                break
            t *= 0.5
        else:
            return theta if definite and decrement < 2.0 * newton._STALL_TOL else None
        theta, f = trial, f_trial
    return None


def starts(name: str, params: tuple[float, ...], z: np.ndarray) -> list[np.ndarray]:
    """scipy's start, the law's parameters, and perturbed starts near and far (some
    backtrack, some do not converge)."""
    rng = np.random.default_rng(5)
    out = [scipy_start(name, z), np.array(params, dtype=float)]
    for spread in (0.2, 0.2, 1.0, 1.0, 2.0):
        th = np.array(params) * (1 + spread * rng.standard_normal(3))
        th += 0.5 * spread * rng.standard_normal(3)
        th[2] = abs(th[2])
        out.append(th)
    return out


@pytest.mark.parametrize(
    ("name", "params"), FIXTURES + [("genextreme", (0.004, 0.1, 1.0))]
)  # the last: genextreme's central differences near c = 0
def test_newton_fit_is_the_plain_loop_bit_for_bit(name, params) -> None:
    """Reusing the full step's pass for the next iteration changes no decision and no
    parameter: the same result as ``penalised_nll`` at every trial, bit for bit (None where
    that gives None), from starts that converge, backtrack or fail."""
    for n in (300, 20_000):
        z = sample(name, params, n=n)
        for start in starts(name, params, z):
            got = newton.newton_fit(name, z, start)
            ref = reference_fit(name, z, start)
            assert (got is None) == (ref is None), (n, start)
            if ref is not None:
                assert got.tobytes() == ref.tobytes(), (n, start, got, ref)


def test_the_pass_value_is_penalised_nlls_bit_for_bit() -> None:
    """The objective the line search reads from Newton's pass is ``penalised_nll``'s, bit for
    bit, where the pass stands for it (and it defers to ``penalised_nll`` elsewhere)."""
    rng = np.random.default_rng(9)
    for name, params in FIXTURES:
        z = np.ascontiguousarray(sample(name, params, n=5_000))
        nll = compiled.penalised_nll(name, z)
        terms, parts = np.empty_like(z), compiled.scratch(z.size, newton._ROWS)
        exact = 0
        for _ in range(40):
            theta = np.array(params) * (1 + 0.3 * rng.standard_normal(3))
            theta[2] = abs(theta[2])
            at = newton._at(name, z, theta, terms, parts)
            if at is not None and at[0] is not None:
                exact += 1
                assert at[0] == nll(theta)
        assert exact >= 20


def test_an_accepted_full_step_costs_one_pass(monkeypatch) -> None:
    """Passes over the sample (Newton's and ``penalised_nll``'s) per fit from scipy's start:
    ``penalised_nll``'s only for backtracked trials; Newton's one per iteration as before
    (the fixtures: 3–13 iterations, 3–29 ``penalised_nll`` passes before, 0–23 now)."""
    counts = {"sums": 0, "nll": 0}
    sums, penalised = newton._sums, newton.penalised_nll

    def counted_sums(*args):
        counts["sums"] += 1
        return sums(*args)

    def counted_penalised(name, x):
        inner = penalised(name, x)

        def nll(theta, *rest):
            counts["nll"] += 1
            return inner(theta, *rest)

        return nll

    monkeypatch.setattr(newton, "_sums", counted_sums)
    monkeypatch.setattr(newton, "penalised_nll", counted_penalised)
    for name, params in FIXTURES:
        z = sample(name, params)
        start = scipy_start(name, z)
        if name == "genextreme" and params[0] < 0:
            start = np.array([0.0, *stats.gumbel_r.fit(z)])
        counts.update(sums=0, nll=0)
        ref = reference_fit(name, z, start)
        plain = dict(counts)
        counts.update(sums=0, nll=0)
        got = newton.newton_fit(name, z, start)
        assert ref is not None and got is not None and got.tobytes() == ref.tobytes()
        iterations = plain["sums"]
        assert plain["nll"] >= iterations  # the start, and a trial per step at least
        assert counts["sums"] == iterations  # one pass per iteration, the start's included
        assert counts["sums"] == plain["sums"]  # these fits: no full step outside the guard
        # the start's nll and each full step's are gone (genextreme's first steps, to a
        # negative scale, backtrack: penalised_nll's, as before)
        assert plain["nll"] - counts["nll"] >= iterations - 2 >= 1, (name, plain, counts)


@pytest.mark.parametrize(("name", "params"), FIXTURES)
def test_the_fit_is_scipys_fit_with_newton_as_its_optimizer(name, params) -> None:
    """The estimator takes scipy's start from the optimizer hook and runs Newton itself: the
    parameters of ``scipy.stats.<name>.fit`` with Newton as its optimizer, bit for bit."""
    z = sample(name, params)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        ref = getattr(stats, name).fit(z, optimizer=newton.fit_optimizer(name, z))
    got = _fit(name, z)
    assert got is not None
    assert np.array(got).tobytes() == np.array(ref, dtype=float).tobytes()
