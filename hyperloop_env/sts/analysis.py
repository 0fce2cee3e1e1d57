"""The STS procedure: pool, fit, test, bootstrap and account for contacts, per unit and over
episodes (:func:`analyse_unit`, :func:`analyse_episodes`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike
from scipy import stats

from hyperloop_env.sts.bootstrap import (
    _bootstrap_fit_p,
)
from hyperloop_env.sts.common import (
    _BLOCK_TAU_FACTOR,
    _DEGENERATE_RTOL,
    CONFIDENCE,
    DEFAULT_CANDIDATES,
    DEFAULT_CLEARANCE_M,
    UNIT_NAMES,
    FloatArray,
    _as_finite_1d,
    _check_finite,
    _to_generator,
    _validate_common,
)
from hyperloop_env.sts.estimators import (
    _contact_indices,
    _fit_candidate,
    _iat,
    _ks,
    _ks_pvalue,
    _ks_statistic,
    _law_p_unsteady,
    _to_metres,
    wilson_interval,
)
from hyperloop_env.sts.results import (
    EpisodeSignal,
    STSReport,
    UnitSTS,
)


@dataclass(frozen=True)
class _ContactInfo:
    n_contacts: int
    n_contacts_settling: int
    n_terminal_contacts: int
    time_to_contact_s: float | None


def _nan_pair() -> tuple[float, float]:
    return (math.nan, math.nan)


def _no_tests() -> dict[str, Any]:
    """The test and bootstrap fields of a unit that was not fitted (too few samples or a
    constant signal)."""
    nan = math.nan
    return {
        "ks_statistic": nan,
        "ks_pvalue": nan,
        "ks_accepted": False,
        "normal_ks_statistic": nan,
        "normal_ks_pvalue": nan,
        "normal_accepted": False,
        "effective_sample_size": nan,
        "autocorrelation_time": nan,
        "thinning_stride": 0,
        "thinned_n_samples": 0,
        "thinned_ks_pvalue": nan,
        "thinned_ks_accepted": False,
        "thinned_normal_ks_pvalue": nan,
        "block_length": 0,
        "n_boot": 0,
    }


def _point_p_unsteady(f: float, p_fit: float) -> float:
    """P(unsteady) from the episode failure rate ``f`` and the fitted ``p_fit``."""
    if math.isfinite(p_fit):
        return f + (1.0 - f) * p_fit
    return f if f > 0.0 else math.nan


def _finish(
    base: dict[str, Any], f: float, p_fit: float, fit_ci: tuple[float, float], **kw: Any
) -> UnitSTS:
    """The unit's record: ``base`` and ``kw`` plus P(unsteady) combining the episode failure
    rate ``f`` with the fitted ``p_fit`` (and their CIs)."""
    p_un = _point_p_unsteady(f, p_fit)
    if math.isfinite(p_fit):
        if f == 1.0:
            ci = (1.0, 1.0)
        elif all(math.isfinite(c) for c in fit_ci):
            ci = (f + (1.0 - f) * fit_ci[0], f + (1.0 - f) * fit_ci[1])
        else:
            ci = _nan_pair()
    else:
        ci = (f, 1.0)
    return UnitSTS(
        **base,
        **kw,
        p_unsteady_fit=p_fit,
        p_unsteady_fit_ci=fit_ci,
        p_unsteady=p_un,
        p_steady=1.0 - p_un,
        p_unsteady_ci=ci,
    )


@dataclass(frozen=True)
class _LawChoice:
    """The law chosen for the standardised samples and the KS tests behind the choice."""

    name: str
    params: tuple[float, ...]
    ks_d: float
    ks_p: float
    normal_d: float
    normal_p: float
    thin_normal_p: float
    thin_p: float


def _choose_law(
    z: FloatArray,
    z_thin: FloatArray,
    *,
    alpha: float,
    candidates: Sequence[str],
    selection_test: str,
    max_fit_samples: int,
) -> _LawChoice:
    """The normal unless its KS test (thinned or raw, per ``selection_test``) rejects it; then
    the candidate with the smallest raw KS statistic (the normal included)."""
    n = int(z.size)
    norm_params = (0.0, 1.0)
    z_sorted = np.sort(z)
    normal_d = _ks_statistic(z_sorted, "norm", norm_params)
    normal_p = _ks_pvalue(normal_d, n)
    _, thin_normal_p = _ks(z_thin, "norm", norm_params)
    decide_p = thin_normal_p if selection_test == "thinned" else normal_p
    chosen, chosen_params, chosen_d, chosen_p = "norm", norm_params, normal_d, normal_p
    if not decide_p >= alpha:
        z_fit = z
        if n > max_fit_samples:
            z_fit = z[np.linspace(0, n - 1, max_fit_samples).round().astype(np.int64)]
        for cand in dict.fromkeys(str(c) for c in candidates):
            if cand == "norm":
                continue
            params = _fit_candidate(cand, z_fit)
            if params is None:
                continue
            d = _ks_statistic(z_sorted, cand, params)
            if math.isfinite(d) and d < chosen_d:
                chosen, chosen_params, chosen_d = cand, params, d
        if chosen != "norm":
            chosen_p = _ks_pvalue(chosen_d, n)
    _, thin_p = (None, thin_normal_p) if chosen == "norm" else _ks(z_thin, chosen, chosen_params)
    return _LawChoice(
        chosen, chosen_params, chosen_d, chosen_p, normal_d, normal_p, thin_normal_p, thin_p
    )


_NOT_WORST = "none (intervals='worst': only the worst unit's interval was drawn)"


def worst_index(p_unsteady: Sequence[float]) -> int:
    """The unit reported as the worst: the largest finite P(unsteady), the first on a tie
    (the first unit where none is finite)."""
    return max(
        range(len(p_unsteady)),
        key=lambda u: p_unsteady[u] if math.isfinite(p_unsteady[u]) else -1.0,
    )


def _bootstrap_ci(
    law: _LawChoice,
    z: FloatArray,
    lengths: list[int],
    block: int,
    z_hi: float,
    z_lo: float,
    n_boot: int,
    max_fit_samples: int,
    rng: np.random.Generator,
) -> tuple[int, str, tuple[float, float]]:
    """Moving-block bootstrap CI of the fitted P(unsteady): (valid replicates, CI method, CI);
    NaN if fewer than half the replicates (or than 2) gave a finite value."""
    if n_boot <= 0:
        return 0, "none (n_boot=0)", _nan_pair()
    p_b, ci_method = _bootstrap_fit_p(
        law.name, z, law.params, lengths, block, z_hi, z_lo, n_boot, max_fit_samples, rng
    )
    n_tried = int(p_b.size)
    p_b = p_b[np.isfinite(p_b)]
    n_valid = int(p_b.size)
    if n_valid >= max(2, n_tried // 2):
        lo, hi = np.quantile(p_b, [(1 - CONFIDENCE) / 2, (1 + CONFIDENCE) / 2])
        return n_valid, ci_method, (float(lo), float(hi))
    return n_valid, ci_method, _nan_pair()


def _exceedance_ci(
    segments: Sequence[FloatArray],
    exceed: float,
    om: float,
    n: int,
    tau: float,
    fit_ci: tuple[float, float],
) -> tuple[tuple[float, float], bool | None]:
    """Wilson interval of the empirical exceedance with the effective sample size, and whether
    it overlaps the fitted CI (None if either is not finite)."""
    tau_ind = math.nan
    if 0.0 < exceed < 1.0:
        tau_ind = _iat([(np.abs(s) >= om) - exceed for s in segments], n)
    tau_exc = max(tau, tau_ind) if math.isfinite(tau_ind) else tau
    exc_ci = wilson_interval(exceed, n / tau_exc)
    tail_ok: bool | None = None
    if all(math.isfinite(c) for c in (*fit_ci, *exc_ci)):
        tail_ok = not (fit_ci[1] < exc_ci[0] or fit_ci[0] > exc_ci[1])
    return exc_ci, tail_ok


@dataclass(frozen=True)
class _LawFit:
    """A unit's standardised samples with their law chosen and fitted: everything of its
    record but the bootstrap interval and what depends on it."""

    segments: Sequence[FloatArray]
    z: FloatArray
    lengths: list[int]
    law: _LawChoice
    p_fit: float
    tau: float
    stride: int
    n_thin: int
    block: int
    z_hi: float
    z_lo: float
    mean: float
    std: float


def _fit_law(
    segments: Sequence[FloatArray],
    x: FloatArray,
    mean: float,
    std: float,
    om: float,
    *,
    alpha: float,
    candidates: Sequence[str],
    selection_test: str,
    max_fit_samples: int,
) -> _LawFit:
    """Standardise, estimate the autocorrelation, choose and fit the law."""
    n = int(x.size)
    z = (x - mean) / std
    z_segments = [(s - mean) / std for s in segments]
    lengths = [s.size for s in segments]
    tau = _iat(z_segments, n)
    stride = max(1, int(round(tau)))
    z_thin = np.concatenate([s[::stride] for s in z_segments])
    z_hi = (om - mean) / std
    z_lo = (-om - mean) / std

    law = _choose_law(
        z,
        z_thin,
        alpha=alpha,
        candidates=candidates,
        selection_test=selection_test,
        max_fit_samples=max_fit_samples,
    )
    p_fit = float(_law_p_unsteady(law.name, law.params, z_hi, z_lo))
    block = max(1, min(int(math.ceil(_BLOCK_TAU_FACTOR * tau)), max(lengths)))
    return _LawFit(
        segments,
        z,
        lengths,
        law,
        p_fit,
        tau,
        stride,
        int(z_thin.size),
        block,
        z_hi,
        z_lo,
        mean,
        std,
    )


def _with_ci(
    fit: _LawFit,
    exceed: float,
    om: float,
    *,
    alpha: float,
    rng: np.random.Generator,
    n_boot: int,
    max_fit_samples: int,
) -> tuple[float, tuple[float, float], dict[str, Any]]:
    """Bootstrap the fitted law's P(unsteady) and check it against the empirical
    exceedance: (p_fit, its CI, the other fields of the unit's record)."""
    law, n = fit.law, int(fit.z.size)
    n_valid, ci_method, fit_ci = _bootstrap_ci(
        law, fit.z, fit.lengths, fit.block, fit.z_hi, fit.z_lo, n_boot, max_fit_samples, rng
    )
    exc_ci, tail_ok = _exceedance_ci(fit.segments, exceed, om, n, fit.tau, fit_ci)

    return (
        fit.p_fit,
        fit_ci,
        {
            "distribution": law.name,
            "distribution_params": _to_metres(law.params, fit.mean, fit.std),
            "ks_statistic": law.ks_d,
            "ks_pvalue": law.ks_p,
            "ks_accepted": bool(law.ks_p >= alpha),
            "normal_ks_statistic": law.normal_d,
            "normal_ks_pvalue": law.normal_p,
            "normal_accepted": bool(law.normal_p >= alpha),
            "effective_sample_size": n / fit.tau,
            "autocorrelation_time": fit.tau,
            "thinning_stride": fit.stride,
            "thinned_n_samples": fit.n_thin,
            "thinned_ks_pvalue": float(law.thin_p),
            "thinned_ks_accepted": bool(law.thin_p >= alpha),
            "thinned_normal_ks_pvalue": law.thin_normal_p,
            "block_length": fit.block,
            "n_boot": n_valid,
            "ci_method": ci_method,
            "empirical_exceedance_ci": exc_ci,
            "tail_consistent": tail_ok,
        },
    )


def _summary_fields(
    name: str,
    x: FloatArray,
    om: float,
    contacts: _ContactInfo,
    n_episodes: int,
    n_failed: int,
    *,
    alpha: float,
    selection_test: str,
) -> dict[str, Any]:
    """The fields of a unit's record that need no fit: sample moments, empirical exceedance,
    contacts and failures, settings."""
    n = int(x.size)
    nan = math.nan
    mean = float(x.mean()) if n else nan
    std = float(x.std()) if n >= 2 else nan
    exceed = float(np.mean(np.abs(x) >= om)) if n else nan
    return {
        "name": name,
        "n_samples": n,
        "n_episodes": n_episodes,
        "mean_m": mean,
        "std_m": std,
        "empirical_exceedance": exceed,
        "n_contacts": contacts.n_contacts,
        "n_contacts_settling": contacts.n_contacts_settling,
        "n_failed_episodes": n_failed,
        "episode_failure_rate": n_failed / n_episodes,
        "n_terminal_contacts": contacts.n_terminal_contacts,
        "terminated_in_contact": contacts.n_terminal_contacts > 0,
        "time_to_contact_s": contacts.time_to_contact_s,
        "clearance_m": om,
        "alpha": float(alpha),
        "selection_test": selection_test,
    }


@dataclass(frozen=True)
class _Pending:
    """A unit fitted, its bootstrap interval not yet drawn (:func:`_complete`)."""

    base: dict[str, Any]
    f: float
    fit: _LawFit
    alpha: float
    max_fit_samples: int

    @property
    def p_unsteady(self) -> float:
        """The record's ``p_unsteady`` (no interval needed)."""
        return _point_p_unsteady(self.f, self.fit.p_fit)


def _complete(
    unit: UnitSTS | _Pending, rng: np.random.Generator, n_boot: int, no_boot: str = ""
) -> UnitSTS:
    """The unit's record, its fitted P(unsteady) bootstrapped with ``n_boot`` replicates
    (a unit that needed no fit as it is; ``no_boot``: the ``ci_method`` of a unit whose
    interval is not drawn, ``n_boot`` 0)."""
    if not isinstance(unit, _Pending):
        return unit
    pending = unit
    p_fit, fit_ci, fitted = _with_ci(
        pending.fit,
        pending.base["empirical_exceedance"],
        pending.base["clearance_m"],
        alpha=pending.alpha,
        rng=rng,
        n_boot=n_boot,
        max_fit_samples=pending.max_fit_samples,
    )
    if no_boot:
        fitted["ci_method"] = no_boot
    return _finish(pending.base, pending.f, p_fit, fit_ci, **fitted)


def _prepare_pooled(
    name: str,
    segments: Sequence[FloatArray],
    contacts: _ContactInfo,
    n_episodes: int,
    n_failed: int,
    *,
    clearance_m: float,
    alpha: float,
    candidates: Sequence[str],
    selection_test: str,
    min_samples: int,
    max_fit_samples: int,
) -> UnitSTS | _Pending:
    """The unit's record where it needs no fit (too few samples, a constant signal), else
    the fitted unit awaiting its bootstrap interval."""
    segments = [s for s in segments if s.size > 0]
    x = np.concatenate(segments) if segments else np.zeros(0)
    n = int(x.size)
    om = float(clearance_m)
    f = n_failed / n_episodes
    nan = math.nan
    base = _summary_fields(
        name, x, om, contacts, n_episodes, n_failed, alpha=alpha, selection_test=selection_test
    )
    mean, std, exceed = base["mean_m"], base["std_m"], base["empirical_exceedance"]

    # -- too few samples: report, never drop ---------------------------------------------------
    if n < min_samples:
        return _finish(
            base,
            f,
            nan,
            _nan_pair(),
            **_no_tests(),
            distribution="none",
            distribution_params=(),
            ci_method=f"none: fewer than min_samples={min_samples} post-settling samples",
            empirical_exceedance_ci=_nan_pair(),
            tail_consistent=None,
        )

    # -- constant signal: degenerate law ---------------------------------------------------------
    if std <= _DEGENERATE_RTOL * max(om, abs(mean)):
        p_deg = 1.0 if abs(mean) >= om else 0.0
        return _finish(
            base,
            f,
            p_deg,
            (p_deg, p_deg),
            **_no_tests(),
            distribution="degenerate",
            distribution_params=(mean,),
            ci_method="degenerate law (constant signal)",
            empirical_exceedance_ci=(exceed, exceed),
            tail_consistent=True,
        )

    fit = _fit_law(
        segments,
        x,
        mean,
        std,
        om,
        alpha=alpha,
        candidates=candidates,
        selection_test=selection_test,
        max_fit_samples=max_fit_samples,
    )
    return _Pending(base, f, fit, alpha, max_fit_samples)


def _settle_samples(settle_s: float, dt_s: float) -> int:
    return int(math.ceil(settle_s / dt_s - 1e-9)) if settle_s > 0 else 0


# --------------------------------------------------------------------------------------------
# Public analysis API
# --------------------------------------------------------------------------------------------


def analyse_unit(
    signal: ArrayLike,
    dt_s: float,
    *,
    clearance_m: float = DEFAULT_CLEARANCE_M,
    settle_s: float = 0.0,
    alpha: float = 0.05,
    name: str = "",
    terminated_in_contact: bool = False,
    candidates: Sequence[str] = DEFAULT_CANDIDATES,
    rng: int | np.random.Generator | None = 0,
    n_boot: int = 1000,
    selection_test: Literal["thinned", "raw"] = "thinned",
    min_samples: int = 20,
    max_fit_samples: int = 20_000,
) -> UnitSTS:
    """STS of one unit from one episode.

    Args:
        signal: gap excursion s(t) [m], 1-D, sampled every ``dt_s``; must be finite.
        dt_s: sampling period [s], ``> 0``.
        clearance_m: clearance Omega [m], ``> 0``.
        settle_s: settling time [s] discarded before the fit (contacts are still counted).
        alpha: KS significance level in (0, 1).
        name: unit name.
        terminated_in_contact: the episode ended by a contact of this unit.  Then
            ``p_unsteady = 1`` with CI ``(1, 1)`` (contact is absorbing, see module docstring)
            while ``p_unsteady_fit`` still describes the pre-contact samples.
        candidates: scipy.stats continuous laws tried when the normal is rejected.
        rng: seed or Generator of the bootstrap (default 0: reproducible; None: OS entropy).
        n_boot: bootstrap replicates (0 disables the bootstrap CI).
        selection_test: ``"thinned"`` (default) or ``"raw"`` KS test deciding normal rejection.
        min_samples: fewer post-settling samples than this -> ``distribution = "none"``.
        max_fit_samples: cap on the samples used by the candidate MLE fits.

    Raises:
        ValueError: non-finite signal values or invalid arguments (the message names them).
    """
    _validate_common(
        dt_s,
        clearance_m,
        settle_s,
        alpha,
        n_boot,
        min_samples,
        max_fit_samples,
        selection_test,
        candidates,
    )
    x = _as_finite_1d(signal, "signal")
    gen = _to_generator(rng)
    n_settle = _settle_samples(settle_s, dt_s)
    idx = _contact_indices(x, float(clearance_m), bool(terminated_in_contact))
    contacts = _ContactInfo(
        n_contacts=len(idx),
        n_contacts_settling=sum(i < n_settle for i in idx),
        n_terminal_contacts=int(bool(terminated_in_contact)),
        time_to_contact_s=idx[0] * float(dt_s) if idx else None,
    )
    unit = _prepare_pooled(
        name,
        [x[n_settle:]],
        contacts,
        1,
        int(bool(terminated_in_contact)),
        clearance_m=float(clearance_m),
        alpha=float(alpha),
        candidates=candidates,
        selection_test=selection_test,
        min_samples=int(min_samples),
        max_fit_samples=int(max_fit_samples),
    )
    return _complete(unit, gen, int(n_boot))


EpisodeLike = EpisodeSignal | tuple[ArrayLike, bool] | ArrayLike


def _normalise_episode(
    ep: EpisodeLike, i: int, unit_names: Sequence[str]
) -> tuple[FloatArray, bool, tuple[str | int, ...] | None]:
    if isinstance(ep, EpisodeSignal):
        sig, term, who = ep.signal, bool(ep.terminated_in_contact), ep.contact_units
    elif isinstance(ep, tuple) and len(ep) == 2 and isinstance(ep[1], (bool, np.bool_)):
        sig, term, who = ep[0], bool(ep[1]), None
    else:
        sig, term, who = ep, False, None
    try:
        arr = np.asarray(sig, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"episodes[{i}] signal must be numeric: {exc}") from None
    n_units = len(unit_names)
    if arr.ndim == 1 and n_units == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[1] != n_units:
        raise ValueError(
            f"episodes[{i}] signal must have shape (T, {n_units}) to match unit_names "
            f"{tuple(unit_names)}, got {arr.shape}"
        )
    _check_finite(arr, f"episodes[{i}] signal")
    if who is not None and not term:
        raise ValueError(f"episodes[{i}]: contact_units given but terminated_in_contact is False")
    return arr, term, who


def _attribute_contact(
    arr: FloatArray, who: tuple[str | int, ...] | None, unit_names: Sequence[str], om: float, i: int
) -> set[int]:
    if who is not None:
        out = set()
        for u in who:
            if isinstance(u, (int, np.integer)) and 0 <= int(u) < len(unit_names):
                out.add(int(u))
            elif u in unit_names:
                out.add(list(unit_names).index(u))
            else:
                raise ValueError(f"episodes[{i}]: unknown contact unit {u!r}")
        return out
    if arr.shape[0] == 0:
        return set(range(len(unit_names)))
    last = np.abs(arr[-1])
    hit = set(np.flatnonzero(last >= om).tolist())
    return hit if hit else set(np.flatnonzero(last == last.max()).tolist())


def _spawn(rng: int | np.random.Generator | None, n: int) -> list[np.random.Generator]:
    if isinstance(rng, np.random.Generator):
        return list(rng.spawn(n))
    if rng is None or isinstance(rng, (int, np.integer)):
        return [np.random.default_rng(s) for s in np.random.SeedSequence(rng).spawn(n)]
    raise ValueError(f"rng must be None, an int seed or a numpy Generator, got {rng!r}")


def _check_episodes_and_names(episodes: Sequence[EpisodeLike], unit_names: Sequence[str]) -> None:
    if isinstance(unit_names, str) or len(unit_names) == 0:
        raise ValueError(f"unit_names must be a non-empty sequence of names, got {unit_names!r}")
    if len(set(unit_names)) != len(unit_names):
        raise ValueError(f"unit_names must be unique, got {tuple(unit_names)}")
    if isinstance(episodes, np.ndarray) or len(episodes) == 0:
        raise ValueError("episodes must be a non-empty sequence of episodes")


@dataclass(frozen=True)
class _PooledEpisodes:
    """Per unit: the post-settling segments of every episode and the contact counts."""

    segments: list[list[FloatArray]]
    contacts: list[_ContactInfo]
    n_failed: int
    any_contact: bool


def _pool_episodes(
    episodes: Sequence[EpisodeLike],
    unit_names: Sequence[str],
    om: float,
    n_settle: int,
    dt_s: float,
) -> _PooledEpisodes:
    """Validate every episode, attribute its terminal contact, count each unit's contacts and
    collect its post-settling samples."""
    n_units = len(unit_names)
    segments: list[list[FloatArray]] = [[] for _ in range(n_units)]
    n_contacts = [0] * n_units
    n_settling = [0] * n_units
    n_terminal = [0] * n_units
    first_contact: list[float | None] = [None] * n_units
    n_failed = 0
    any_contact = False
    for i, ep in enumerate(episodes):
        arr, term, who = _normalise_episode(ep, i, unit_names)
        culprits = _attribute_contact(arr, who, unit_names, om, i) if term else set()
        n_failed += int(term)
        for u in range(n_units):
            col = arr[:, u]
            segments[u].append(col[n_settle:])
            idx = _contact_indices(col, om, u in culprits)
            n_contacts[u] += len(idx)
            n_settling[u] += sum(j < n_settle for j in idx)
            n_terminal[u] += int(u in culprits)
            if idx:
                any_contact = True
                t = idx[0] * float(dt_s)
                first_contact[u] = t if first_contact[u] is None else min(first_contact[u], t)
    contacts = [
        _ContactInfo(n_contacts[u], n_settling[u], n_terminal[u], first_contact[u])
        for u in range(n_units)
    ]
    return _PooledEpisodes(segments, contacts, n_failed, any_contact)


def analyse_episodes(
    episodes: Sequence[EpisodeLike],
    dt_s: float,
    *,
    unit_names: Sequence[str] = UNIT_NAMES,
    clearance_m: float = DEFAULT_CLEARANCE_M,
    settle_s: float = 0.0,
    alpha: float = 0.05,
    candidates: Sequence[str] = DEFAULT_CANDIDATES,
    rng: int | np.random.Generator | None = 0,
    n_boot: int = 1000,
    selection_test: Literal["thinned", "raw"] = "thinned",
    min_samples: int = 20,
    max_fit_samples: int = 20_000,
    intervals: Literal["all", "worst"] = "all",
) -> STSReport:
    """STS of every unit, pooling the post-settling samples of several episodes (seeds).

    ``dt_s``, ``clearance_m``, ``settle_s``, ``alpha``, ``candidates``, ``n_boot``,
    ``selection_test``, ``min_samples`` and ``max_fit_samples`` are as in
    :func:`analyse_unit`.

    Args:
        episodes: each an :class:`EpisodeSignal`, a tuple ``(signal (T, n_units) [m],
            terminated_in_contact)`` or a bare ``(T, n_units)`` array (not terminated).
            Episodes that terminated in contact are never dropped (see module docstring).
        unit_names: names of the signal columns.
        rng: seed or Generator; independent child streams are spawned per unit.
        intervals: ``"all"`` (default): every unit's bootstrap interval; ``"worst"``: only
            that of the unit with the largest finite ``p_unsteady`` (the first such unit;
            the first unit if none is finite), the others' ``ci_method`` says so and their
            intervals are NaN. That unit's record is the same as with ``"all"`` (each unit
            draws from its own child stream), at a fraction of the bootstrap's cost.

    Returns:
        :class:`STSReport` with one :class:`UnitSTS` per unit.
    """
    _validate_common(
        dt_s,
        clearance_m,
        settle_s,
        alpha,
        n_boot,
        min_samples,
        max_fit_samples,
        selection_test,
        candidates,
    )
    _check_episodes_and_names(episodes, unit_names)
    if intervals not in ("all", "worst"):
        raise ValueError(f"intervals must be 'all' or 'worst', got {intervals!r}")
    om = float(clearance_m)
    n_units = len(unit_names)
    pooled = _pool_episodes(episodes, unit_names, om, _settle_samples(settle_s, dt_s), dt_s)
    n_failed = pooled.n_failed

    n_ep = len(episodes)
    gens = _spawn(rng, n_units)
    prepared = [
        _prepare_pooled(
            str(unit_names[u]),
            pooled.segments[u],
            pooled.contacts[u],
            n_ep,
            n_failed,
            clearance_m=om,
            alpha=float(alpha),
            candidates=candidates,
            selection_test=selection_test,
            min_samples=int(min_samples),
            max_fit_samples=int(max_fit_samples),
        )
        for u in range(n_units)
    ]
    drawn = range(n_units)
    if intervals == "worst":
        drawn = (worst_index([p.p_unsteady for p in prepared]),)
    units = tuple(
        _complete(p, gens[u], int(n_boot)) if u in drawn else _complete(p, gens[u], 0, _NOT_WORST)
        for u, p in enumerate(prepared)
    )
    ci = stats.binomtest(n_failed, n_ep).proportion_ci(CONFIDENCE, method="exact")
    return STSReport(
        units=units,
        dt_s=float(dt_s),
        clearance_m=om,
        settle_s=float(settle_s),
        alpha=float(alpha),
        n_episodes=n_ep,
        n_failed_episodes=n_failed,
        episode_failure_rate=n_failed / n_ep,
        episode_failure_rate_ci=(float(ci.low), float(ci.high)),
        any_contact=pooled.any_contact or n_failed > 0,
    )
