"""Result records of the STS analysis (per unit, per report, per episode)."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

from numpy.typing import ArrayLike

from hyperloop_env.json_values import json_value


@dataclass(frozen=True)
class UnitSTS:
    """STS result of one magnet unit (pooled over the analysed episodes).

    Lengths in metres, times in seconds, probabilities in [0, 1]; NaN means "not available"
    (``to_dict`` turns NaN into ``None``).
    """

    name: str
    n_samples: int
    """Post-settling samples analysed (pooled over episodes)."""
    n_episodes: int
    mean_m: float
    std_m: float
    """Sample standard deviation (``ddof=0``, the normal MLE) [m]."""
    distribution: str
    """Chosen law: a scipy.stats name, ``"degenerate"`` (constant signal) or ``"none"``."""
    distribution_params: tuple[float, ...]
    """scipy parameter order (shapes..., loc [m], scale [m]); ``(value,)`` if degenerate."""
    ks_statistic: float
    """Raw KS statistic of the chosen law on all pooled samples."""
    ks_pvalue: float
    ks_accepted: bool
    """``ks_pvalue >= alpha`` (raw test, as in the paper)."""
    normal_ks_statistic: float
    normal_ks_pvalue: float
    normal_accepted: bool
    """Raw KS test of the normal fit, always reported as the paper does."""
    effective_sample_size: float
    autocorrelation_time: float
    """Integrated autocorrelation time tau [samples]."""
    thinning_stride: int
    thinned_n_samples: int
    thinned_ks_pvalue: float
    """KS p-value of the chosen law on the sample thinned with stride ``round(tau)``."""
    thinned_ks_accepted: bool
    thinned_normal_ks_pvalue: float
    selection_test: str
    """``"thinned"`` or ``"raw"``: the test that decided whether the normal was rejected."""
    p_unsteady_fit: float
    """``P(|s| >= Omega)`` under the fitted law (conditioned on survival)."""
    p_unsteady_fit_ci: tuple[float, float]
    ci_method: str
    block_length: int
    """Moving-block bootstrap block length [samples]."""
    n_boot: int
    """Number of valid bootstrap replicates behind ``p_unsteady_fit_ci``."""
    p_steady: float
    p_unsteady: float
    """``f + (1 - f) * p_unsteady_fit`` with ``f`` the episode failure rate (>= ``f``)."""
    p_unsteady_ci: tuple[float, float]
    empirical_exceedance: float
    """Fraction of post-settling samples with ``|s| >= Omega``."""
    empirical_exceedance_ci: tuple[float, float]
    tail_consistent: bool | None
    """False if ``p_unsteady_fit_ci`` and ``empirical_exceedance_ci`` are disjoint (the fitted
    tail contradicts the observed exceedance); None if not assessable."""
    n_contacts: int
    """Entries into ``|s| >= Omega`` over whole episodes, terminal contacts included."""
    n_contacts_settling: int
    n_failed_episodes: int
    """Episodes (vehicle level) that terminated in contact."""
    episode_failure_rate: float
    n_terminal_contacts: int
    """Terminal contacts attributed to this unit."""
    terminated_in_contact: bool
    """True if at least one episode terminated by a contact of this unit."""
    time_to_contact_s: float | None
    """Earliest contact time from the start of an episode [s], None if no contact."""
    clearance_m: float
    alpha: float

    @property
    def p_unsteady_ci_width(self) -> float:
        """Width of ``p_unsteady_ci``."""
        return self.p_unsteady_ci[1] - self.p_unsteady_ci[0]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (NaN/inf -> None, tuples -> lists)."""
        return {f.name: json_value(getattr(self, f.name)) for f in fields(self)}


@dataclass(frozen=True)
class STSReport:
    """STS of all units over a set of episodes (seeds)."""

    units: tuple[UnitSTS, ...]
    dt_s: float
    clearance_m: float
    settle_s: float
    alpha: float
    n_episodes: int
    n_failed_episodes: int
    episode_failure_rate: float
    episode_failure_rate_ci: tuple[float, float]
    """Clopper-Pearson 95 % interval of the per-episode failure probability (new seeds)."""
    any_contact: bool
    """True if any unit had any contact in any episode (settling included)."""

    @property
    def worst_p_unsteady(self) -> float:
        """Largest ``p_unsteady`` over units (NaN if any unit's value is undetermined)."""
        values = [u.p_unsteady for u in self.units]
        if not values or any(not math.isfinite(v) for v in values):
            return math.nan
        return max(values)

    @property
    def worst_unit(self) -> str | None:
        """Name of the unit with the largest ``p_unsteady`` (None if undetermined)."""
        if not math.isfinite(self.worst_p_unsteady):
            return None
        return max(self.units, key=lambda u: u.p_unsteady).name

    def unit(self, name: str) -> UnitSTS:
        """Result of the unit called ``name``."""
        for u in self.units:
            if u.name == name:
                return u
        raise KeyError(name)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict of the whole report."""
        out: dict[str, Any] = {
            f.name: json_value(getattr(self, f.name)) for f in fields(self) if f.name != "units"
        }
        out["worst_p_unsteady"] = json_value(self.worst_p_unsteady)
        out["worst_unit"] = self.worst_unit
        out["units"] = [u.to_dict() for u in self.units]
        return out

    def to_rows(self) -> list[dict[str, Any]]:
        """One flat dict per unit, for CSV (non-finite values -> None)."""
        rows = []
        for u in self.units:
            row = {
                "unit": u.name,
                "n_samples": u.n_samples,
                "n_episodes": u.n_episodes,
                "mean_mm": u.mean_m * 1e3,
                "std_mm": u.std_m * 1e3,
                "distribution": u.distribution,
                "ks_statistic": u.ks_statistic,
                "ks_pvalue": u.ks_pvalue,
                "ks_accepted": u.ks_accepted,
                "thinned_ks_pvalue": u.thinned_ks_pvalue,
                "normal_ks_pvalue": u.normal_ks_pvalue,
                "effective_sample_size": u.effective_sample_size,
                "p_steady": u.p_steady,
                "p_unsteady": u.p_unsteady,
                "p_unsteady_ci_lo": u.p_unsteady_ci[0],
                "p_unsteady_ci_hi": u.p_unsteady_ci[1],
                "p_unsteady_fit": u.p_unsteady_fit,
                "empirical_exceedance": u.empirical_exceedance,
                "tail_consistent": u.tail_consistent,
                "n_contacts": u.n_contacts,
                "n_failed_episodes": u.n_failed_episodes,
                "episode_failure_rate": u.episode_failure_rate,
            }
            rows.append({k: json_value(v) for k, v in row.items()})
        return rows


@dataclass(frozen=True)
class EpisodeSignal:
    """Gap excursions of one episode.

    Attributes:
        signal: array ``(T, n_units)`` of gap excursions [m] sampled every ``dt_s``.
        terminated_in_contact: the episode ended because a magnet touched.
        contact_units: names (or column indices) of the unit(s) that touched.  If None and the
            episode terminated in contact, the contact is attributed to the units whose last
            sample has ``|s| >= Omega``, else to the unit(s) with the largest ``|s|`` in the last
            sample (all units for an empty signal).
    """

    signal: ArrayLike
    terminated_in_contact: bool = False
    contact_units: tuple[str | int, ...] | None = None
