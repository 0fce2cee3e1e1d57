"""Writing an evaluation: Markdown report, JSON, CSV (summary and per unit); tables by
:mod:`agents.evaluation.render`, figures by :mod:`agents.evaluation.figures`. Every file is
written atomically (:mod:`agents.evaluation.outputs`): an interrupted write leaves the old
file or none, never a truncated one."""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path
from typing import Any

from agents.evaluation.figures import plot_comparison as plot_comparison  # its old home
from agents.evaluation.outputs import atomic_write_text
from agents.evaluation.render import fixed, probability, table
from hyperloop_env.json_values import json_value
from hyperloop_env.physics.units import UNIT_NAMES

SUMMARY_HEADER = (
    "controller",
    "condition",
    "worst P(unsteady) gap s",
    "worst P(unsteady) guidance z",
    "RMS gap [mm]",
    "max abs gap [mm]",
    "contact episodes",
    "first contact [s] (kind)",
    "mean / max abs z [mm]",
    "a_wz W_k [m/s²]",
    "a_wy W_d [m/s²]",
    "comfort (ISO 2631-1)",
    "RMS ΔI lev. / guid. [A]",
)
"""The columns of the summary table (evaluate's report and the README's baselines)."""


def summary_table(results: list[dict[str, Any]]) -> str:
    """Markdown table: one row per controller × condition."""
    rows = []
    for r in results:
        m = r["metrics"]
        tc = m["time_to_first_contact_s"]
        tcs = "none" if tc is None else f"{fixed(tc)} ({m['contact_kind']})"
        rows.append(
            (
                m["controller"],
                m["condition"],
                probability(m["p_unsteady"]),
                probability(m.get("p_unsteady_guidance", math.nan)),
                fixed(m["rms_gap_mm"]),
                fixed(m["max_abs_gap_mm"]),
                f"{m['n_contact_episodes']}/{m['n_episodes']}",
                tcs,
                f"{fixed(m['mean_lateral_mm'])} / {fixed(m['max_abs_lateral_mm'])}",
                fixed(m["a_wz_m_s2"]),
                fixed(m["a_wy_m_s2"]),
                m["comfort"],
                f"{fixed(m['rms_current_dev_A'], 2)} / "
                f"{fixed(m.get('rms_guidance_current_A', math.nan), 2)}",
            )
        )
    return table(SUMMARY_HEADER, rows, "llrrrrrlrrrlr")


def _by_controller(results: list[dict[str, Any]]) -> dict[str, list[dict[str, Any]]]:
    by: dict[str, list[dict[str, Any]]] = {}
    for r in results:
        by.setdefault(r["metrics"]["controller"], []).append(r["metrics"])
    return by


def verdict(results: list[dict[str, Any]], distance_km: float, n_seeds: int) -> str:
    """What an evaluation found, in a few lines: which controller held the gap best (mean
    RMS gap excursion over the scenarios, contacts first), the numbers of every controller,
    and what ``n_seeds`` seeds × ``distance_km`` km per scenario can and cannot resolve."""
    rows = []
    for name, ms in _by_controller(results).items():
        rms = [m["rms_gap_mm"] for m in ms if math.isfinite(m.get("rms_gap_mm", math.nan))]
        contacts = sum(int(m["n_contact_episodes"]) for m in ms)
        runs = sum(int(m["n_episodes"]) for m in ms)
        mean = sum(rms) / len(rms) if rms else math.inf
        rows.append((contacts, mean, name, runs, len(ms)))
    rows.sort()
    if not rows:
        return "No results."
    best = rows[0]
    parts = [
        f"{name} {mean:.3f} mm" + (f" ({c}/{n} runs touched)" if c else "")
        for c, mean, name, n, _ in rows
    ]
    lines = [
        f"Verdict: {best[2]} held the gap best — mean RMS gap excursion over the "
        f"{best[4]} scenarios " + "; ".join(parts) + ".",
    ]
    total_contacts = sum(r[0] for r in rows)
    lines.append(
        "Contacts: none."
        if total_contacts == 0
        else f"Contacts: {total_contacts} of {sum(r[3] for r in rows)} runs touched "
        "(a touch ends the run; its RMS covers the flown part only)."
    )
    lines.append(
        f"What this can resolve: {n_seeds} seed(s) × {distance_km:g} km per scenario rank "
        "the controllers' RMS gap on these tracks; it cannot estimate the seed-to-seed "
        "spread" + (" (one seed)" if n_seeds < 2 else "") + ", how much disturbance a "
        "controller takes before it touches, or P(contact) (the fitted P(unsteady) tails "
        "far below 1e-6 are extrapolations). To decide between controllers: "
        "`hyperloop capacity` (per-seed capacities on 32 common seeds, paired "
        "verdicts)."
    )
    return "\n".join(lines)


_SUMMARY_CSV_KEYS: tuple[str, ...] = (
    "controller",
    "condition",
    "magnet",
    "speed_kmh",
    "curve_radius_m",
    "n_episodes",
    "p_unsteady",
    "unit",
    "p_unsteady_guidance",
    "unit_guidance",
    "rms_gap_mm",
    "max_abs_gap_mm",
    "rms_lateral_mm",
    "n_contact_episodes",
    "time_to_first_contact_s",
    "position_of_first_contact_m",
    "contact_kind",
    "mean_lateral_mm",
    "max_abs_lateral_mm",
    "a_wz_m_s2",
    "a_wy_m_s2",
    "a_v_m_s2",
    "comfort",
    "rms_current_dev_A",
    "rms_guidance_current_A",
    "steps_total",
    "wall_s",
)
"""The columns of summary.csv (metrics of one controller × condition per row)."""


