"""The one vocabulary of the evaluation outputs: every key and column name that evaluate,
reproduce_paper, fragility, benchmark and capacity write (JSON records, CSV columns), with
its unit and meaning. One quantity has one name in every output:

* ``p_unsteady`` — the paper's P(unsteady) of the levitation gap s: the worst unit's in a
  summary record (a case, a level, a severity), the named unit's in a per-unit row;
  ``p_unsteady_guidance`` the same of the guidance gap z; ``unit`` / ``unit_guidance``
  the unit it belongs to (formerly ``worst_p_unsteady``, ``worst_unit``,
  ``p_unsteady_unit``, ``p_unsteady_gap``, … — :data:`ALIASES`).
* ``condition`` — the operating condition a result was flown on, written as the name of
  the environment scenario that sets it (``paper-1000-straight``, …). Chosen over
  ``scenario`` because it names what the column holds in every output: the condition the
  controller is judged at (speed, curve, track), which the fragility, benchmark and
  capacity outputs, their ``--conditions`` flags, the published headline (JSON, CSV,
  README) and the paper (its four operating conditions) all call a condition. The
  environment keyword ``scenario`` keeps its name: it is an input (which preset builds
  the configuration), not an output column; evaluate's ``--scenarios`` flag takes those
  inputs.

Readers of files written before a rename go through :func:`canonical`, which maps the
old keys (:data:`ALIASES`) to the declared ones. Names containing ``{family}`` are
templates (one column per disturbance family). The nested STS reports (``sts``,
``sts_guidance``: :meth:`hyperloop_env.sts.STSReport.to_dict`) and fit dicts (``fit``,
``binary_fit``, ``ecdf``) are the environment's and the statistics modules' own records,
declared here as one key each."""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Term:
    """One output name: its unit ("" dimensionless or not a number; "—" a record) and
    meaning."""

    unit: str
    meaning: str


_P = "probability"
_REC = "—"

