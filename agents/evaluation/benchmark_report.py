"""The benchmark's headline, from its fragility sweeps: per paper condition and entrant the
median capacity θ with its interval (or the bracket of grid levels that holds it), the STS
at the reference level, contact rates and comfort, and whether two entrants are resolved;
rendered as Markdown, CSV and the README table."""

from __future__ import annotations

import csv
import io
import math
from typing import Any

from agents.evaluation.benchmark_blocks import _in, settings_seeds
from agents.evaluation.benchmark_suite import REFERENCE_FAMILY
from agents.evaluation.render import (
    NA,
    fixed,
    interval,
    significant,
    table,
    table_lines,
    with_interval,
)
from agents.evaluation.seeds import SEED_RANGES


def capacity_estimate(fit: Any) -> float:
    """θ of a fit, or the bound a degenerate sweep gives (no contact: the largest level
    × 1.5 — at least that; every level in contact: the smallest ÷ 1.5; separated: the
    geometric middle of its bracket; quasi-separated: its limit). ``fit``: a
    :class:`~agents.evaluation.fragility_fit.FragilityFit` or its ``to_dict()``."""
    if not isinstance(fit, dict):
        fit = fit.to_dict()
    st = fit.get("status")
    b = fit.get("bounds") or {}
    if st == "fit":
        return float(fit["theta"])
    if st == "no_contact":
        return 1.5 * float(b["theta_lower"])
    if st == "all_contact":
        return float(b["theta_upper"]) / 1.5
    if st == "separated":
        return math.sqrt(float(b["theta_lower"]) * float(b["theta_upper"]))
    if st == "quasi_separated":
        return float(b["theta_limit"])
    return math.nan


def capacity_interval(fit: dict[str, Any]) -> tuple[float, float, float, str]:
    """(estimate, low, high, kind) of a fit dict (``FragilityFit.to_dict()``): kind
    ``"bootstrap"`` for a finite MLE, ``"bracket"`` for degenerate data (the grid levels
    around θ), ``"lower bound"`` / ``"upper bound"`` when no or every run touched."""
    st = fit.get("status")
    b = fit.get("bounds") or {}
    levels = sorted(fit.get("levels") or [])
    est = capacity_estimate(fit)
    if st == "fit":
        lo, hi = fit.get("theta_ci") or (math.nan, math.nan)
        return est, _num(lo), _num(hi), "bootstrap"
    if st == "no_contact":
        return est, float(b["theta_lower"]), math.inf, "lower bound"
    if st == "all_contact":
        return est, 0.0, float(b["theta_upper"]), "upper bound"
    if st == "separated":
        return est, float(b["theta_lower"]), float(b["theta_upper"]), "bracket"
    if st == "quasi_separated":
        m = float(b["theta_limit"])
        below = [s for s in levels if s < m]
        above = [s for s in levels if s > m]
        return est, (below[-1] if below else 0.0), (above[0] if above else math.inf), "bracket"
    return est, math.nan, math.nan, str(st)


def _num(x: Any) -> float:
    return math.nan if x is None else float(x)


def _bounds(c: dict[str, Any] | tuple[float, float]) -> tuple[float, float]:
    """(low, high) of a capacity entry; in JSON an infinite bound is null, so a missing
    high of a "lower bound" or a "bracket" is +inf and every other missing value is unknown
    (NaN)."""
    if isinstance(c, tuple | list):
        lo, hi = c
        kind = ""
    else:
        lo, hi, kind = c.get("lo"), c.get("hi"), c.get("kind", "")
    lo = math.nan if lo is None else float(lo)
    # a bracket whose θ limit is the top grid level has no level above it: open upwards
    hi = (math.inf if kind in ("lower bound", "bracket") else math.nan) if hi is None else float(hi)
    return lo, hi


def resolved(
    a: dict[str, Any] | tuple[float, float], b: dict[str, Any] | tuple[float, float]
) -> bool:
    """True when two capacity intervals do not overlap (an unknown bound: unresolved)."""
    (a0, a1), (b0, b1) = _bounds(a), _bounds(b)
    if any(math.isnan(v) for v in (a0, a1, b0, b1)):
        return False
    return a1 < b0 or b1 < a0


