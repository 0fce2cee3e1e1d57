"""Fragility functions and the intervals of a fragility study.

* :func:`clopper_pearson`, :func:`wilson` — 95 % intervals of a binomial proportion
  (contacts in n runs); Clopper–Pearson is exact (never undercovers).
* :func:`poisson_rate_interval` — exact (Garwood) interval of a Poisson count, for the
  contact rate per 100 km (contacts / distance flown).
* :func:`fit_lognormal` — the lognormal fragility function
  ``P(contact | s) = Φ(ln(s/θ)/β)`` fitted by maximum likelihood to binary run outcomes
  grouped by severity level (Baker 2015, "Efficient analytical fragility function fitting
  using dynamic structural analysis data", Earthquake Spectra 31(1)): maximise
  ``Σ_i [z_i ln p_i + (n_i − z_i) ln(1 − p_i)]`` over the median capacity θ and the
  dispersion β, for ``z_i`` contacts in ``n_i`` runs at level ``s_i > 0``. Written as a
  probit regression ``p = Φ(a + b ln s)`` (``b = 1/β``, ``a = −ln θ/β``) the
  log-likelihood is concave, so Newton's method with step halving finds the unique
  maximum when it exists.
* :func:`fit_fragility` — the fit with a bootstrap (runs resampled with replacement within
  each level, i.e. ``z_i* ~ Binomial(n_i, z_i/n_i)``) and honest handling of the data that
  have no finite maximum-likelihood estimate:

  ======================  ==================================================================
  status                  what is reported
  ======================  ==================================================================
  ``fit``                 θ̂, β̂ and percentile bootstrap intervals
  ``no_contact``          no run touched: θ is above the largest level; θ_lower = s_max and
                          the Clopper–Pearson upper bound of P(contact) at s_max
  ``all_contact``         every run touched: θ below the smallest level; θ_upper = s_min
  ``separated``           contacts only at levels ≥ s_hi and none at levels ≤ s_lo (complete
                          separation, s_lo < s_hi): θ in (s_lo, s_hi], β → 0 (the MLE does
                          not exist; a sharp threshold fits the data best)
  ``quasi_separated``     as ``separated`` but one level s_m has both outcomes and every
                          other level is pure: θ → s_m, β → 0
  ``single_level``        all runs at one level: θ and β are not separately identifiable
  ``decreasing``          the fitted slope is negative (fewer contacts at higher severity):
                          no lognormal fragility function describes the data
  ======================  ==================================================================

  Bootstrap replicates that are themselves degenerate are counted (``n_degenerate``) and
  enter the intervals at their limits (β = 0; θ at the separating level, or the geometric
  mean of the separating bracket); all-zero / all-one replicates are excluded from the θ
  interval and counted. The number of replicates is always reported.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from scipy import stats

CONFIDENCE = 0.95


def clopper_pearson(k: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Exact (Clopper–Pearson) interval of a binomial proportion k/n."""
    if n <= 0:
        return (math.nan, math.nan)
    a = 1.0 - confidence
    lo = 0.0 if k == 0 else float(stats.beta.ppf(a / 2, k, n - k + 1))
    hi = 1.0 if k == n else float(stats.beta.ppf(1 - a / 2, k + 1, n - k))
    return lo, hi