VOCABULARY: dict[str, Term] = {
    # --- what a record is about
    "controller": Term("", "controller name (registry name, entry point or checkpoint)"),
    "entrant": Term("", "benchmark entrant: controller name, `+g` when its guidance loops act"),
    "actuators": Term("", "actuated coils: levitation or levitation+guidance"),
    "condition": Term("", "operating condition, as the environment scenario that sets it"),
    "magnet": Term("", "magnet arrangement: repelling or attracting"),
    "family": Term("", "disturbance family whose severity is scaled"),
    "level": Term("family's severity unit", "severity level of a fragility sweep"),
    "severity": Term("family's severity unit", "severity of a disturbance family"),
    "reference_level": Term("roughness severity", "roughness level of the P(unsteady) columns"),
    "speed_kmh": Term("km/h", "vehicle speed"),
    "curve_radius_m": Term("m", "guideway curve radius (inf: straight)"),
    "radius_m": Term("m", "curve radius of a sweep run"),
    "a_lat_m_s2": Term("m/s²", "quasi-static lateral demand v²/R (no cant)"),
    "signal": Term("", "STS signal of a per-unit row: levitation_gap or guidance_gap"),
    "seed": Term("", "seed of one run (fixes the guideway realisation)"),
    "seeds": Term("", "seeds of the runs, in order"),
    # --- runs and contacts
    "n_episodes": Term("", "number of episodes (runs) of an evaluate case or an STS sample"),
    "n_runs": Term("", "number of runs (one per seed) of a level or severity"),
    "runs": Term("", "the runs of a capacity search (list), or their number per entrant"),
    "n_contact_episodes": Term("", "episodes of an evaluate case that ended in contact"),
    "safety_cost_episodes": Term(
        "", "summed safety cost (info['cost'], indicator, 2 mm margin) of each episode"
    ),
    "safety_cost_mean": Term("", "mean over the episodes of their summed safety cost"),
    "n_contacts": Term("", "runs that ended in contact (per unit in an STS row: its contacts)"),
    "contact": Term("", "the run ended in contact (bool)"),
    "contact_kind": Term("", "kind of the first contact: gap, lateral or gap+lateral"),
    "kind": Term("", "contact kind of a capacity run, or kind of a capacity interval"),
    "contact_kinds": Term("", "number of contacts per kind"),
    "contact_times_s": Term("s", "time of contact of each episode that touched"),
    "time_to_first_contact_s": Term("s", "earliest time of contact over the episodes"),
    "position_of_first_contact_m": Term("m", "track position of the earliest contact"),
    "first_contact_position_m": Term("m", "smallest track position of a contact"),
    "contact_positions_m": Term("m", "track position of each contact"),
    "time_to_contact_s": Term("s", "time of contact of one run (None: flew)"),
    "position_of_contact_m": Term("m", "track position of the contact of one run"),
    "time_s": Term("s", "time of the first contact of a capacity run, or its end"),
    "phase": Term("", "phase of a capacity search that flew the run"),
    "p_contact": Term(_P, "P(contact) per run (per severity: a list of estimates)"),
    "p_contact_ci": Term(_P, "95 % interval of p_contact"),
    "p_contact_lo": Term(_P, "low end of p_contact_ci"),
    "p_contact_hi": Term(_P, "high end of p_contact_ci"),
    "interval": Term("", "binomial interval of p_contact: exact (Clopper–Pearson) or wilson"),
    "empirical": Term(_P, "P(contact | severity) from the empirical capacity distribution"),
    "lognormal": Term(_P, "P(contact | severity) from the lognormal capacity fit"),
    "contact_rate_per_100km": Term("1/(100 km)", "contacts per 100 km flown"),
    "contact_rate_per_100km_ci": Term("1/(100 km)", "Garwood 95 % interval of the rate"),
    "contact_rate_lo": Term("1/(100 km)", "low end of contact_rate_per_100km_ci"),
    "contact_rate_hi": Term("1/(100 km)", "high end of contact_rate_per_100km_ci"),
    "distance_km": Term("km", "distance flown by the runs"),
    "distance_km_mean": Term("km", "mean distance flown per episode"),
    # --- the paper's STS
    "p_unsteady": Term(
        _P, "P(unsteady) of the levitation gap s (worst unit; per-unit row: the unit's)"
    ),
    "unit": Term("", "the unit p_unsteady belongs to (FL, FR, RL, RR)"),
    "p_unsteady_ci": Term(_P, "block-bootstrap 95 % interval of p_unsteady"),
    "p_unsteady_lo": Term(_P, "low end of p_unsteady_ci"),
    "p_unsteady_hi": Term(_P, "high end of p_unsteady_ci"),
    "p_unsteady_ci_lo": Term(_P, "low end of p_unsteady_ci (per-unit row)"),
    "p_unsteady_ci_hi": Term(_P, "high end of p_unsteady_ci (per-unit row)"),
    "p_unsteady_fit": Term(_P, "P(unsteady) of the fitted law alone (without contacts)"),
    "p_unsteady_fit_ci": Term(_P, "95 % interval of p_unsteady_fit"),
    "p_unsteady_fit_lo": Term(_P, "low end of p_unsteady_fit_ci"),
    "p_unsteady_fit_hi": Term(_P, "high end of p_unsteady_fit_ci"),
    "p_unsteady_units": Term(_P, "p_unsteady of each unit (FL, FR, RL, RR)"),
    "p_unsteady_guidance": Term(_P, "P(unsteady) of the guidance gap z (worst unit)"),
    "unit_guidance": Term("", "the unit p_unsteady_guidance belongs to"),
    "p_unsteady_guidance_ci": Term(_P, "block-bootstrap 95 % interval of p_unsteady_guidance"),
    "p_unsteady_units_guidance": Term(_P, "p_unsteady_guidance of each unit"),
    "p_steady": Term(_P, "1 − p_unsteady (per-unit row)"),
    "distribution": Term("", "law fitted to the excursions (KS test at α = 0.05)"),
    "empirical_exceedance": Term(_P, "fraction of STS samples beyond the clearance"),
    "empirical_exceedance_ci": Term(_P, "95 % interval of empirical_exceedance"),
    "exceedance_any_unit_exact": Term(_P, "fraction of all samples with any unit beyond Ω"),
    "exceedance_levels_mm": Term("mm", "excursion levels of the exceedance counts"),
    "exceedance_counts_any_unit": Term("", "samples with any unit beyond each level"),
    "exceedance_counts_units": Term("", "samples beyond each level, per unit"),
    "n_samples": Term("", "samples of a unit's STS fit"),
    "n_samples_after_settle": Term("", "samples after the settling time, per unit"),
    "n_thinned_samples": Term("", "thinned samples of the STS fit, per signal"),
    "thin_stride": Term("", "every k-th sample enters the STS fit of a streamed run"),
    "mean_mm": Term("mm", "mean excursion of a unit"),
    "std_mm": Term("mm", "standard deviation of a unit's excursion"),
    "ks_statistic": Term("", "Kolmogorov–Smirnov statistic of the fitted law"),
    "ks_pvalue": Term("", "KS p-value of the fitted law"),
    "ks_accepted": Term("", "the fitted law passes the KS test (α = 0.05)"),
    "thinned_ks_pvalue": Term("", "KS p-value on the decorrelated (thinned) sample"),
    "normal_ks_pvalue": Term("", "KS p-value of a normal law"),
    "effective_sample_size": Term("", "sample size corrected for autocorrelation"),
    "tail_consistent": Term("", "fitted tail consistent with the empirical exceedance"),
    "n_failed_episodes": Term("", "episodes in which the unit touched"),
    "episode_failure_rate": Term(_P, "fraction of episodes in which the unit touched"),
    "sts": Term(_REC, "STS report of the levitation gap (STSReport.to_dict)"),
    "sts_guidance": Term(_REC, "STS report of the guidance gap (STSReport.to_dict)"),
    "gap": Term(_REC, "STS summary of the levitation gap at one severity"),
    "guidance": Term(_REC, "STS summary of the guidance gap at one severity"),
    "sts_at_start": Term(_REC, "STS at the family's start severity (older headline files)"),
    "sts_at_levels": Term(_REC, "STS at each of the suite's levels"),
    # --- gap, guidance, currents, comfort
    "rms_gap_mm": Term("mm", "RMS gap excursion over units and post-settling samples"),
    "rms_gap_units_mm": Term("mm", "RMS gap excursion per unit"),
    "std_gap_units_mm": Term("mm", "standard deviation of the gap excursion per unit"),
    "max_abs_gap_mm": Term("mm", "largest |gap excursion|"),
    "mean_lateral_mm": Term("mm", "mean guidance gap excursion z"),
    "max_abs_lateral_mm": Term("mm", "largest |guidance gap excursion z|"),
    "rms_lateral_mm": Term("mm", "RMS guidance gap excursion z"),
    "rms_current_dev_A": Term("A", "RMS levitation coil-current deviation from I0"),
    "rms_guidance_current_A": Term("A", "RMS guidance differential current"),
    "a_wz_m_s2": Term("m/s²", "ISO 2631-1 W_k-weighted RMS vertical acceleration"),
    "a_wy_m_s2": Term("m/s²", "ISO 2631-1 W_d-weighted RMS lateral acceleration"),
    "a_v_m_s2": Term("m/s²", "ISO 2631-1 vibration total value sqrt((1.4 a_wy)² + a_wz²)"),
    "comfort": Term("", "ISO 2631-1 comfort reaction of a_v"),
    # --- cost of a run
    "steps": Term("", "control steps simulated"),
    "steps_total": Term("", "control steps simulated over the episodes of a case"),
    "wall_s": Term("s", "wall-clock time"),
    "batched": Term("", "the runs used the batched (vector) environment"),
    # --- fragility fits and capacities
    "fit": Term(_REC, "lognormal fit (FragilityFit.to_dict or capacity_stats fit)"),
    "binary_fit": Term(_REC, "binary-outcome fragility fit on the same seeds (cross-check)"),
    "ecdf": Term(_REC, "empirical capacity distribution with its confidence band"),
    "summary": Term("", "one-line text of a fragility fit"),
    "status": Term("", "fit status: fit, no_contact, all_contact, separated, …"),
    "theta": Term("severity unit", "median capacity θ (severity at which half touch)"),
    "theta_ci": Term("severity unit", "95 % bootstrap interval of theta"),
    "theta_lo": Term("severity unit", "low end of theta's interval"),
    "theta_hi": Term("severity unit", "high end of theta's interval"),
    "beta": Term("", "lognormal dispersion β of the capacities"),
    "beta_ci": Term("", "95 % bootstrap interval of beta"),
    "beta_lo": Term("", "low end of beta_ci"),
    "beta_hi": Term("", "high end of beta_ci"),
    "n_boot": Term("", "bootstrap resamples"),
    "n_boot_fit": Term("", "bootstrap resamples with a finite fit"),
    "n_degenerate": Term("", "degenerate bootstrap resamples"),
    "n_excluded": Term("", "runs excluded from the fit"),
    "capacity": Term(
        "severity unit",
        "per-seed capacity (smallest touching severity); per "
        "benchmark entrant the capacity estimate per family",
    ),
    "lo": Term("", "low end of an interval (capacity or ratio)"),
    "hi": Term("", "high end of an interval (capacity or ratio)"),
    "bracket": Term("severity unit", "(largest flying, smallest touching) severity"),
    "censored": Term("", "right (flies at the upper bound), left (touches at the lower)"),
    "left_censored": Term("", "seeds that touch at the lower bound"),
    "n_censored": Term("", "right-censored seeds"),
    "non_monotone": Term(
        "",
        "a higher severity flew after a lower one touched (per entrant: the number of such seeds)",
    ),
    "n": Term("", "seeds of a capacity fit"),
    "median_empirical": Term("severity unit", "median of the empirical capacities"),
    "median_empirical_ci": Term("severity unit", "95 % interval of median_empirical"),
    "binary_theta": Term("severity unit", "θ of the binary-outcome fit (cross-check)"),
    "contact_at_capacity": Term(
        "",
        "seeds per kind of first contact of the run at the capacity (gap, lateral, "
        "gap+lateral; none: right-censored)",
    ),
    "levels": Term("severity unit", "the suite's levels of a family"),
    "entrants": Term(_REC, "per-entrant analysis of a condition × family cell"),
    "verdicts": Term(_REC, "paired verdicts of the entrants"),
    "decided_fraction": Term("", "fraction of the pairs decided"),
    # --- paired verdicts
    "a": Term("", "first entrant of a pair"),
    "b": Term("", "second entrant of a pair"),
    "verdict": Term("", "A above B, B above A, equivalent or undecided"),
    "ratio": Term("", "ratio of median capacities A / B (geometric mean of per-seed ratios)"),
    "p_value": Term("", "Wilcoxon signed-rank p-value of the pair"),
    "reason": Term("", "why the verdict was reached"),
    "pairs": Term("", "number of entrant pairs"),
    "decided": Term("", "pairs decided (above, below or equivalent)"),
    "capacities": Term(_REC, "capacity rows of the headline"),
    "rows": Term(_REC, "headline rows (condition × entrant)"),
    "at_levels": Term(_REC, "per-level numbers of a headline row"),
    # --- reproduce_paper
    "critical_radius_m": Term("m", "smallest radius without contact (bisection)"),
    "bracket_m": Term("m", "final bracket of the critical-radius bisection"),
    "bracket_rel": Term("", "relative width of bracket_m"),
    "evaluations": Term("", "every (radius [m], contact) of the bisection"),
    "note": Term("", "why a bisection has no bracket"),
    # --- per-family CSV columns (templates)
    "theta_{family}": Term("severity unit", "theta of a family"),
    "theta_{family}_lo": Term("severity unit", "low end of theta_{family}'s interval"),
    "theta_{family}_hi": Term("severity unit", "high end of theta_{family}'s interval"),
    "theta_{family}_kind": Term("", "kind of theta_{family}'s interval"),
}
"""Every output name → its unit and meaning."""