def _fmt_cap(c: dict[str, Any]) -> str:
    lo, hi = _bounds(c)
    kind = c["kind"]
    est = math.nan if c["theta"] is None else float(c["theta"])
    if kind == "lower bound":
        return f"> {significant(lo)}"
    if kind == "upper bound":
        return f"< {significant(hi)}"
    if not math.isfinite(est):
        return NA
    mark = "" if kind == "bootstrap" else " ‡"
    return f"{significant(est)} {interval(lo, hi, _bound)}{mark}"


def _bound(x: float) -> str:
    """An interval end of a capacity: ∞ for an open top."""
    return "∞" if x == math.inf else significant(x)


def _fmt_rate(at: dict[str, Any]) -> str:
    """Contacts per 100 km at a level with its interval, three significant digits."""
    return with_interval(at.get("contact_rate_per_100km"), at.get("contact_rate_per_100km_ci"))


def _fmt_p(p: Any, ci: Any = None) -> str:
    """A probability of the headline with its interval, two significant digits."""
    return with_interval(p, ci, 2)


def headline(
    sweeps: dict[str, dict[str, dict[str, Any]]],
    suite: dict[str, Any],
    entrants: list[str],
    conditions: list[str],
) -> dict[str, Any]:
    """Collect the headline from the sweeps ``{family: {label: fragility result}}``."""
    rough = suite["families"][REFERENCE_FAMILY]
    ref_level = float(rough["levels"][len(rough["levels"]) // 2])
    rows = []
    for cond in conditions:
        for label in entrants:
            row: dict[str, Any] = {
                "condition": cond,
                "entrant": label,
                "capacity": {},
                "at_levels": [],
            }
            for fam, by_label in sweeps.items():
                res = by_label.get(label)
                if res is None:
                    continue
                for f in res["fits"]:
                    if f["condition"] == cond:
                        fd = f["fit"] if isinstance(f["fit"], dict) else f["fit"].to_dict()
                        est, lo, hi, kind = capacity_interval(fd)
                        row["capacity"][fam] = {
                            "theta": est,
                            "lo": lo,
                            "hi": hi,
                            "kind": kind,
                            "status": fd.get("status"),
                        }
                if fam == REFERENCE_FAMILY:
                    for r in res["levels"]:
                        if r["condition"] != cond or not _in(r["level"], rough["levels"]):
                            continue
                        g = r.get("sts_guidance") or {}
                        gw = _worst_unit(g)
                        row["at_levels"].append(
                            {
                                "level": r["level"],
                                "p_contact": r["p_contact"],
                                "p_contact_ci": r["p_contact_ci"],
                                "p_unsteady": r["p_unsteady"],
                                "p_unsteady_ci": r["p_unsteady_ci"],
                                "p_unsteady_guidance": r.get("p_unsteady_guidance"),
                                "p_unsteady_guidance_ci": gw.get("p_unsteady_ci"),
                                "contact_rate_per_100km": r["contact_rate_per_100km"],
                                "contact_rate_per_100km_ci": r["contact_rate_per_100km_ci"],
                                "rms_gap_mm": r["rms_gap_mm"],
                                "a_wz_m_s2": r["a_wz_m_s2"],
                                "a_wy_m_s2": r["a_wy_m_s2"],
                                "a_v_m_s2": r["a_v_m_s2"],
                                "comfort": r["comfort"],
                            }
                        )
            rows.append(row)
    return {"reference_level": ref_level, "rows": rows}


def _worst_unit(sts: dict[str, Any]) -> dict[str, Any]:
    units = sts.get("units") or []
    name = sts.get("worst_unit")
    for u in units:
        if u.get("name") == name:
            return u
    return {}


def _seed_text(settings: dict[str, Any]) -> str:
    """The seeds of a run in words: "evaluation range, 1000000–1000007" (or the list)."""
    seeds = settings_seeds(settings)
    lo, hi = min(seeds), max(seeds)
    contiguous = seeds == list(range(lo, hi + 1))
    span = (
        f"{lo}–{hi}"
        if contiguous
        else ", ".join(map(str, seeds[:6])) + (", …" if len(seeds) > 6 else "")
    )
    for name, (a, b) in SEED_RANGES.items():
        if a <= lo and hi <= b:
            return f"{name} range, {span}"
    return span


def _headline_intro(settings: dict[str, Any], conditions: list[str]) -> list[str]:
    """The headline's title, command, run settings and how to read the capacities."""
    return [
        "# Benchmark headline",
        "",
        f"Command: `{settings['command']}`",
        "",
        f"Entrants {', '.join(settings['entrants'])}; conditions "
        f"{', '.join(conditions)}; {settings['seeds']} seeds ({_seed_text(settings)}) "
        f"× {settings['distance_km']:g} km per level; wall time "
        f"{settings['wall_s']:.0f} s.",
        "",
        "Median capacity θ (severity at which half the runs touch; lognormal fragility "
        "fitted by maximum likelihood, 95 % bootstrap interval; ‡ = no finite MLE, θ "
        "bracketed by the grid levels around it); `+g` = the controller's guidance "
        "loops active (actuators levitation+guidance).",
        "",
    ]


def _condition_table(h: dict[str, Any], cond: str, families: list[str]) -> list[str]:
    """One condition's section: per entrant the capacity on every family and, at the
    reference level, P(unsteady), contact rate and comfort."""
    ref = h["reference_level"]
    header = (
        "entrant",
        *(f"θ {f}" for f in families),
        f"P(unsteady) gap @ roughness {ref:g}",
        f"P(unsteady) guidance @ {ref:g}",
        f"contacts / 100 km @ {ref:g}",
        f"W_k a_wz [m/s²] @ {ref:g}",
        "comfort",
    )
    cells = []
    for row in h["rows"]:
        if row["condition"] != cond:
            continue
        caps = [(_fmt_cap(row["capacity"][f]) if f in row["capacity"] else "—") for f in families]
        at = next((a for a in row["at_levels"] if abs(a["level"] - ref) < 1e-12), None)
        if at is None:
            rest = ["n/a"] * 5
        else:
            rest = [
                _fmt_p(at["p_unsteady"], at["p_unsteady_ci"]),
                _fmt_p(at["p_unsteady_guidance"], at["p_unsteady_guidance_ci"]),
                _fmt_rate(at),
                fixed(at["a_wz_m_s2"]),
                at["comfort"],
            ]
        cells.append((row["entrant"], *caps, *rest))
    align = "l" * (1 + len(families)) + "lllrl"
    return [f"## {cond}", "", *table_lines(header, cells, align), ""]


def _levels_section(h: dict[str, Any]) -> list[str]:
    """P(contact) and P(unsteady) of every entrant at every roughness suite level."""
    return [
        "## P(unsteady) at the roughness suite levels",
        "",
        "Worst unit's P(unsteady) (fitted law including contacts, 95 % block-bootstrap "
        "interval) of the levitation gap and of the guidance gap.",
        "",
        *table_lines(
            (
                "condition",
                "entrant",
                "level",
                "P(contact) per run",
                "P(unsteady) gap",
                "P(unsteady) guidance",
            ),
            (
                (
                    row["condition"],
                    row["entrant"],
                    f"{a['level']:g}",
                    _fmt_p(a["p_contact"], a["p_contact_ci"]),
                    _fmt_p(a["p_unsteady"], a["p_unsteady_ci"]),
                    _fmt_p(a["p_unsteady_guidance"], a["p_unsteady_guidance_ci"]),
                )
                for row in h["rows"]
                for a in row["at_levels"]
            ),
            "llrlll",
        ),
    ]


def _resolved_section(h: dict[str, Any], families: list[str], conditions: list[str]) -> list[str]:
    """Per condition and family, the pairs of entrants whose capacity intervals do not
    overlap (the higher one first)."""
    lines = [
        "",
        "## Resolved differences",
        "",
        "Pairs whose capacity intervals do not overlap (per family and condition):",
        "",
    ]
    for cond in conditions:
        rs = [r for r in h["rows"] if r["condition"] == cond]
        for f in families:
            pairs = []
            for i, a in enumerate(rs):
                for b in rs[i + 1 :]:
                    ca, cb = a["capacity"].get(f), b["capacity"].get(f)
                    if ca and cb and resolved(ca, cb):
                        hi_, lo_ = (a, b) if _bounds(ca)[0] > _bounds(cb)[0] else (b, a)
                        pairs.append(f"{hi_['entrant']} > {lo_['entrant']}")
            lines.append(f"- {cond}, {f}: {'; '.join(pairs) if pairs else 'none resolved'}")
    return lines


def headline_markdown(
    h: dict[str, Any],
    suite: dict[str, Any],
    families: list[str],
    conditions: list[str],
    settings: dict[str, Any],
) -> str:
    lines = _headline_intro(settings, conditions)
    units = {f: suite["families"][f].get("unit", "") for f in families}
    for cond in conditions:
        lines += _condition_table(h, cond, families)
    del units
    lines += _levels_section(h)
    lines += _resolved_section(h, families, conditions)
    targets = target_lines(h, families)
    if targets:
        lines += ["", "## Targets", "", targets.rstrip("\n")]
    return "\n".join(lines) + "\n"


def readme_table(h: dict[str, Any], families: list[str]) -> str:
    """The compact headline table of the README (one row per condition × entrant), built
    from ``headline.json`` only, so the README can be checked against it."""
    ref = h["reference_level"]
    short = {
        "paper-1000-straight": "1000 straight",
        "paper-1000-curved": "1000 R200",
        "paper-2000-straight": "2000 straight",
        "paper-2000-curved": "2000 R200",
    }
    header = (
        "condition",
        "entrant",
        *(f"θ {f}" for f in families),
        f"P(unst.) gap @ {ref:g}",
        f"P(unst.) guid. @ {ref:g}",
        f"contacts/100 km @ {ref:g}",
        f"W_k a_wz [m/s²] @ {ref:g}",
    )
    cells = []
    for row in h["rows"]:
        caps = [(_fmt_cap(row["capacity"][f]) if f in row["capacity"] else "—") for f in families]
        at = next((a for a in row["at_levels"] if abs(a["level"] - ref) < 1e-12), None)
        if at is None:
            rest = ["n/a"] * 4
        else:
            rest = [
                _fmt_p(at["p_unsteady"], at["p_unsteady_ci"]),
                _fmt_p(at["p_unsteady_guidance"], at["p_unsteady_guidance_ci"]),
                _fmt_rate(at),
                fixed(at["a_wz_m_s2"]),
            ]
        cond = short.get(row["condition"], row["condition"])
        cells.append((cond, row["entrant"], *caps, *rest))
    return table(header, cells, "l" * (2 + len(families)) + "lllr")


TARGETS: tuple[tuple[str, str, tuple[str, ...] | None, bool], ...] = (
    # (entrant, reference, families (None = all of the run), W_k no worse at the ref. level)
    ("ppo", "lqr", (REFERENCE_FAMILY,), True),
    ("ppo-guidance", "lqr+g", None, False),
)

"""The issue's targets: ``ppo`` (the four levitation currents) has a higher roughness median
capacity than LQR at every paper condition with non-overlapping intervals and W_k no worse
than LQR's; ``ppo-guidance`` beats LQR with guidance loops the same way on the families."""


def _side(a: dict[str, Any] | None, b: dict[str, Any] | None) -> str:
    """ "higher" / "lower" (intervals do not overlap), "unresolved" or "n/a"."""
    if not a or not b:
        return "n/a"
    if not resolved(a, b):
        return "unresolved"
    return "higher" if _bounds(a)[0] > _bounds(b)[1] else "lower"


def target_lines(h: dict[str, Any], families: list[str]) -> str:
    """The targets (:data:`TARGETS`) checked on the headline: met or not, with the numbers
    per condition. Empty when the run lacks the entrants."""
    short = {
        "paper-1000-straight": "1000 straight",
        "paper-1000-curved": "1000 R200",
        "paper-2000-straight": "2000 straight",
        "paper-2000-curved": "2000 R200",
    }
    ref = h["reference_level"]
    rows = {(r["condition"], r["entrant"]): r for r in h["rows"]}
    conds = list(dict.fromkeys(r["condition"] for r in h["rows"]))
    out = []
    for a, b, fams, comfort in TARGETS:
        if not all((c, e) in rows for c in conds for e in (a, b)):
            continue
        fams = [f for f in (fams or families) if f in families]
        ok = True
        parts = []
        for c in conds:
            ra, rb = rows[(c, a)], rows[(c, b)]
            cells = []
            for f in fams:
                ca, cb = ra["capacity"].get(f), rb["capacity"].get(f)
                side = _side(ca, cb)
                ok &= side == "higher"
                fa = _fmt_cap(ca) if ca else "n/a"
                fb = _fmt_cap(cb) if cb else "n/a"
                cells.append(f"{f} {fa} vs {fb}: {side}")
            if comfort:
                wa, wb = (
                    next(
                        (x["a_wz_m_s2"] for x in r["at_levels"] if abs(x["level"] - ref) < 1e-12),
                        None,
                    )
                    for r in (ra, rb)
                )
                if wa is None or wb is None or not (math.isfinite(wa) and math.isfinite(wb)):
                    ok = False
                    cells.append(f"W_k @ {ref:g} n/a")
                else:
                    ok &= wa <= wb
                    cells.append(f"W_k @ {ref:g} {wa:.3f} vs {wb:.3f} m/s²")
            parts.append(f"{short.get(c, c)}: " + "; ".join(cells))
        what = (
            f"`{a}` vs `{b}`: median capacity higher with non-overlapping intervals "
            f"({', '.join(fams)}) at every condition"
            + (f", W_k at roughness {ref:g} no worse" if comfort else "")
        )
        out.append(f"- {what}: **{'met' if ok else 'not met'}**. " + " — ".join(parts) + ".")
    return ("\n".join(out) + "\n") if out else ""


def headline_csv(h: dict[str, Any], families: list[str]) -> str:
    buf = io.StringIO()
    cols = ["condition", "entrant"]
    for f in families:
        cols += [f"theta_{f}", f"theta_{f}_lo", f"theta_{f}_hi", f"theta_{f}_kind"]
    cols += [
        "level",
        "p_contact",
        "p_unsteady",
        "p_unsteady_lo",
        "p_unsteady_hi",
        "p_unsteady_guidance",
        "contact_rate_per_100km",
        "a_wz_m_s2",
        "a_v_m_s2",
        "comfort",
    ]
    w = csv.DictWriter(buf, fieldnames=cols)
    w.writeheader()
    for row in h["rows"]:
        base: dict[str, Any] = {"condition": row["condition"], "entrant": row["entrant"]}
        for f in families:
            c = row["capacity"].get(f, {})
            base.update(
                {
                    f"theta_{f}": c.get("theta"),
                    f"theta_{f}_lo": c.get("lo"),
                    f"theta_{f}_hi": c.get("hi"),
                    f"theta_{f}_kind": c.get("kind"),
                }
            )
        for a in row["at_levels"] or [{}]:
            ci = a.get("p_unsteady_ci") or [None, None]
            w.writerow(
                {
                    **base,
                    "level": a.get("level"),
                    "p_contact": a.get("p_contact"),
                    "p_unsteady": a.get("p_unsteady"),
                    "p_unsteady_lo": ci[0],
                    "p_unsteady_hi": ci[1],
                    "p_unsteady_guidance": a.get("p_unsteady_guidance"),
                    "contact_rate_per_100km": a.get("contact_rate_per_100km"),
                    "a_wz_m_s2": a.get("a_wz_m_s2"),
                    "a_v_m_s2": a.get("a_v_m_s2"),
                    "comfort": a.get("comfort"),
                }
            )
    return buf.getvalue()
