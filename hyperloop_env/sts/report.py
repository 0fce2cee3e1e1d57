"""Formatting: probabilities that are never rounded to zero, and the per-unit tables in the
form of the paper's Tables 2–3."""

from __future__ import annotations

import math

from scipy import stats

from hyperloop_env.sts.results import (
    STSReport,
    UnitSTS,
)


def format_probability(p: float, *, complement_of: float | None = None) -> str:
    """Format a probability for tables without ever rounding small values to zero.

    Values below 1e-3 use scientific notation (``5.1e-07``); exact 0 and 1 print as ``0`` and
    ``1``; NaN prints as ``n/a``.  If ``complement_of`` is given (``p = 1 - complement_of``) and
    that complement is below 1e-3, the value is printed as ``1 - 5.1e-07`` instead of a
    misleading ``1.0000``.
    """
    if p is None or not math.isfinite(p):
        return "n/a"
    if complement_of is not None and math.isfinite(complement_of) and 0.0 < complement_of < 1e-3:
        return f"1 - {complement_of:.1e}"
    if p == 0.0:
        return "0"
    if p == 1.0:
        return "1"
    if p < 1e-3:
        return f"{p:.1e}"
    return f"{p:#.4g}"


def _fmt_p(p: float) -> str:
    if not math.isfinite(p):
        return "n/a"
    if p == 0.0:
        return "0"
    return f"{p:.1e}" if p < 1e-3 else f"{p:.3g}"


def _law_label(u: UnitSTS) -> str:
    if u.distribution in ("none", "degenerate"):
        return u.distribution
    shapes = getattr(stats, u.distribution).shapes
    if not shapes:
        return u.distribution
    names = [s.strip() for s in shapes.split(",")]
    vals = ", ".join(f"{k}={v:.3g}" for k, v in zip(names, u.distribution_params, strict=False))
    return f"{u.distribution}({vals})"


def _p_unsteady_cell(u: UnitSTS) -> str:
    cell = format_probability(u.p_unsteady)
    if u.episode_failure_rate > 0.0 and math.isfinite(u.p_unsteady_fit):
        cell += f" (fit {format_probability(u.p_unsteady_fit)})"
    if u.tail_consistent is False:
        cell += " \u2020"
    return cell


def paper_table_markdown(report: STSReport, title: str = "") -> str:
    """Markdown table in the form of the paper's Tables 2-3, one row per unit.

    Small probabilities are printed in scientific notation (never rounded to 0.0000) and
    ``P(steady)`` close to one as ``1 - 5.1e-07``.
    """
    lines = []
    if title:
        lines += [f"**{title}**", ""]
    lines += [
        "| Unit | mean [mm] | std [mm] | distribution | KS p (accepted?) | P(steady) "
        "| P(unsteady) | 95 % CI | empirical exceedance | contacts |",
        "|---|---:|---:|---|---|---:|---:|---|---:|---:|",
    ]
    for u in report.units:
        mean = f"{u.mean_m * 1e3:.4f}" if math.isfinite(u.mean_m) else "n/a"
        std = f"{u.std_m * 1e3:.4f}" if math.isfinite(u.std_m) else "n/a"
        if math.isfinite(u.ks_pvalue):
            ks = f"{_fmt_p(u.ks_pvalue)} ({'yes' if u.ks_accepted else 'no'})"
            ks += f"; thinned {_fmt_p(u.thinned_ks_pvalue)}"
        else:
            ks = "n/a"
        ci = f"[{format_probability(u.p_unsteady_ci[0])}, {format_probability(u.p_unsteady_ci[1])}]"
        lines.append(
            f"| {u.name} | {mean} | {std} | {_law_label(u)} | {ks} "
            f"| {format_probability(u.p_steady, complement_of=u.p_unsteady)} "
            f"| {_p_unsteady_cell(u)} | {ci} "
            f"| {format_probability(u.empirical_exceedance)} | {u.n_contacts} |"
        )
    lines += [
        "",
        f"Clearance {report.clearance_m * 1e3:g} mm, settling {report.settle_s:g} s, "
        f"alpha {report.alpha:g}; {report.n_episodes} episode(s), "
        f"{report.n_failed_episodes} terminated in contact (failure rate "
        f"{format_probability(report.episode_failure_rate)}, 95 % CI "
        f"[{format_probability(report.episode_failure_rate_ci[0])}, "
        f"{format_probability(report.episode_failure_rate_ci[1])}]).",
        "KS p-values use parameters fitted on the same data (conservative, Lilliefors); the "
        "raw test assumes independent samples, the thinned one uses every round(tau)-th sample. "
        "P(unsteady) = f + (1 - f) * P_fit with f the episode failure rate (P_fit shown as "
        "'fit' when f > 0).",
    ]
    if any(u.tail_consistent is False for u in report.units):
        lines.append(
            "\u2020 The fitted law's tail contradicts the empirical exceedance (disjoint 95 % "
            "intervals): its P(unsteady) extrapolation is unreliable for this unit."
        )
    return "\n".join(lines) + "\n"