def _header_lines(settings: dict[str, Any], title: str) -> list[str]:
    """The report's title, command, settings and the definitions of its quantities."""
    md = [f"# {title}", ""]
    md += [f"Command: `{settings.get('command', '')}`", ""]
    md += [
        f"Magnet: **{settings['magnet']}**; distance {settings['distance_km']} km per episode; "
        f"seeds {settings['seeds']}; settling {settings['settle_s']} s discarded before the "
        f"fits; clearance Ω = {settings['clearance_m'] * 1e3:g} mm; "
        f"control interval {settings.get('dt_s', 1e-3)} s; "
        f"wall time {settings.get('wall_s', float('nan')):.1f} s.",
        "",
        "RMS gap = RMS of the gap excursion over all units and post-settling samples; "
        "comfort = ISO 2631-1 frequency-weighted RMS capsule acceleration (W_k vertical, W_d "
        "lateral; a_v = sqrt((1.4 a_wy)² + a_wz²) labels the comfort reaction); RMS ΔI = RMS "
        "coil-current deviation from I0. An episode that ends in contact is kept: its "
        "P(unsteady) is 1 (contact is absorbing) and its time of contact is listed.",
        "",
    ]
    return md


def _contact_lines(results: list[dict[str, Any]]) -> list[str]:
    """The "Contacts" section: one line per case with a contact (none if no case had one)."""
    failed = [r for r in results if r["metrics"]["n_contact_episodes"]]
    if not failed:
        return []
    md = ["### Contacts", ""]
    for r in failed:
        m = r["metrics"]
        times = ", ".join(f"{t:.3f} s" for t in m["contact_times_s"])
        md.append(
            f"- **{m['controller']} / {m['condition']}** ({m['magnet']}): "
            f"{m['n_contact_episodes']} of {m['n_episodes']} episode(s) ended in "
            f"{m['contact_kind']} contact (at {times}; first at x = "
            f"{fixed(m['position_of_first_contact_m'], 1)} m) — P(unsteady) = 1."
        )
    md.append("")
    return md


def _sts_lines(results: list[dict[str, Any]], out: Path) -> list[str]:
    """The STS tables per condition, each case's RMS gap per unit and its figures."""
    scen = list(dict.fromkeys(r["metrics"]["condition"] for r in results))
    md = ["## STS tables (form of the paper's Tables 2–3)", ""]
    for sc in scen:
        md += [f"### {sc}", ""]
        for r in results:
            if r["metrics"]["condition"] != sc:
                continue
            m = r["metrics"]
            for key in ("table_md", "table_md_guidance"):
                if key in r:
                    md.append(
                        r[key].replace("**", f"**{m['controller']}: ", 1)
                        if r[key].startswith("**")
                        else r[key]
                    )
            md.append(
                "RMS gap per unit [mm]: "
                + ", ".join(
                    f"{n} {fixed(v)}"
                    for n, v in zip(UNIT_NAMES, m["rms_gap_units_mm"], strict=True)
                )
                + "."
            )
            for f in r.get("figures", []):
                md.append(f"![{Path(f).name}]({Path(f).relative_to(out).as_posix()})")
            md.append("")
    return md


def _results_json(results: list[dict[str, Any]], out: Path, settings: dict[str, Any]) -> str:
    """results.json: the settings and, per case, its metrics, STS reports and figures."""
    payload = {
        "settings": settings,
        "results": [
            {
                "metrics": r["metrics"],
                "sts": r["report"].to_dict(),
                "sts_guidance": r["report_guidance"].to_dict() if "report_guidance" in r else None,
                "figures": [Path(f).relative_to(out).as_posix() for f in r.get("figures", [])],
            }
            for r in results
        ],
    }
    return json.dumps(json_value(payload), indent=1) + "\n"


def _summary_csv(results: list[dict[str, Any]]) -> str:
    """summary.csv: the :data:`_SUMMARY_CSV_KEYS` metrics of every case."""
    keys = list(_SUMMARY_CSV_KEYS)
    fh = io.StringIO(newline="")
    w = csv.DictWriter(fh, fieldnames=keys)
    w.writeheader()
    for r in results:
        w.writerow({k: json_value(r["metrics"].get(k)) for k in keys})
    return fh.getvalue()


def _units_csv(results: list[dict[str, Any]]) -> str:
    """sts_units.csv: one row per case × signal (levitation, guidance gap) × unit."""
    rows = []
    for r in results:
        for signal, key in (("levitation_gap", "report"), ("guidance_gap", "report_guidance")):
            if key not in r:
                continue
            for row in r[key].to_rows():
                rows.append(
                    {
                        "controller": r["metrics"]["controller"],
                        "condition": r["metrics"]["condition"],
                        "magnet": r["metrics"]["magnet"],
                        "signal": signal,
                        **row,
                    }
                )
    fh = io.StringIO(newline="")
    if rows:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return fh.getvalue()


def write_outputs(
    results: list[dict[str, Any]], out: Path, settings: dict[str, Any], title: str
) -> dict[str, Path]:
    """report.md, results.json, summary.csv, sts_units.csv into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    md = _header_lines(settings, title)
    md += ["## Summary", "", summary_table(results)]
    md += _contact_lines(results)
    md += _sts_lines(results, out)
    paths = {"md": out / "report.md", "json": out / "results.json"}
    atomic_write_text(paths["md"], "\n".join(md) + "\n")
    atomic_write_text(paths["json"], _results_json(results, out, settings))
    paths["csv"] = out / "summary.csv"
    atomic_write_text(paths["csv"], _summary_csv(results))
    paths["units_csv"] = out / "sts_units.csv"
    atomic_write_text(paths["units_csv"], _units_csv(results))
    return paths
