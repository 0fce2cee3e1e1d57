"""A fragility sweep's report: its JSON (:func:`to_json`), the level and fit tables as CSV
and Markdown (:func:`markdown`) and the files of its output folder (:func:`write_outputs`)
— rendered from the results :func:`agents.evaluation.fragility.fragility` computes."""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from agents.evaluation.figures import plot_fragility
from agents.evaluation.fragility_fit import (
    FragilityFit,
)
from agents.evaluation.outputs import (
    atomic_write_text,
)
from agents.evaluation.render import fixed, interval, probability, table_lines
from hyperloop_env.json_values import json_value

OWNED = ("report.md", "results.json", "fragility_levels.csv", "fragility_fits.csv", "figures")
DEFAULT_MAX_SAMPLES = 100_000
DEFAULT_BLOCK_SIZE = 16
DEFAULT_MAX_BLOCK_MB = 2048.0
PROFILE_BYTES_PER_POINT = 64
"""Memory per guideway-profile grid point and run held by the environment (the
simulator's precomputed (3, n) profile and the transient arrays that generate it; measured
with ``speed/bench_fragility.py --part memory``: one 1000 km run, n = 2^24 points,
peak RSS 1257 MB against 216 MB for 1 km, i.e. about 65 B per point). The profile grows
with the distance (0.1 m grid, rounded up to a power of two), so blocks of long runs are
made smaller to keep a block under ``max_block_mb``."""


def to_json(res: dict[str, Any]) -> dict[str, Any]:
    return json_value({k: v for k, v in res.items() if k != "paths"})


def deterministic_view(res: dict[str, Any]) -> dict[str, Any]:
    """The results without wall times and run settings that may differ between equivalent
    runs (backend, workers): what must be bit-identical for the same seeds."""
    d = to_json(res)
    for k in ("wall_s", "backend", "workers", "command"):
        d["settings"].pop(k, None)
    for r in d["levels"]:
        r.pop("wall_s", None)
    return d


LEVEL_COLUMNS = (
    "controller",
    "condition",
    "level",
    "n_runs",
    "n_contacts",
    "p_contact",
    "p_contact_lo",
    "p_contact_hi",
    "distance_km",
    "contact_rate_per_100km",
    "contact_rate_lo",
    "contact_rate_hi",
    "p_unsteady",
    "p_unsteady_lo",
    "p_unsteady_hi",
    "p_unsteady_fit",
    "p_unsteady_fit_lo",
    "p_unsteady_fit_hi",
    "p_unsteady_guidance",
    "empirical_exceedance",
    "exceedance_any_unit_exact",
    "rms_gap_mm",
    "max_abs_gap_mm",
    "a_wz_m_s2",
    "a_wy_m_s2",
    "a_v_m_s2",
    "comfort",
    "thin_stride",
    "steps",
)


FIT_COLUMNS = (
    "controller",
    "condition",
    "status",
    "theta",
    "theta_lo",
    "theta_hi",
    "beta",
    "beta_lo",
    "beta_hi",
    "n_boot",
    "n_boot_fit",
    "n_degenerate",
    "n_excluded",
    "summary",
)


def level_rows(res: dict[str, Any]) -> list[dict[str, Any]]:
    out = []
    for r in res["levels"]:
        row = {k: r.get(k) for k in LEVEL_COLUMNS}
        row["p_contact_lo"], row["p_contact_hi"] = r["p_contact_ci"]
        row["contact_rate_lo"], row["contact_rate_hi"] = r["contact_rate_per_100km_ci"]
        row["p_unsteady_lo"], row["p_unsteady_hi"] = r["p_unsteady_ci"]
        row["p_unsteady_fit_lo"], row["p_unsteady_fit_hi"] = r["p_unsteady_fit_ci"]
        out.append(json_value(row))
    return out


def fit_rows(res: dict[str, Any]) -> list[dict[str, Any]]:
    out = []
    for f in res["fits"]:
        ft: FragilityFit = f["fit"]
        out.append(
            json_value(
                {
                    "controller": f["controller"],
                    "condition": f["condition"],
                    "status": ft.status,
                    "theta": ft.theta,
                    "theta_lo": ft.theta_ci[0],
                    "theta_hi": ft.theta_ci[1],
                    "beta": ft.beta,
                    "beta_lo": ft.beta_ci[0],
                    "beta_hi": ft.beta_ci[1],
                    "n_boot": ft.n_boot,
                    "n_boot_fit": ft.n_boot_fit,
                    "n_degenerate": ft.n_degenerate,
                    "n_excluded": ft.n_excluded,
                    "summary": f["summary"],
                }
            )
        )
    return out


def _csv(rows: list[dict[str, Any]], columns: Sequence[str]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(columns), lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in columns})
    return buf.getvalue()


