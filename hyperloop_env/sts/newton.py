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
iteration needs there, which also yields the penalised objective bit for bit (the pass's
terms are ``penalised_nll``'s own, :func:`~hyperloop_env.sts.compiled.law_terms`, summed
the same way): an iteration whose full step is accepted costs one pass; only backtracked
trials pass over the sample again.

A pass evaluates each sample's transcendental parts once, with numpy's vectorised log1p and
exp (``law_terms``' parts: y, log1p(y²/ν); log1p(−c y), its 1/c multiple and exp;
log Φ(a y) and φ/Φ), and sums the derivatives below in one compiled loop per law whose
summation order is left to the compiler (``fastmath`` reassociation, so vectorised: the
gradient and Hessian steer the steps and are not compared bit for bit; the objective is).

The result is the likelihood's maximum, so it agrees with scipy's Nelder–Mead result to
scipy's tolerance (not to rounding), with a log-likelihood at least as large; the tolerance
stated and tested in ``tests/env/test_sts_compiled.py``. Where Newton does not converge (a
maximum on the support's boundary, a start too far away) it returns None and the caller
keeps scipy's Nelder–Mead.

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
    gev_parts,
    law_terms,
    penalised_nll,
    penalised_value,
    scratch,
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


# The sums' order is free (reassociated, hence vectorised; no nnan: a NaN still shows). The
# per-sample functions say fastmath=False: numba's callees inherit a caller's fastmath
# unless they set it, and whichever caller compiled them first would decide their rounding.
_FAST = {"reassoc", "nsz", "arcp", "contract"}
_ROWS = 10  # the pass's scratch: law_terms' parts, and genextreme's at c + h and c − h
_GEV_FD = 3  # the law code of genextreme's central differences in c


@nb.njit(cache=True, error_model="numpy", fastmath=False)
def _d_t(
    P: FloatArray, i: int, s: float, h: float, k1: float, k3: float, k4: float
) -> tuple[float, float, float, float, float, float, float]:
    """``t``'s (y, g, g_y, g_yy, g_ν, g_νν, g_νy) of sample ``i`` (row 1: log1p(y²/ν); k1 =
    c(ν), k3 = c′(ν), k4 = c″(ν))."""
    y = P[0, i]
    lq = P[1, i]
    y2 = y * y
    q = s + y2
    nq = s * q
    return (
        y,
        k1 - 0.5 * (s + 1.0) * lq,
        -(s + 1.0) * y / q,
        -(s + 1.0) * (s - y2) / (q * q),
        k3 - 0.5 * lq + (s + 1.0) * y2 / (2.0 * s * q),
        k4 + y2 / (2.0 * nq) + 0.5 * y2 * (nq - (s + 1.0) * (q + s)) / (nq * nq),
        -y * (y2 - 1.0) / (q * q),
    )


@nb.njit(cache=True, error_model="numpy", fastmath=False)
def _d_skew(
    P: FloatArray, i: int, s: float, h: float, k1: float, k3: float, k4: float
) -> tuple[float, float, float, float, float, float, float]:
    """``skewnorm``'s (y, g, g_y, g_yy, g_a, g_aa, g_ay) of sample ``i`` (row 1: log Φ(a y),
    row 3: r(a y) = φ/Φ)."""
    y = P[0, i]
    v = s * y
    r = P[3, i]
    norm = -(y**2) / 2.0 - _LOG_SQRT_2PI
    g = norm if s == 0.0 else _LOG2 + norm + P[1, i]
    rr = r * (v + r)
    return y, g, -y + s * r, -1.0 - s * s * rr, y * r, -y * y * rr, r - v * rr


@nb.njit(cache=True, error_model="numpy", fastmath=False)
def _gev_g3(y: float, lu: float, p: float, w: float, s: float) -> tuple[float, float, float]:
    """``genextreme``'s (g, g_y, g_yy) from its parts lu, p, w at shape ``s`` (at c = 0,
    lu = 0 and p = −y: −e^(−y) − y, e^(−y) − 1, −e^(−y))."""
    u = 1.0 - s * y
    return -w + p - lu, (w - 1.0 + s) / u, (s * (w - 1.0 + s) - w) / (u * u)


@nb.njit(cache=True, error_model="numpy", fastmath=False)
def _d_gev(
    P: FloatArray, i: int, s: float, h: float, k1: float, k3: float, k4: float
) -> tuple[float, float, float, float, float, float, float]:
    """``genextreme``'s (y, g, g_y, g_yy, g_c, g_cc, g_cy) of sample ``i`` in closed form
    (rows 1–3: lu, p, w)."""
    y = P[0, i]
    lu = P[1, i]
    w = P[3, i]
    g, gy, gyy = _gev_g3(y, lu, P[2, i], w, s)
    u = 1.0 - s * y
    l_c = -y / u
    l_cc = -(y * y) / (u * u)
    t_c = l_c / s - lu / (s * s)
    t_cc = l_cc / s - 2.0 * l_c / (s * s) + 2.0 * lu / (s * s * s)
    g_c = (1.0 - w) * t_c - l_c
    g_cc = (1.0 - w) * t_cc - w * t_c * t_c - l_cc
    g_cy = ((w * t_c + 1.0) * u + y * (w - 1.0 + s)) / (u * u)
    return y, g, gy, gyy, g_c, g_cc, g_cy


@nb.njit(cache=True, error_model="numpy", fastmath=False)
def _d_gev_fd(
    P: FloatArray, i: int, s: float, h: float, k1: float, k3: float, k4: float
) -> tuple[float, float, float, float, float, float, float]:
    """``genextreme``'s (y, g, g_y, g_yy, g_c, g_cc, g_cy) of sample ``i``, the shape
    derivatives by central differences with step ``h`` (rows 4–6 and 7–9: the parts at
    c + h and c − h)."""
    y = P[0, i]
    g, gy, gyy = _gev_g3(y, P[1, i], P[2, i], P[3, i], s)
    gp, gyp, _ = _gev_g3(y, P[4, i], P[5, i], P[6, i], s + h)
    gm, gym, _ = _gev_g3(y, P[7, i], P[8, i], P[9, i], s - h)
    g_c = (gp - gm) / (2.0 * h)
    return y, g, gy, gyy, g_c, (gp - 2.0 * g + gm) / (h * h), (gyp - gym) / (2.0 * h)


@nb.njit(cache=True, error_model="numpy", fastmath=False)
def _d6(
    law: int, P: FloatArray, i: int, s: float, h: float, k1: float, k3: float, k4: float
) -> tuple[float, float, float, float, float, float, float]:
    """Sample ``i``'s (y, g, g_y, g_yy, g_s, g_ss, g_sy) of law code ``law`` (0 ``t``, 1
    ``genextreme``, 2 ``skewnorm``, 3 ``genextreme`` by central differences in c)."""
    if law == 0:
        return _d_t(P, i, s, h, k1, k3, k4)
    if law == 1:
        return _d_gev(P, i, s, h, k1, k3, k4)
    if law == 2:
        return _d_skew(P, i, s, h, k1, k3, k4)
    return _d_gev_fd(P, i, s, h, k1, k3, k4)


_Sums = tuple[float, float, float, float, float, float, float, float, float, float]


@nb.njit(cache=True, error_model="numpy", fastmath=_FAST)
def _acc(
    a: _Sums, y: float, g: float, gy: float, gyy: float, gs: float, gss: float, gsy: float
) -> _Sums:
    """One sample added to the sums Σg, Σg_y, Σy g_y, Σg_yy, Σy g_yy, Σy² g_yy, Σg_s,
    Σg_ss, Σg_sy, Σy g_sy."""
    return (
        a[0] + g,
        a[1] + gy,
        a[2] + y * gy,
        a[3] + gyy,
        a[4] + y * gyy,
        a[5] + y * y * gyy,
        a[6] + gs,
        a[7] + gss,
        a[8] + gsy,
        a[9] + y * gsy,
    )


# One loop per law: a loop over one law's arithmetic is vectorised, a switch inside is not, and
# a kernel taking the per-sample function as an argument is recompiled in every process
# (numba's disk cache does not key it), so the four loops are written out.
@nb.njit(cache=True, error_model="numpy", fastmath=_FAST)
def _sums_t(P: FloatArray, s: float, h: float, k1: float, k3: float, k4: float) -> _Sums:
    a = (0.0,) * 10
    for i in range(P.shape[1]):
        y, g, gy, gyy, gs, gss, gsy = _d_t(P, i, s, h, k1, k3, k4)
        a = _acc(a, y, g, gy, gyy, gs, gss, gsy)
    return a


@nb.njit(cache=True, error_model="numpy", fastmath=_FAST)
def _sums_gev(P: FloatArray, s: float, h: float, k1: float, k3: float, k4: float) -> _Sums:
    a = (0.0,) * 10
    for i in range(P.shape[1]):
        y, g, gy, gyy, gs, gss, gsy = _d_gev(P, i, s, h, k1, k3, k4)
        a = _acc(a, y, g, gy, gyy, gs, gss, gsy)
    return a


@nb.njit(cache=True, error_model="numpy", fastmath=_FAST)
def _sums_skew(P: FloatArray, s: float, h: float, k1: float, k3: float, k4: float) -> _Sums:
    a = (0.0,) * 10
    for i in range(P.shape[1]):
        y, g, gy, gyy, gs, gss, gsy = _d_skew(P, i, s, h, k1, k3, k4)
        a = _acc(a, y, g, gy, gyy, gs, gss, gsy)
    return a


@nb.njit(cache=True, error_model="numpy", fastmath=_FAST)
def _sums_gev_fd(P: FloatArray, s: float, h: float, k1: float, k3: float, k4: float) -> _Sums:
    a = (0.0,) * 10
    for i in range(P.shape[1]):
        y, g, gy, gyy, gs, gss, gsy = _d_gev_fd(P, i, s, h, k1, k3, k4)
        a = _acc(a, y, g, gy, gyy, gs, gss, gsy)
    return a


_LAW_SUMS = (_sums_t, _sums_gev, _sums_skew, _sums_gev_fd)  # by law code


@nb.njit(cache=True, error_model="numpy")
def _assemble(a: _Sums, n: int, scale: float) -> tuple[float, FloatArray, FloatArray, bool]:
    """The negative log-likelihood's value, gradient and Hessian over (shape, loc, scale)
    from the sums (:func:`_acc`), with y = (x − loc)/scale and log f = g − log scale:
    ∂/∂loc = −g_y/scale, ∂/∂scale = −(y g_y + 1)/scale, ∂/∂s = g_s and the second
    derivatives of the module's docstring; ``ok`` False if any is not finite."""
    sg, sgy, sygy, sgyy, sygyy, syygyy, sgs, sgss, sgsy, sygsy = a
    s2 = scale * scale
    grad = np.array([-sgs, sgy / scale, (sygy + n) / scale])
    hess = np.empty((3, 3))
    hess[0, 0] = -sgss
    hess[0, 1] = hess[1, 0] = sgsy / scale
    hess[0, 2] = hess[2, 0] = sygsy / scale
    hess[1, 1] = -sgyy / s2
    hess[1, 2] = hess[2, 1] = -(sgy + sygyy) / s2
    hess[2, 2] = -(2.0 * sygy + syygyy + n) / s2
    value = -sg + n * math.log(scale)
    ok = math.isfinite(value) and np.isfinite(grad).all() and np.isfinite(hess).all()
    return value, grad, hess, ok


def _sums(
    law: int, P: FloatArray, s: float, scale: float, h: float, k1: float, k3: float, k4: float
) -> tuple[float, FloatArray, FloatArray, bool]:
    """The negative log-likelihood's value, gradient and Hessian from the per-sample
    derivatives of law code ``law`` (:func:`_d6`), summed in any order (vectorised: they
    steer Newton's steps; the objective the line search compares is
    :func:`~hyperloop_env.sts.compiled.penalised_value`'s); ``ok`` False if any is not
    finite."""
    return _assemble(_LAW_SUMS[law](P, s, h, k1, k3, k4), P.shape[1], scale)


@nb.njit(cache=True, error_model="numpy", fastmath=False)
def _per_sample(
    law: int, P: FloatArray, s: float, h: float, k1: float, k3: float, k4: float
) -> FloatArray:
    """``(n, 6)``: g, g_y, g_yy, g_s, g_ss, g_sy of every sample (:func:`_d6`)."""
    out = np.empty((P.shape[1], 6))
    for i in range(P.shape[1]):
        _, g, gy, gyy, gs, gss, gsy = _d6(law, P, i, s, h, k1, k3, k4)
        out[i, 0] = g
        out[i, 1] = gy
        out[i, 2] = gyy
        out[i, 3] = gs
        out[i, 4] = gss
        out[i, 5] = gsy
    return out


_LAWS = {"t": 0, "genextreme": 1, "skewnorm": 2}
NEWTON_LAWS = frozenset(_LAWS)


def _prepare(
    name: str, x: FloatArray, theta: FloatArray, h: float, P: FloatArray, terms: FloatArray
) -> tuple[int, int] | None:
    """The pass's parts at ``theta`` into ``P`` (``_ROWS`` rows) and the penalised
    objective's terms into ``terms`` (:func:`~hyperloop_env.sts.compiled.law_terms`, the
    objective's own evaluation): (the law code for :func:`_d6`, the count of non-finite
    terms); None for a shape outside the law's domain. Adds skewnorm's r(a y) = φ/Φ and,
    for genextreme within 0.01 of c = 0, its parts at c ± h (numpy's vectorised exp and
    log1p)."""
    bad = law_terms(name, x, theta, P, terms)
    if bad is None:
        return None
    s = float(theta[0])
    if name == "skewnorm":
        v, r = P[2], P[3]  # v = a y from law_terms
        np.multiply(v, v, out=r)
        r *= -0.5
        r -= _LOG_SQRT_2PI
        r -= P[1]
        with np.errstate(all="ignore"):
            np.exp(r, out=r)
    if name == "genextreme" and abs(s) < _GEV_CLOSED_FORM:
        gev_parts(P[0], s + h, P[4], P[5], P[6])
        gev_parts(P[0], s - h, P[7], P[8], P[9])
        return _GEV_FD, bad
    return _LAWS[name], bad


def _parts_at(
    name: str, x: FloatArray, params: tuple[float, ...]
) -> tuple[int, FloatArray, float, FloatArray] | None:
    """(law code, parts, h, t's constants) of :func:`_prepare` at ``params``; None for
    parameters outside the law's domain."""
    theta = np.asarray(params, dtype=np.float64)
    shape = float(theta[0])
    if not theta[2] > 0.0:
        return None
    h = _H * (1.0 + abs(shape))
    if name == "t" and not shape - h > 0.0:
        return None
    x = np.ascontiguousarray(x, dtype=np.float64)
    P = scratch(x.size, _ROWS)
    prep = _prepare(name, x, theta, h, P, np.empty_like(x))
    if prep is None:
        return None
    return prep[0], P, h, _step_consts(name, shape, h)


def per_sample(name: str, x: FloatArray, params: tuple[float, ...]) -> FloatArray | None:
    """``(n, 6)``: g = log f + log scale and its derivatives g_y, g_yy, g_s, g_ss, g_sy at
    y = (x − loc)/scale of every sample (the closed forms above); None for parameters
    outside the law's domain. Not finite outside the support."""
    at = _parts_at(name, x, params)
    if at is None:
        return None
    law, P, h, c = at
    return _per_sample(law, P, float(params[0]), h, c[1], c[3], c[4])


def scores_and_hessian(
    name: str, x: FloatArray, params: tuple[float, ...]
) -> tuple[FloatArray, FloatArray] | None:
    """Per-sample scores ``(n, 3)`` of log f over (shape, loc, scale) and the mean Hessian
    ``(3, 3)`` of log f, at ``params``; None if a sample is outside the support or a term
    is not finite."""
    at = _parts_at(name, x, params)
    if at is None:
        return None
    law, P, h, c = at
    shape, scale = float(params[0]), float(params[2])
    _, _, hess, ok = _sums(law, P, shape, scale, h, c[1], c[3], c[4])
    d = _per_sample(law, P, shape, h, c[1], c[3], c[4])
    if not ok or not np.isfinite(d).all():
        return None
    y, gy = P[0], d[:, 1]
    s0 = np.column_stack([d[:, 3], -gy / scale, -(y * gy + 1.0) / scale])
    return s0, -hess / y.size


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


@nb.njit(cache=True, error_model="numpy")
def _cholesky3(a: FloatArray) -> tuple[FloatArray, bool]:
    """The lower Cholesky factor of a symmetric 3×3 ``a``; False where a pivot is not
    positive (``a`` not positive definite, LAPACK's ``potrf`` failure)."""
    low = np.zeros((3, 3))
    for j in range(3):
        d = a[j, j]
        for k in range(j):
            d -= low[j, k] * low[j, k]
        if not d > 0.0:
            return low, False
        low[j, j] = math.sqrt(d)
        for i in range(j + 1, 3):
            v = a[i, j]
            for k in range(j):
                v -= low[i, k] * low[j, k]
            low[i, j] = v / low[j, j]
    return low, True


@nb.njit(cache=True, error_model="numpy")
def _direction_core(grad: FloatArray, hess: FloatArray) -> tuple[FloatArray, bool, bool]:
    """(−H⁻¹ g, H positive definite, a direction found): :func:`_direction` compiled."""
    eig = np.linalg.eigvalsh(hess)
    if eig[0] > _CONDITION * eig[-1]:
        return -np.linalg.solve(hess, grad), True, True
    lam = 0.0
    scale = max(abs(hess[0, 0]), abs(hess[1, 1]), abs(hess[2, 2]))
    scale = scale if scale != 0.0 else 1.0
    for _ in range(60):
        low, ok = _cholesky3(hess + lam * np.eye(3))
        if not ok:
            lam = max(2.0 * lam, 1e-8 * scale)
            continue
        v = np.zeros(3)  # L v = g, then Lᵀ d = v
        for i in range(3):
            v[i] = (grad[i] - low[i, 0] * v[0] - low[i, 1] * v[1]) / low[i, i]
        d = np.zeros(3)
        for i in range(2, -1, -1):
            s = v[i]
            for k in range(i + 1, 3):
                s -= low[k, i] * d[k]
            d[i] = s / low[i, i]
        return -d, False, True
    return np.zeros(3), False, False


def _direction(grad: FloatArray, hess: FloatArray) -> tuple[FloatArray, bool] | None:
    """(−H⁻¹ g, whether H is positive definite), with H shifted by λ I (Levenberg–Marquardt)
    until positive definite where its smallest eigenvalue is not above 1e-6 of its largest
    (a saddle, or skewnorm's singular information at a = 0); None where no shift up to
    2⁵⁹·1e-8 of H's largest diagonal entry makes it so. Compiled (:func:`_direction_core`):
    LAPACK's ``syevd`` and ``gesv`` as numpy's, the shifted systems by a 3×3 Cholesky."""
    d, definite, found = _direction_core(grad, hess)
    return (d, definite) if found else None


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
    name: str, x: FloatArray, theta: FloatArray, terms: FloatArray, P: FloatArray
) -> tuple[float | None, FloatArray, FloatArray] | None:
    """One pass at ``theta``: (the penalised objective or None, gradient, Hessian); None
    where Newton stops there (:func:`_guard`, a shape outside the law's domain, or a term,
    gradient or Hessian not finite). The objective is
    :func:`~hyperloop_env.sts.compiled.penalised_value` of the pass's terms, which are
    :func:`~hyperloop_env.sts.compiled.penalised_nll`'s (the same
    :func:`~hyperloop_env.sts.compiled.law_terms`, the same numpy sum): bit for bit its
    value. None (the caller then calls ``penalised_nll``) where that would take another
    branch: a term not finite (the penalty)."""
    h = _guard(name, theta)
    if h is None:
        return None
    shape = float(theta[0])
    prep = _prepare(name, x, theta, h, P, terms)
    if prep is None:
        return None
    law, bad = prep
    c = _step_consts(name, shape, h)
    _, grad, hess, ok = _sums(law, P, shape, float(theta[2]), h, c[1], c[3], c[4])
    if not ok:
        return None
    return (penalised_value(terms, 0, float(theta[2])) if bad == 0 else None), grad, hess


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
    terms, P = np.empty_like(x), scratch(x.size, _ROWS)
    theta = _feasible(name, x, np.asarray(x0, dtype=np.float64).copy())
    here = _at(name, x, theta, terms, P)
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
                full = _at(name, x, trial, terms, P)
                f_trial = nll(trial) if full is None or full[0] is None else full[0]
            else:
                f_trial = nll(trial)
            if f_trial <= f - 1e-4 * t * decrement:
                break
            t *= 0.5
        else:
            return theta if definite and decrement < 2.0 * _STALL_TOL else None
        theta, f = trial, f_trial
        here = full if t == 1.0 else _at(name, x, theta, terms, P)
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