ALIASES: dict[str, str] = {
    "worst_p_unsteady": "p_unsteady",
    "worst_unit": "unit",
    "worst_p_unsteady_guidance": "p_unsteady_guidance",
    "worst_unit_guidance": "unit_guidance",
    "p_unsteady_unit": "unit",
    "p_unsteady_guidance_unit": "unit_guidance",
    "p_unsteady_gap": "p_unsteady",
    "p_unsteady_gap_ci": "p_unsteady_ci",
    "scenario": "condition",
}
"""Old output name → declared name (files written before the vocabulary)."""

_TEMPLATES = [
    re.compile("^" + re.escape(k).replace(re.escape("{family}"), "[a-z0-9_]+") + "$")
    for k in VOCABULARY
    if "{family}" in k
]


def declared(name: str) -> bool:
    """True if ``name`` is a declared output name (or fits a template of one)."""
    return name in VOCABULARY or any(t.match(name) for t in _TEMPLATES)


def canonical(record: Mapping[str, Any]) -> dict[str, Any]:
    """``record`` with its old keys (:data:`ALIASES`) renamed to the declared ones (a key
    already present under its declared name wins): how a reader accepts files written
    before a rename. Not recursive."""
    out: dict[str, Any] = {}
    for k, v in record.items():
        new = ALIASES.get(k, k)
        if new != k and new in record:
            continue
        out[new] = v
    return out