def wilson(k: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion k/n."""
    if n <= 0:
        return (math.nan, math.nan)
    z = float(stats.norm.ppf(0.5 + confidence / 2))
    p = k / n
    den = 1 + z * z / n
    c = (p + z * z / (2 * n)) / den
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return max(0.0, c - h), min(1.0, c + h)


def binomial_interval(k: int, n: int, method: str = "exact") -> tuple[float, float]:
    if method == "exact":
        return clopper_pearson(k, n)
    if method == "wilson":
        return wilson(k, n)
    raise ValueError(f"interval method must be 'exact' or 'wilson', got {method!r}")


def poisson_rate_interval(
    k: int, exposure: float, confidence: float = CONFIDENCE
) -> tuple[float, float, float]:
    """(rate, lower, upper) of k events over ``exposure`` (Garwood's exact interval:
    ``χ²(α/2; 2k)/2`` and ``χ²(1 − α/2; 2k + 2)/2`` events)."""
    if not exposure > 0:
        return (math.nan, math.nan, math.nan)
    a = 1.0 - confidence
    lo = 0.0 if k == 0 else float(stats.chi2.ppf(a / 2, 2 * k)) / 2
    hi = float(stats.chi2.ppf(1 - a / 2, 2 * k + 2)) / 2
    return k / exposure, lo / exposure, hi / exposure


# --------------------------------------------------------------------------------------
# lognormal MLE
# --------------------------------------------------------------------------------------


def log_likelihood(theta: float, beta: float, s: np.ndarray, n: np.ndarray, z: np.ndarray) -> float:
    """Binomial log-likelihood (without the constant) of the lognormal fragility."""
    u = np.log(np.asarray(s, float) / theta) / beta
    return float(np.sum(z * stats.norm.logcdf(u) + (n - z) * stats.norm.logsf(u)))


def _probit_mle(
    x: np.ndarray, n: np.ndarray, z: np.ndarray, max_iter: int = 200
) -> tuple[float, float, bool]:
    """Newton's method with step halving on ``p = Φ(a + b·x)``; (a, b, converged)."""
    p0 = (z.sum() + 0.5) / (n.sum() + 1.0)
    a, b = float(stats.norm.ppf(p0)), 0.0
    xm = np.average(x, weights=n)
    if np.any(x != xm):  # start from a moderate slope through the pooled rate
        b = 1.0 / max(np.sqrt(np.average((x - xm) ** 2, weights=n)), 1e-3)
        a = float(stats.norm.ppf(p0)) - b * xm

    def ll(a: float, b: float) -> float:
        u = a + b * x
        return float(np.sum(z * stats.norm.logcdf(u) + (n - z) * stats.norm.logsf(u)))

    cur = ll(a, b)
    for _ in range(max_iter):
        u = a + b * x
        lc, ls = stats.norm.logcdf(u), stats.norm.logsf(u)
        phi = stats.norm.logpdf(u)
        lam1 = np.exp(phi - lc)  # φ/Φ
        lam0 = np.exp(phi - ls)  # φ/(1 − Φ)
        g_u = z * lam1 - (n - z) * lam0  # d ll / d u
        h_u = -z * lam1 * (u + lam1) - (n - z) * lam0 * (lam0 - u)  # d² ll / d u² (< 0)
        g = np.array([g_u.sum(), (g_u * x).sum()])
        h = np.array([[h_u.sum(), (h_u * x).sum()], [(h_u * x).sum(), (h_u * x * x).sum()]])
        try:
            step = -np.linalg.solve(h, g)
        except np.linalg.LinAlgError:
            return a, b, False
        t = 1.0
        while t > 1e-10:
            na, nb = a + t * step[0], b + t * step[1]
            new = ll(na, nb)
            if math.isfinite(new) and new >= cur - 1e-12:
                break
            t *= 0.5
        else:
            return a, b, False
        a, b = na, nb
        done = abs(new - cur) < 1e-12 and np.max(np.abs(t * step)) < 1e-9 * (1 + abs(b))
        cur = new
        if done:
            return a, b, True
    return a, b, False


def classify(s: np.ndarray, n: np.ndarray, z: np.ndarray) -> tuple[str, dict[str, float]]:
    """The status of grouped binary data (see the module docstring) and its bounds."""
    with_contact = s[z > 0]
    with_survivor = s[z < n]
    if with_contact.size == 0:
        return "no_contact", {"theta_lower": float(s.max())}
    if with_survivor.size == 0:
        return "all_contact", {"theta_upper": float(s.min())}
    if np.unique(s).size < 2:
        return "single_level", {"level": float(s[0])}
    s1, s0 = float(with_contact.min()), float(with_survivor.max())
    if s0 < s1:
        return "separated", {"theta_lower": s0, "theta_upper": s1}
    if s0 == s1:
        return "quasi_separated", {"theta_limit": s0}
    return "fit", {}


def fit_lognormal(s: Any, n: Any, z: Any) -> dict[str, Any]:
    """Maximum-likelihood θ, β of ``Φ(ln(s/θ)/β)`` for ``z`` contacts in ``n`` runs at
    levels ``s`` (> 0); ``{"status", "theta", "beta", …}`` (θ, β NaN unless status is
    ``fit``; bounds as in the module docstring)."""
    s = np.asarray(s, dtype=float)
    n = np.asarray(n, dtype=np.int64)
    z = np.asarray(z, dtype=np.int64)
    if s.shape != n.shape or s.shape != z.shape or s.ndim != 1 or s.size == 0:
        raise ValueError("s, n and z must be 1-D arrays of the same, non-zero length")
    if np.any(~np.isfinite(s)) or np.any(s <= 0):
        raise ValueError(f"severity levels must be finite and > 0 for a lognormal fit, got {s}")
    if np.any(n < 1) or np.any(z < 0) or np.any(z > n):
        raise ValueError("need n >= 1 and 0 <= z <= n at every level")
    status, bounds = classify(s, n, z)
    out: dict[str, Any] = {"status": status, "theta": math.nan, "beta": math.nan, **bounds}
    if status != "fit":
        return out
    a, b, ok = _probit_mle(np.log(s), n.astype(float), z.astype(float))
    if not ok or not (math.isfinite(a) and math.isfinite(b)):
        out["status"] = "no_convergence"
        return out
    if b <= 0:
        out["status"] = "decreasing"
        return out
    out["theta"] = float(math.exp(-a / b))
    out["beta"] = float(1.0 / b)
    out["log_likelihood"] = log_likelihood(out["theta"], out["beta"], s, n, z)
    return out


@dataclass
class FragilityFit:
    """A fitted fragility function with its bootstrap (see the module docstring)."""

    status: str
    theta: float
    beta: float
    theta_ci: tuple[float, float]
    beta_ci: tuple[float, float]
    n_boot: int
    n_boot_fit: int
    n_degenerate: int
    n_excluded: int
    bounds: dict[str, float] = field(default_factory=dict)
    levels: list[float] = field(default_factory=list)
    n_runs: list[int] = field(default_factory=list)
    n_contacts: list[int] = field(default_factory=list)
    note: str = ""

    def probability(self, s: Any) -> np.ndarray:
        """The fitted P(contact | s) (NaN unless status is ``fit``)."""
        s = np.asarray(s, dtype=float)
        if self.status != "fit":
            return np.full(s.shape, np.nan)
        with np.errstate(divide="ignore"):
            return stats.norm.cdf(np.log(s / self.theta) / self.beta)

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)

        def clean(v: Any) -> Any:
            if isinstance(v, float):
                return v if math.isfinite(v) else None
            if isinstance(v, list | tuple):
                return [clean(x) for x in v]
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items()}
            return v

        return clean(d)

    def summary(self, unit: str = "") -> str:
        """One line for reports."""
        u = f" {unit}" if unit else ""
        b = self.bounds
        if self.status == "fit":
            return (
                f"θ = {self.theta:.4g}{u} [{self.theta_ci[0]:.4g}, {self.theta_ci[1]:.4g}], "
                f"β = {self.beta:.3g} [{self.beta_ci[0]:.3g}, {self.beta_ci[1]:.3g}] "
                f"({self.n_boot} bootstrap replicates, "
                f"{self.n_degenerate} degenerate)"
            )
        if self.status == "no_contact":
            return f"no contact at any level: θ > {b['theta_lower']:.4g}{u}"
        if self.status == "all_contact":
            return f"contact at every level: θ < {b['theta_upper']:.4g}{u}"
        if self.status == "separated":
            return (
                f"separated data: θ in ({b['theta_lower']:.4g}, {b['theta_upper']:.4g}]{u}, "
                "β → 0 (no finite MLE)"
            )
        if self.status == "quasi_separated":
            return f"quasi-separated data: θ → {b['theta_limit']:.4g}{u}, β → 0 (no finite MLE)"
        if self.status == "single_level":
            return f"one level only ({b['level']:.4g}{u}): θ and β not identifiable"
        return f"{self.status}: no fragility function fitted"


