"""Newton's method for the maximum-likelihood fits of the heavy candidate laws (``t``,
``genextreme``, ``skewnorm``), from scipy's own start.

scipy's ``rv_continuous.fit`` minimises the negative log-likelihood with Nelder–Mead and
stops where its simplex is 1e-4 wide (``xtol = ftol = 1e-4``): a few hundred passes over
the samples per fit, and parameters within about 1e-4 of the maximum. :func:`newton_fit`
runs Newton's method on the same objective instead, each iteration one compiled pass that
sums the log-likelihood, its gradient and its Hessian, with a Levenberg–Marquardt shift
where the Hessian is not positive definite and a backtracking (Armijo) line search on
scipy's penalised objective (:func:`hyperloop_env.sts.compiled.penalised_nll`). It stops
when the Hessian is positive definite (a maximum, not a saddle) and the Newton decrement
``g·H⁻¹·g / 2`` (the predicted remaining gain of log-likelihood, in nats) is below 1e-8:
typically 5–10 iterations. A full step's trial point is evaluated by the pass the next
iteration needs there, which also yields the penalised objective bit for bit (the same
per-sample expressions and sum as ``penalised_nll``): an iteration whose full step is accepted costs
one pass; only backtracked trials pass over the sample again. The result is the
likelihood's maximum, so it agrees with scipy's Nelder–Mead result to scipy's tolerance (not
to rounding), with a log-likelihood at least as large; the tolerance stated and tested in
``tests/env/test_sts_compiled.py``. Where Newton does not converge (a maximum on the
support's boundary, a start too far away) it returns None and the caller keeps scipy's
Nelder–Mead.

Per sample, with y = (x − loc)/scale, shape s and log f = g(y; s) − log(scale):

* ∂/∂loc = −g_y / scale, ∂/∂scale = −(y g_y + 1) / scale, ∂/∂s = g_s;
* ∂²/∂loc² = g_yy / scale², ∂²/∂loc∂scale = (g_y + y g_yy) / scale²,
  ∂²/∂scale² = (2 y g_y + y² g_yy + 1) / scale², ∂²/∂s∂loc = −g_sy / scale,
  ∂²/∂s∂scale = −y g_sy / scale, ∂²/∂s² = g_ss;

g_y and g_yy in closed form per law (below); the shape derivatives g_s, g_ss, g_sy in closed
form, except ``genextreme``'s for |c| < 0.01, where its closed forms cancel (terms in
log(u)/c³): there central differences in c with step h = 1e-5 (1 + |c|) (truncation error
~h², far inside scipy's 1e-4).

* ``t`` (ν), q = ν + y²: g = c(ν) − (ν+1)/2 · log1p(y²/ν), g_y = −(ν+1) y/q,
  g_yy = −(ν+1)(ν−y²)/q², c(ν) = log Γ((ν+1)/2) − log Γ(ν/2) − ½ log(νπ);
  g_ν = c′ − ½ log1p(y²/ν) + (ν+1) y²/(2νq),
  g_νν = c″ + y²/(2νq) + ½ y² (νq − (ν+1)(q+ν))/(νq)², g_νy = −y (y² − 1)/q²;
* ``genextreme`` (c, scipy's sign), u = 1 − c y > 0, w = u^(1/c):
  g = −w + log(u)/c − log u, g_y = (w − 1 + c)/u, g_yy = (c (w − 1 + c) − w)/u²
  (c = 0: g = −e^(−y) − y, g_y = e^(−y) − 1, g_yy = −e^(−y)); with L = log u, t = L/c,
  L_c = −y/u, L_cc = −y²/u², t_c = L_c/c − L/c², t_cc = L_cc/c − 2L_c/c² + 2L/c³:
  g_c = (1 − w) t_c − L_c, g_cc = (1 − w) t_cc − w t_c² − L_cc,
  g_cy = ((w t_c + 1) u + y (w − 1 + c))/u²;
* ``skewnorm`` (a), r(v) = φ(v)/Φ(v): g = log 2 − y²/2 − log √(2π) + log Φ(a y),
  g_y = −y + a r(a y), g_yy = −1 − a² r(a y) (a y + r(a y)), with v = a y:
  g_a = y r(v), g_aa = −y² r(v)(v + r(v)), g_ay = r(v) − v r(v)(v + r(v)).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numba as nb
import numpy as np
from scipy import optimize, special

from hyperloop_env.sts.common import FloatArray
from hyperloop_env.sts.compiled import (
    _LOG_SQRT_2PI,
    _XMIN,
    _log_ndtr,
    penalised_nll,
    penalised_value,
    t_const,
)

_LOG2 = math.log(2.0)
_DECREMENT_TOL = 1e-8  # nats of log-likelihood still to gain: converged below this
_STALL_TOL = 1e-5  # a failed line search this close to the maximum: converged
_MAX_ITER = 60
_GEV_CLOSED_FORM = 1e-2  # |c| from which genextreme's shape derivatives are closed forms
_EDGE_U = 0.05  # 1 − c y of the outermost sample in a widened genextreme start
_T_DF_MAX = 1e3  # t's ν beyond this: the normal limit, left to Nelder–Mead
_CONDITION = 1e-6  # smallest/largest eigenvalue of a Hessian taken as positive definite
_H = 1e-5  # relative step of the central differences in the shape
_MAX_BACKTRACK = 40


@nb.njit(cache=True)
def _g(law: int, y: float, s: float, c0: float) -> tuple[float, float, float]:
    """(g, g_y, g_yy) of law ``law`` (0 t, 1 genextreme, 2 skewnorm) at y, shape s; g = −inf
    outside the support."""
    if law == 0:
        q = s + y * y
        return (
            c0 - 0.5 * (s + 1.0) * math.log1p(y * y / s),
            -(s + 1.0) * y / q,
            (-(s + 1.0) * (s - y * y) / (q * q)),
        )
    if law == 1:
        if s == 0.0:
            e = math.exp(-y)
            return -e - y, e - 1.0, -e
        u = 1.0 - s * y
        if not u > 0.0:
            return -np.inf, 0.0, 0.0
        lu = math.log1p(-s * y)
        w = math.exp(lu / s)
        return -w + lu / s - lu, (w - 1.0 + s) / u, (s * (w - 1.0 + s) - w) / (u * u)
    v = s * y
    lphi = _log_ndtr(v)
    r = math.exp(-0.5 * v * v - _LOG_SQRT_2PI - lphi)
    g = _LOG2 - 0.5 * y * y - _LOG_SQRT_2PI + lphi
    return g, -y + s * r, -1.0 - s * s * r * (v + r)


@nb.njit(cache=True)
def _g6(
    law: int, y: float, s: float, h: float, c: FloatArray
) -> tuple[float, float, float, float, float, float]:
    """(g, g_y, g_yy, g_s, g_ss, g_sy): the shape derivatives in closed form for ``t``
    (``c`` = c(ν−h), c(ν), c(ν+h), c′(ν), c″(ν)), ``skewnorm`` and ``genextreme`` with
    |c| ≥ 0.01; by central differences with step ``h`` for ``genextreme`` nearer c = 0, where
    its closed forms (terms in log(u)/c³) cancel."""
    if law == 0:
        g, gy, gyy = _g(law, y, s, c[1])
        y2 = y * y
        q = s + y2
        lq = math.log1p(y2 / s)
        gs = c[3] - 0.5 * lq + (s + 1.0) * y2 / (2.0 * s * q)
        nq = s * q
        gss = c[4] + y2 / (2.0 * nq) + 0.5 * y2 * (nq - (s + 1.0) * (q + s)) / (nq * nq)
        return g, gy, gyy, gs, gss, -y * (y2 - 1.0) / (q * q)
    if law == 2:
        v = s * y
        lphi = _log_ndtr(v)
        r = math.exp(-0.5 * v * v - _LOG_SQRT_2PI - lphi)
        norm = -(y**2) / 2.0 - _LOG_SQRT_2PI  # g as penalised_nll's term computes it
        g = norm if s == 0.0 else _LOG2 + norm + lphi
        rr = r * (v + r)
        return g, -y + s * r, -1.0 - s * s * rr, y * r, -y * y * rr, r - v * rr
    if abs(s) >= _GEV_CLOSED_FORM:
        u = 1.0 - s * y
        if not u > 0.0:
            return -np.inf, 0.0, 0.0, 0.0, 0.0, 0.0
        lu = math.log1p(-s * y)
        w = math.exp(lu / s)
        g = -w + lu / s - lu  # _g's expressions, its log1p and exp computed once
        gy = (w - 1.0 + s) / u
        gyy = (s * (w - 1.0 + s) - w) / (u * u)
        l_c = -y / u
        l_cc = -(y * y) / (u * u)
        t_c = l_c / s - lu / (s * s)
        t_cc = l_cc / s - 2.0 * l_c / (s * s) + 2.0 * lu / (s * s * s)
        g_c = (1.0 - w) * t_c - l_c
        g_cc = (1.0 - w) * t_cc - w * t_c * t_c - l_cc
        g_cy = ((w * t_c + 1.0) * u + y * (w - 1.0 + s)) / (u * u)
        return g, gy, gyy, g_c, g_cc, g_cy
    g, gy, gyy = _g(law, y, s, 0.0)
    gp, gyp, _ = _g(law, y, s + h, 0.0)
    gm, gym, _ = _g(law, y, s - h, 0.0)
    return g, gy, gyy, (gp - gm) / (2.0 * h), (gp - 2.0 * g + gm) / (h * h), (gyp - gym) / (2.0 * h)


@nb.njit(cache=True)
def _sums(
    law: int,
    x: FloatArray,
    shape: float,
    loc: float,
    scale: float,
    h: float,
    c0: FloatArray,
    terms: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, bool, int]:
    """The negative log-likelihood's value, gradient and Hessian over (shape, loc, scale);
    ``ok`` False if a sample is outside the support or a term is not finite. In the same
    pass, :func:`~hyperloop_env.sts.compiled.penalised_nll`'s per-sample terms into
    ``terms`` and the count of those not finite: g itself, whose expressions are that
    objective's operation for operation (``t``: c − ½(ν+1)·log1p(y²/ν), the same constant;
    ``genextreme``: −e^(L/c) + L/c − L with L = log1p(−c y), −e^(−y) − y at c = 0;
    ``skewnorm``: log 2 + (−y²/2 − log √(2π)) + log Φ(a y)), −inf outside its support bounds.
    Where g is −inf inside those bounds (rounding at genextreme's edge) the count is not 0
    and the caller does not use the terms."""
    sg = sgy = sygy = sgyy = sygyy = syygyy = 0.0
    sgs = sgss = sgsy = sygsy = 0.0
    bad = 0
    lo = 1.0 / min(shape, -_XMIN) if shape < 0.0 else -np.inf  # genextreme's support in y,
    hi = 1.0 / max(shape, _XMIN) if shape > 0.0 else np.inf  # as penalised_nll bounds it
    for i in range(x.size):
        y = (x[i] - loc) / scale
        g, gy, gyy, gs, gss, gsy = _g6(law, y, shape, h, c0)
        v = g if law != 1 or lo < y < hi else -np.inf
        terms[i] = v
        if not math.isfinite(v):
            bad += 1
        sg += g
        sgy += gy
        sygy += y * gy
        sgyy += gyy
        sygyy += y * gyy
        syygyy += y * y * gyy
        sgs += gs
        sgss += gss
        sgsy += gsy
        sygsy += y * gsy
    n = x.size
    s2 = scale * scale
    grad = np.array([-sgs, sgy / scale, (sygy + n) / scale])
    hess = np.empty((3, 3))
    hess[0, 0] = -sgss
    hess[0, 1] = hess[1, 0] = sgsy / scale
    hess[0, 2] = hess[2, 0] = sygsy / scale
    hess[1, 1] = -sgyy / s2
    hess[1, 2] = hess[2, 1] = -(sgy + sygyy) / s2
    hess[2, 2] = -(2.0 * sygy + syygyy + n) / s2
    value = np.array([-sg + n * math.log(scale)])
    ok = math.isfinite(value[0]) and np.isfinite(grad).all() and np.isfinite(hess).all()
    return value, grad, hess, ok, bad


@nb.njit(cache=True)
def _scores(
    law: int, x: FloatArray, shape: float, loc: float, scale: float, h: float, c0: FloatArray
) -> FloatArray:
    """Per-sample gradient of log f over (shape, loc, scale): ``(n, 3)``."""
    out = np.empty((x.size, 3))
    for i in range(x.size):
        y = (x[i] - loc) / scale
        _, gy, _, gs, _, _ = _g6(law, y, shape, h, c0)
        out[i, 0] = gs
        out[i, 1] = -gy / scale
        out[i, 2] = -(y * gy + 1.0) / scale
    return out


_LAWS = {"t": 0, "genextreme": 1, "skewnorm": 2}
NEWTON_LAWS = frozenset(_LAWS)


def scores_and_hessian(
    name: str, x: FloatArray, params: tuple[float, ...]
) -> tuple[FloatArray, FloatArray] | None:
    """Per-sample scores ``(n, 3)`` of log f over (shape, loc, scale) and the mean Hessian
    ``(3, 3)`` of log f, at ``params``; None if a sample is outside the support or a term
    is not finite."""
    shape, loc, scale = (float(p) for p in params)
    if not scale > 0.0:
        return None
    h = _H * (1.0 + abs(shape))
    if name == "t" and not shape - h > 0.0:
        return None
    x = np.ascontiguousarray(x, dtype=np.float64)
    consts = _step_consts(name, shape, h)
    _, _, hess, ok, _ = _sums(_LAWS[name], x, shape, loc, scale, h, consts, np.empty_like(x))
    if not ok:
        return None
    s0 = _scores(_LAWS[name], x, shape, loc, scale, h, consts)
    if not np.isfinite(s0).all():
        return None
    return s0, -hess / x.size


def _t_const(nu: float) -> float:
    return t_const(nu)  # the objective's own constant: the same terms as penalised_nll's


def _step_consts(name: str, shape: float, h: float) -> FloatArray:
    """t's constant c(ν) at ν − h, ν, ν + h and its derivatives c′(ν), c″(ν) (digamma ψ and
    trigamma ψ′: c′ = ½ψ((ν+1)/2) − ½ψ(ν/2) − 1/(2ν), c″ = ¼ψ′((ν+1)/2) − ¼ψ′(ν/2) + 1/(2ν²));
    zeros for the other laws."""
    if name != "t":
        return np.zeros(5)
    a, b = 0.5 * (shape + 1.0), 0.5 * shape
    d1 = 0.5 * (special.digamma(a) - special.digamma(b)) - 0.5 / shape
    d2 = 0.25 * (special.polygamma(1, a) - special.polygamma(1, b)) + 0.5 / shape**2
    return np.array(
        [_t_const(shape - h), _t_const(shape), _t_const(shape + h), float(d1), float(d2)]
    )


def _direction(grad: FloatArray, hess: FloatArray) -> tuple[FloatArray, bool] | None:
    """(−H⁻¹ g, whether H is positive definite), with H shifted by λ I (Levenberg–Marquardt)
    until positive definite where its smallest eigenvalue is not above 1e-6 of its largest
    (a saddle, or skewnorm's singular information at a = 0)."""
    eig = np.linalg.eigvalsh(hess)
    if eig[0] > _CONDITION * eig[-1]:
        return -np.linalg.solve(hess, grad), True
    lam = 0.0
    scale = float(np.max(np.abs(np.diag(hess)))) or 1.0
    for _ in range(60):
        try:
            chol = np.linalg.cholesky(hess + lam * np.eye(3))
        except np.linalg.LinAlgError:
            lam = max(2.0 * lam, 1e-8 * scale)
            continue
        return -np.linalg.solve(chol.T, np.linalg.solve(chol, grad)), False
    return None


def _feasible(name: str, x: FloatArray, theta: FloatArray) -> FloatArray:
    """``genextreme``'s start with every sample inside the support (1 − c y > 0): Newton
    needs finite terms to start from. The scale is widened until the outermost sample has
    1 − c y = 0.05 (a bootstrap replicate's start is the full sample's fit, often with a
    sample just beyond its edge: the nearest feasible start)."""
    if name != "genextreme" or theta[0] == 0.0 or not theta[2] > 0.0:
        return theta
    edge = float(x.max() if theta[0] > 0.0 else x.min())
    if 1.0 - theta[0] * (edge - theta[1]) / theta[2] > 0.0:
        return theta
    theta[2] = theta[0] * (edge - theta[1]) / (1.0 - _EDGE_U)
    return theta


def _guard(name: str, theta: FloatArray) -> float | None:
    """The shape's central-difference step h at ``theta``; None where Newton stops (scale not
    positive, ``t``'s ν at or beyond the normal limit or within h of 0)."""
    if not theta[2] > 0.0:
        return None
    if name == "t" and not 0.0 < theta[0] < _T_DF_MAX:
        return None  # ν → ∞ (normal data): the maximum is at the boundary
    h = _H * (1.0 + abs(theta[0]))
    if name == "t" and not theta[0] - h > 0.0:
        return None
    return h


def _at(
    name: str, x: FloatArray, theta: FloatArray, terms: FloatArray
) -> tuple[float | None, FloatArray, FloatArray] | None:
    """One pass at ``theta``: (the penalised objective or None, gradient, Hessian); None
    where Newton stops there (:func:`_guard`, or a term, gradient or Hessian not finite).
    The objective is :func:`~hyperloop_env.sts.compiled.penalised_value` of the pass's terms,
    which are :func:`~hyperloop_env.sts.compiled.penalised_nll`'s (the same expressions,
    :func:`_sums`; the same numpy sum): bit for bit its value. None (the caller then calls
    ``penalised_nll``) where that would take another branch: a shape outside the law's
    domain, or a term not finite (the penalty)."""
    h = _guard(name, theta)
    if h is None:
        return None
    shape = theta[0]
    consts = _step_consts(name, shape, h)
    _, grad, hess, ok, bad = _sums(_LAWS[name], x, shape, theta[1], theta[2], h, consts, terms)
    if not ok:
        return None
    exact = bad == 0 and math.isfinite(shape)
    return (penalised_value(terms, 0, float(theta[2])) if exact else None), grad, hess


def newton_fit(name: str, x: FloatArray, x0: FloatArray) -> FloatArray | None:
    """The maximum-likelihood (shape, loc, scale) of law ``name`` on ``x`` by Newton's method
    from ``x0``; None where it does not converge (the caller keeps Nelder–Mead).

    Passes: a full step's trial point (t = 1) is evaluated by the pass that sums the
    gradient and Hessian there as well (:func:`_at`), so an accepted full step costs one
    pass, not ``penalised_nll``'s and then the next iteration's; backtracked trials
    (t < 1) call ``penalised_nll``, and after one is accepted the next iteration's pass
    follows. The line search compares the same numbers as with ``penalised_nll`` alone:
    the pass's objective is bit for bit ``penalised_nll``'s (the same per-sample
    expressions, operation for operation, :func:`_sums`, and the same numpy sum,
    :func:`~hyperloop_env.sts.compiled.penalised_value`; IEEE arithmetic, compiled without
    fast-math, gives the same bits for the same operations), and ``penalised_nll`` itself is
    called wherever the pass cannot stand for it. So every accept/reject decision, and the
    fitted parameters, are those of evaluating ``penalised_nll`` at every trial
    (``tests/env/test_sts_newton.py`` checks this bit for bit against that loop)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    nll = penalised_nll(name, x)
    terms = np.empty_like(x)
    theta = _feasible(name, x, np.asarray(x0, dtype=np.float64).copy())
    here = _at(name, x, theta, terms)
    if here is None:
        return None
    f = nll(theta) if here[0] is None else here[0]
    _, grad, hess = here
    for _ in range(_MAX_ITER):
        if not math.isfinite(f):
            return None
        step = _direction(grad, hess)
        if step is None:
            return None
        d, definite = step
        decrement = -float(grad @ d)
        if definite and decrement < 2.0 * _DECREMENT_TOL:
            return theta  # a minimum of the negative log-likelihood, not a saddle
        t = 1.0
        full: tuple[float | None, FloatArray, FloatArray] | None = None
        for _ in range(_MAX_BACKTRACK):
            trial = theta + t * d
            if t == 1.0:
                full = _at(name, x, trial, terms)
                f_trial = nll(trial) if full is None or full[0] is None else full[0]
            else:
                f_trial = nll(trial)
            if f_trial <= f - 1e-4 * t * decrement:
                break
            t *= 0.5
        else:
            return theta if definite and decrement < 2.0 * _STALL_TOL else None
        theta, f = trial, f_trial
        here = full if t == 1.0 else _at(name, x, theta, terms)
        if here is None:
            return None  # where the next iteration stops
        _, grad, hess = here
    return None


def fit_optimizer(name: str, x: FloatArray) -> Callable[..., FloatArray]:
    """An ``optimizer`` for ``scipy.stats.<name>.fit(x, optimizer=...)``: Newton's method
    from scipy's start (:func:`hyperloop_env.sts.newton.newton_fit`), and where it does not
    converge scipy's default (``optimize.fmin`` with its defaults) over the compiled
    objective."""
    nll = penalised_nll(name, np.ascontiguousarray(x, dtype=np.float64))

    def run(func: Callable[..., float], x0: FloatArray, args: tuple = (), disp: int = 0) -> Any:
        theta = newton_fit(name, x, x0)
        return optimize.fmin(nll, x0, disp=0) if theta is None else theta

    return run