LEVEL_TABLE_HEADER = (
    "controller",
    "condition",
    "level",
    "contacts",
    "P(contact) [95 %]",
    "per 100 km [95 %]",
    "P(unsteady) [95 %]",
    "P_fit",
    "emp. exceed. (STS / exact)",
    "RMS gap [mm]",
    "max gap [mm]",
    "a_v [m/s²]",
    "comfort",
)
"""The columns of the report's per-level table."""


def _level_cells(r: dict[str, Any]) -> tuple[Any, ...]:
    """The cells of one level row of the report's per-level table."""
    lo, hi = r["p_contact_ci"]
    rl, rh = r["contact_rate_per_100km_ci"]
    ul, uh = r["p_unsteady_ci"]
    return (
        r["controller"],
        r["condition"],
        f"{r['level']:g}",
        f"{r['n_contacts']}/{r['n_runs']}",
        f"{r['p_contact']:.3f} [{lo:.3f}, {hi:.3f}]",
        f"{fixed(r['contact_rate_per_100km'], 2)} {interval(rl, rh, lambda v: fixed(v, 2))}",
        f"{probability(r['p_unsteady'])} {interval(ul, uh, probability)}",
        probability(r["p_unsteady_fit"]),
        f"{probability(r['empirical_exceedance'])} / {probability(r['exceedance_any_unit_exact'])}",
        fixed(r["rms_gap_mm"]),
        fixed(r["max_abs_gap_mm"]),
        fixed(r["a_v_m_s2"]),
        r["comfort"],
    )


def markdown(res: dict[str, Any], figure_paths: dict[str, str] | None = None) -> str:
    s = res["settings"]
    lines = [
        f"# Fragility: {s['family']} ({s['severity_unit']})",
        "",
        f"`{s['command']}`",
        "",
        f"Controllers {', '.join(s['controllers'])}; conditions {', '.join(s['conditions'])}; "
        f"levels {', '.join(f'{x:g}' for x in s['levels'])}; {len(s['seeds'])} seeds × "
        f"{s['distance_km']:g} km per level; magnet {s['magnet']}; settle {s['settle_s']:g} s; "
        f"fixed disturbances {s['fixed_disturbances'] or 'none'}; wall time "
        f"{s['wall_s']:.1f} s ({s['backend']} backend, {s['workers']} worker(s)).",
        "",
        "## Fragility functions: P(contact | s) = Φ(ln(s/θ)/β)",
        "",
        "Maximum-likelihood fit to the binary run outcomes (Baker 2015); 95 % percentile "
        "intervals from a bootstrap of the runs within levels. Degenerate data are reported "
        "as bounds.",
        "",
        *table_lines(
            ("controller", "condition", "result"),
            ((f["controller"], f["condition"], f["summary"]) for f in res["fits"]),
        ),
        "",
        "## Per level",
        "",
        f"Contact probability per run with its {'Clopper–Pearson' if s['interval'] == 'exact' else 'Wilson'} "  # noqa: E501
        "95 % interval; contact rate per 100 km flown (Garwood exact interval); the paper's "
        "P(unsteady) of the worst unit (fitted law incl. contacts, block-bootstrap interval) "
        "with the empirical exceedance of the STS sample and, exactly, of every sample "
        "(any unit beyond Ω after settling); RMS / max gap after settling; ISO 2631-1 "
        "vibration total value a_v and comfort.",
        "",
        *table_lines(LEVEL_TABLE_HEADER, map(_level_cells, res["levels"]), "llrrlllllrrrl"),
    ]
    lines += [
        "",
        "Long runs are streamed: the STS fit uses every k-th sample (k = `thin_stride` in "
        f"the CSV/JSON; {s['memory_bound']}); counts, moments and comfort use every sample.",
    ]
    if figure_paths:
        lines += ["", "## Figures", ""]
        for cond, p in figure_paths.items():
            lines.append(f"![{cond}]({Path(p).relative_to(Path(p).parents[1])})")
    return "\n".join(lines) + "\n"


def write_outputs(res: dict[str, Any], out: Path, figures: bool = True) -> dict[str, str]:
    paths: dict[str, str] = {}
    figs: dict[str, str] = {}
    if figures:
        (out / "figures").mkdir(parents=True, exist_ok=True)
        for cond in res["settings"]["conditions"]:
            p = out / "figures" / f"fragility_{cond}.png"
            plot_fragility(res, cond, p)
            figs[cond] = str(p)
            paths[f"figure_{cond}"] = str(p)
    atomic_write_text(out / "results.json", json.dumps(to_json(res), indent=1) + "\n")
    atomic_write_text(out / "fragility_levels.csv", _csv(level_rows(res), LEVEL_COLUMNS))
    atomic_write_text(out / "fragility_fits.csv", _csv(fit_rows(res), FIT_COLUMNS))
    atomic_write_text(out / "report.md", markdown(res, figs))
    for name in ("report.md", "results.json", "fragility_levels.csv", "fragility_fits.csv"):
        paths[name.split(".")[0]] = str(out / name)
    return paths