def _replicate_point(fit: dict[str, Any]) -> tuple[float, float, bool] | None:
    """(θ, β, degenerate) a bootstrap replicate contributes, None to exclude it."""
    st = fit["status"]
    if st == "fit":
        return fit["theta"], fit["beta"], False
    if st == "separated":
        return math.sqrt(fit["theta_lower"] * fit["theta_upper"]), 0.0, True
    if st == "quasi_separated":
        return fit["theta_limit"], 0.0, True
    return None


def fit_fragility(
    s: Any,
    n: Any,
    z: Any,
    n_boot: int = 1000,
    rng: int | np.random.Generator | None = 0,
) -> FragilityFit:
    """Lognormal fragility MLE with a within-level bootstrap of the runs (module docstring).
    Levels ≤ 0 are left out of the fit (ln 0) and named in ``note``."""
    s = np.asarray(s, dtype=float)
    n = np.asarray(n, dtype=np.int64)
    z = np.asarray(z, dtype=np.int64)
    note = ""
    pos = s > 0
    if not pos.all():
        note = f"levels {s[~pos].tolist()} (<= 0) left out of the fit"
        s, n, z = s[pos], n[pos], z[pos]
    if s.size == 0:
        return FragilityFit(
            "no_levels",
            math.nan,
            math.nan,
            (math.nan,) * 2,
            (math.nan,) * 2,
            0,
            0,
            0,
            0,
            note=note or "no level > 0",
        )
    base = fit_lognormal(s, n, z)
    keys = ("theta_lower", "theta_upper", "theta_limit", "level")
    bounds = {k: v for k, v in base.items() if k in keys and base["status"] != "fit"}
    res = FragilityFit(
        status=base["status"],
        theta=base["theta"],
        beta=base["beta"],
        theta_ci=(math.nan, math.nan),
        beta_ci=(math.nan, math.nan),
        n_boot=0,
        n_boot_fit=0,
        n_degenerate=0,
        n_excluded=0,
        bounds=bounds,
        levels=s.tolist(),
        n_runs=n.tolist(),
        n_contacts=z.tolist(),
        note=note,
    )
    if base["status"] != "fit" or n_boot <= 0:
        return res
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    p_hat = z / n
    thetas, betas = [], []
    n_deg = n_exc = n_fit = 0
    for _ in range(int(n_boot)):
        zb = gen.binomial(n, p_hat)
        pt = _replicate_point(fit_lognormal(s, n, zb))
        if pt is None:
            n_exc += 1
            continue
        thetas.append(pt[0])
        betas.append(pt[1])
        n_deg += int(pt[2])
        n_fit += int(not pt[2])
    res.n_boot = int(n_boot)
    res.n_boot_fit = n_fit
    res.n_degenerate = n_deg
    res.n_excluded = n_exc
    q = [(1 - CONFIDENCE) / 2, (1 + CONFIDENCE) / 2]
    if len(thetas) >= 2:
        res.theta_ci = tuple(float(v) for v in np.quantile(thetas, q))  # type: ignore[assignment]
        res.beta_ci = tuple(float(v) for v in np.quantile(betas, q))  # type: ignore[assignment]
    return res
