"""The benchmark suite and the headline: ``python -m agents.benchmark``.

The **benchmark suite** (``agents/evaluation/benchmark_suite.json``, written once by
``scripts/calibrate_benchmark.py`` from the passive and PID baselines — never from a learned
agent) names, per disturbance family,

* ``levels``: a few severities (``low``, ``mid``, ``high``) at which the baselines sit in
  the measurable band (contact probability per 10 km between 0.05 and 0.95, or
  P(unsteady) between 1e-4 and 0.5) — the levels at which the paper's P(unsteady) is
  reported;
* ``grid``: the finer severity grid over which the fragility function (median capacity θ)
  is fitted;
* ``fixed``: disturbances held fixed while the family is swept (a coil fault or a sensor
  dropout is felt only on a rough guideway).

**Seeds** are disjoint by purpose (:data:`SEED_RANGES`): training below
:data:`TRAIN_SEED_LIMIT`, the benchmark's evaluation from :data:`EVAL_SEED0`, the Ray Tune
validation from :data:`VALIDATION_SEED0`, the suite's calibration from
:data:`CALIBRATION_SEED0` (defined in :mod:`agents.evaluation.seeds`). The benchmark runs
``--seeds`` seeds from ``--seed0`` (default :data:`EVAL_SEED0`) or the explicit
``--seed-list``; a learned entrant on training seeds is refused unless
``--allow-training-seeds``.

**Entrants** are controller names of :func:`agents.make_controller`; ``name+g`` runs the
controller with ``actuators="levitation+guidance"`` (its guidance loops active). A learned
agent runs with the actuator set it was trained with (``ppo-guidance``: levitation and
guidance). Each family × actuator set is one fragility sweep
(:func:`agents.evaluation.fragility.fragility`, which writes its own report, figures, JSON
and CSV under ``<out>/<family>/<actuators>/``); the **headline** (``headline.md``, ``.json``,
``.csv``) collects, per paper condition and entrant: the median capacity θ with its
interval on each family, the P(unsteady) of the levitation and guidance gaps with their
intervals at the suite's roughness levels, the contact rate per 100 km and the ISO 2631-1
comfort at the reference level (the roughness suite's ``mid`` level).

A capacity interval is the fit's bootstrap percentile interval; when the data have no
finite maximum-likelihood estimate (a sharp threshold between two grid levels) it is the
**bracket** of grid levels that contains θ, marked "bracket". Two entrants' capacities are
**resolved** when their intervals do not overlap.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agents.controllers import registry
from agents.controllers.registry import GUIDED, LEVITATION
from agents.evaluation import seeds as seeding
from agents.evaluation.render import (
    NA,
    fixed,
    interval,
    significant,
    table,
    table_lines,
    with_interval,
)

# the seed ranges are defined in agents.evaluation.seeds and named here too
from agents.evaluation.seeds import CALIBRATION_SEED0 as CALIBRATION_SEED0
from agents.evaluation.seeds import EVAL_SEED0 as EVAL_SEED0
from agents.evaluation.seeds import SEED_RANGES as SEED_RANGES
from agents.evaluation.seeds import TRAIN_SEED_LIMIT as TRAIN_SEED_LIMIT
from agents.evaluation.seeds import VALIDATION_SEED0 as VALIDATION_SEED0
from agents.evaluation.vocabulary import canonical
from hyperloop_env.json_values import json_value

SUITE_FILE = Path(__file__).with_name("benchmark_suite.json")

REFERENCE_FAMILY = "roughness"
DEFAULT_SEEDS = 8
DEFAULT_DISTANCE_KM = 3.0
HEADLINE_FAMILIES = ("roughness", "pier_settlement", "thermal_camber")
"""The families of the README headline (roughness and two more; the others of the suite
run with ``--families``)."""


# --------------------------------------------------------------------------------------
# the suite
# --------------------------------------------------------------------------------------


def load_suite(path: str | Path | None = None) -> dict[str, Any]:
    """The benchmark suite (module docstring); ValueError naming the problem if the file
    is missing a field or a family is unknown."""
    from hyperloop_env.disturbances import DISTURBANCES

    p = Path(path) if path is not None else SUITE_FILE
    try:
        suite = json.loads(p.read_text(), parse_constant=_no_constant)
    except FileNotFoundError:
        raise ValueError(
            f"no benchmark suite at {p} (write it with python scripts/calibrate_benchmark.py)"
        ) from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ValueError(f"{p}: not a readable JSON suite ({exc})") from None
    if not isinstance(suite, dict):
        raise ValueError(f"{p}: a suite is a JSON object with 'families', got a {_kind(suite)}")
    fams = suite.get("families")
    if not isinstance(fams, dict) or not fams:
        raise ValueError(f"{p}: 'families' must be a non-empty mapping")
    for name, spec in fams.items():
        if name not in DISTURBANCES:
            raise ValueError(f"{p}: unknown family {name!r}; known: {sorted(DISTURBANCES)}")
        if not isinstance(spec, dict):
            raise ValueError(f"{p}: families.{name} must be an object, got a {_kind(spec)}")
        fixed = spec.get("fixed", {})
        if not isinstance(fixed, dict) or not all(
            k in DISTURBANCES and _positive(v) for k, v in fixed.items()
        ):
            raise ValueError(
                f"{p}: families.{name}.fixed must map disturbance names to positive "
                f"severities, got {fixed!r}"
            )
        for key in ("levels", "grid"):
            v = spec.get(key)
            if not isinstance(v, list) or not v or not all(_positive(x) for x in v):
                raise ValueError(
                    f"{p}: families.{name}.{key} must be a non-empty list of "
                    f"positive numbers, got {v!r}"
                )
        spec.setdefault("fixed", {})
    return suite


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number JSON allows")


def _kind(x: Any) -> str:
    return {list: "list", str: "string", dict: "object"}.get(type(x), type(x).__name__)


def _positive(x: Any) -> bool:
    return not isinstance(x, bool) and isinstance(x, int | float) and math.isfinite(x) and x > 0


def suite_markdown(suite: dict[str, Any]) -> str:
    """The suite as a Markdown table (family, unit, levels, grid, fixed)."""
    from hyperloop_env.disturbances import DISTURBANCES

    rows = [
        (
            name,
            DISTURBANCES[name].severity_unit,
            ", ".join(f"{v:g}" for v in spec["levels"]),
            ", ".join(f"{v:g}" for v in spec["grid"]),
            ", ".join(f"{k} = {v:g}" for k, v in spec["fixed"].items()) or "—",
        )
        for name, spec in suite["families"].items()
    ]
    header = (
        "family",
        "severity unit",
        "suite levels (low, mid, high)",
        "fragility grid",
        "held fixed",
    )
    return table(header, rows)


# --------------------------------------------------------------------------------------
# entrants
# --------------------------------------------------------------------------------------


def entrant_actuators(name: str) -> tuple[str, str]:
    """(controller name, actuator set) of an entrant (module docstring)."""
    from agents.controllers.registry import (
        available_controllers,
        controller_problem,
        is_entry_point,
        offered_controllers,
    )

    base, act = (name[:-2], GUIDED) if name.endswith("+g") else (name, None)
    if base not in available_controllers() and not is_entry_point(base):
        raise ValueError(
            f"unknown entrant {name!r}: {base!r} is not a controller "
            f"(available: {offered_controllers()}, 'package.module:factory' "
            "or the path of a saved model.zip; append +g for "
            "levitation+guidance)"
        )
    problem = controller_problem(base)  # not shipped, or the [train] extra missing
    if problem:
        raise ValueError(f"entrant {name!r}: {problem}")
    trained = learned_actuators(base)
    if trained is not None:
        if act is not None and act != trained:
            raise ValueError(f"entrant {name!r}: {base!r} was trained with actuators={trained!r}")
        return base, trained
    return base, act or LEVITATION


def learned_actuators(name: str) -> str | None:
    """The actuator set a shipped learned agent was trained with (None for a classical
    controller or an agent that is not shipped)."""
    from agents.controllers.learned import MODEL_FILE
    from agents.controllers.registry import controller_spec, shipped_folder
    from agents.installation import require_data_file

    spec = controller_spec(name)
    folder = shipped_folder(name) if spec is not None and spec.kind == "learned" else None
    if folder is None or not (folder / MODEL_FILE).is_file():
        return None
    # a shipped agent's log is package data: missing or unreadable is an error naming it
    log = require_data_file(folder / "training_log.json", f"the shipped {name!r} agent")
    try:
        kw = json.loads(log.read_text()).get("env_kwargs") or {}
    except ValueError as exc:
        raise ValueError(f"{log}: not a JSON training log ({exc})") from None
    return str(kw.get("actuators", LEVITATION))


def entrant_label(base: str, actuators: str) -> str:
    from agents.controllers.registry import controller_spec

    spec = controller_spec(base)
    if actuators == GUIDED and (spec is None or spec.kind != "learned"):
        return f"{base}+g"
    return base


def default_entrants() -> tuple[str, ...]:
    """The headline entrants: the registry's entrants with the levitation currents, then
    those with the guidance currents too (:func:`agents.controllers.registry.entrants`),
    labelled as :func:`entrant_label` does."""
    return tuple(entrant_label(n, a) for a in (LEVITATION, GUIDED) for n in registry.entrants(a))


DEFAULT_ENTRANTS = default_entrants()
"""The entrants of ``benchmark`` and ``capacity`` by default (the registry's at import)."""


# --------------------------------------------------------------------------------------
# capacities and the headline
# --------------------------------------------------------------------------------------


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


def _in(x: float, levels: Sequence[float]) -> bool:
    return any(abs(x - v) <= 1e-12 * max(1.0, abs(v)) for v in levels)


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


def headline_markdown(
    h: dict[str, Any],
    suite: dict[str, Any],
    families: list[str],
    conditions: list[str],
    settings: dict[str, Any],
) -> str:
    ref = h["reference_level"]
    lines = [
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
    units = {f: suite["families"][f].get("unit", "") for f in families}
    for cond in conditions:
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
            caps = [
                (_fmt_cap(row["capacity"][f]) if f in row["capacity"] else "—") for f in families
            ]
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
        lines += [f"## {cond}", "", *table_lines(header, cells, align), ""]
    del units
    lines += [
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
    lines += [
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


# --------------------------------------------------------------------------------------
# the run
# --------------------------------------------------------------------------------------


def run_benchmark(
    entrants: Sequence[str] = DEFAULT_ENTRANTS,
    conditions: Sequence[str] = ("paper",),
    families: Sequence[str] | None = None,
    seeds: int | Sequence[int] = DEFAULT_SEEDS,
    distance_km: float = DEFAULT_DISTANCE_KM,
    *,
    seed0: int = EVAL_SEED0,
    allow_training_seeds: bool = False,
    suite: str | Path | dict[str, Any] | None = None,
    workers: int = 1,
    backend: str = "local",
    address: str | None = None,
    out_dir: str | Path | None = None,
    overwrite: bool = False,
    resume: bool = False,
    figures: bool = True,
    progress: bool = True,
    n_boot: int = 200,
    n_boot_fragility: int = 1000,
    command: str | None = None,
) -> dict[str, Any]:
    """Run the suite for ``entrants`` and collect the headline (module docstring).

    ``seeds``: a number of runs per level (seeds ``seed0``, ``seed0 + 1``, …; ``seed0``
    defaults to the evaluation range, :data:`EVAL_SEED0`) or an explicit list (at least two
    either way). A learned entrant on seeds of the training range is refused unless
    ``allow_training_seeds`` (:func:`agents.evaluation.seeds.check_evaluation_seeds`).

    ``resume``: continue an interrupted run in ``out_dir``: a family × actuator block whose
    ``results.json`` is there, complete, and was run with the same entrants, conditions,
    levels, seeds, distance, fixed disturbances, actuators and bootstrap sizes is read
    instead of rerun (the results are deterministic in the seeds, so this equals a fresh
    run); a block whose ``results.json`` is missing, unreadable or incomplete is unfinished
    and runs again (a line on stderr names the file and what is wrong); a complete block run
    with other settings is refused before anything runs.

    Every value is checked before anything is created; ``out_dir`` is held for the run
    (:func:`agents.evaluation.outputs.output_lock`); a block's files are written into a
    temporary directory that replaces ``<out>/<family>/<actuators>`` when it is complete,
    so an interrupt (Ctrl-C, SIGTERM) never leaves a half-written block. The headline's
    ``wall_s`` is this run's wall time plus that of the blocks read from a previous one."""
    from agents.evaluation.fragility import DEFAULT_BLOCK_SIZE, DEFAULT_MAX_SAMPLES, _check_args

    # ---- every value is checked before anything is created -------------------------------
    s = suite if isinstance(suite, dict) else load_suite(suite)
    fams = list(families) if families else list(s["families"])
    for f in fams:
        if f not in s["families"]:
            raise ValueError(f"--families: {f!r} is not in the suite ({sorted(s['families'])})")
    if len(set(fams)) != len(fams):
        raise ValueError(f"--families repeat: {fams}")
    if REFERENCE_FAMILY not in fams:
        raise ValueError(
            f"--families must include {REFERENCE_FAMILY!r} (the headline's reference family)"
        )
    seed_list = seeding.resolve(seeds, seed0, min_n=2)
    from hyperloop_env.scenarios import expand_scenarios

    conds = expand_scenarios(list(conditions))
    parsed = [entrant_actuators(e) for e in entrants]
    labels = [entrant_label(b, a) for b, a in parsed]
    if len(set(labels)) != len(labels):
        raise ValueError(f"entrants repeat: {labels}")
    seeding.check_evaluation_seeds(
        [b for b, _ in parsed], seed_list, allow_training_seeds, names=seeding.API_NAMES
    )
    if resume and (out_dir is None or overwrite):
        raise ValueError("resume needs an output directory and excludes overwrite")
    blocks: list[_Block] = []
    for fam in fams:
        spec = s["families"][fam]
        levels = sorted({*map(float, spec["grid"]), *map(float, spec["levels"])})
        for act in (LEVITATION, GUIDED):
            group = [(b, lab) for (b, a), lab in zip(parsed, labels, strict=True) if a == act]
            if not group:
                continue
            ctrls = [b for b, _ in group]
            _check_args(
                ctrls,
                conds,
                fam,
                levels,
                seed_list,
                distance_km,
                "repelling",
                1.0,
                DEFAULT_BLOCK_SIZE,
                DEFAULT_MAX_SAMPLES,
                "exact",
                allow_training_seeds=allow_training_seeds,
                n_boot=n_boot,
                n_boot_fragility=n_boot_fragility,
                fixed=spec["fixed"] or None,
                env_kwargs={"actuators": act},
            )
            blocks.append(_Block(fam, act, group, levels, dict(spec["fixed"])))
    with contextlib.ExitStack() as held:
        out = None
        if out_dir is not None:
            from agents.evaluation.outputs import output_lock, prepare_output_dir

            held.enter_context(output_lock(out_dir, "benchmark output directory"))
            if resume:
                out = Path(out_dir)
                _check_resumable(out, fams)
            else:
                out = prepare_output_dir(
                    out_dir,
                    overwrite=overwrite,
                    owned=("headline.md", "headline.json", "headline.csv", *fams),
                    flag="--resume to continue it (its finished blocks are kept), or "
                    "--overwrite to delete it and start again",
                )
        return _run_blocks(
            out,
            blocks,
            s,
            fams,
            conds,
            labels,
            seed_list,
            distance_km,
            resume=resume,
            allow_training_seeds=allow_training_seeds,
            backend=backend,
            workers=workers,
            address=address,
            figures=figures,
            progress=progress,
            n_boot=n_boot,
            n_boot_fragility=n_boot_fragility,
            command=command,
        )


def _check_resumable(out: Path, families: Sequence[str]) -> None:
    """``--resume`` continues a benchmark run: refuse a folder holding anything a run of
    these families does not write (a user's files are never replaced), or a report
    without a family folder (not a run of this tool); an empty folder starts the run."""
    from agents.evaluation.outputs import OutputDirError, entries, partial_dirs

    hint = "resume into the folder of an interrupted benchmark run, or choose a new --out"
    blocks = {LEVITATION.replace("+", "-"), GUIDED.replace("+", "-")}
    found = entries(out)
    for q in found:
        inside = []
        if q.name in families and q.is_dir():
            leftovers = set(partial_dirs(q))
            inside = [x for x in q.iterdir() if x.name not in blocks and x not in leftovers]
        elif q.name not in ("headline.md", "headline.json", "headline.csv") or q.is_dir():
            inside = [q]
        if inside:
            raise OutputDirError(
                f"--resume: {out} is not a benchmark run of these families: it holds "
                f"{inside[0]}, which such a run does not write ({hint})"
            )
    if found and not any(q.is_dir() for q in found):
        raise OutputDirError(
            f"--resume: {out} is not a benchmark run: it holds no block of its families ({hint})"
        )


@dataclass(frozen=True)
class _Block:
    """One family × actuator set of a benchmark run (one fragility sweep)."""

    family: str
    actuators: str
    group: list[tuple[str, str]]  # (controller, entrant label)
    levels: list[float]
    fixed: dict[str, Any]

    @property
    def controllers(self) -> list[str]:
        return [b for b, _ in self.group]

    def dir(self, out: Path) -> Path:
        return out / self.family / self.actuators.replace("+", "-")


def _run_blocks(
    out: Path | None,
    blocks: list[_Block],
    s: dict[str, Any],
    fams: list[str],
    conds: list[str],
    labels: list[str],
    seed_list: list[int],
    distance_km: float,
    *,
    resume: bool,
    allow_training_seeds: bool,
    backend: str,
    workers: int,
    address: str | None,
    figures: bool,
    progress: bool,
    n_boot: int,
    n_boot_fragility: int,
    command: str | None,
) -> dict[str, Any]:
    import shutil

    from agents.evaluation.fragility import fragility, to_json, write_outputs
    from agents.evaluation.outputs import atomic_dir, atomic_write_text, partial_dirs

    t0 = time.perf_counter()
    done: dict[int, dict[str, Any]] = {}
    if out is not None:
        for fam in fams:  # leftovers of a killed run (this run holds the directory's lock)
            for q in partial_dirs(out / fam):
                shutil.rmtree(q, ignore_errors=True)
    if resume and out is not None:  # every finished block, or a refusal, before any runs
        for k, b in enumerate(blocks):
            doc = _finished_block(
                b.dir(out),
                b.controllers,
                conds,
                b.levels,
                seed_list,
                distance_km,
                b.fixed,
                actuators=b.actuators,
                n_boot=n_boot,
                n_boot_fragility=n_boot_fragility,
            )
            if doc is not None:
                done[k] = doc
    sweeps: dict[str, dict[str, dict[str, Any]]] = {}
    raw: dict[str, dict[str, Any]] = {}
    for k, b in enumerate(blocks):
        if k in done:
            doc = done[k]
        else:
            res = fragility(
                b.controllers,
                conds,
                b.family,
                b.levels,
                seeds=seed_list,
                allow_training_seeds=allow_training_seeds,
                distance_km=distance_km,
                fixed=b.fixed or None,
                env_kwargs={"actuators": b.actuators},
                n_boot=n_boot,
                n_boot_fragility=n_boot_fragility,
                backend=backend,
                workers=workers,
                address=address,
                out_dir=None,
                progress=progress,
                command=command,
            )
            if out is not None:  # the block appears whole or not at all
                sub = b.dir(out)
                with atomic_dir(sub) as tmp:
                    paths = write_outputs(res, tmp, figures)
                res["paths"] = {k_: str(sub / Path(v).relative_to(tmp)) for k_, v in paths.items()}
            doc = to_json(res)
        raw.setdefault(b.family, {})[b.actuators] = doc
        for c, lab in b.group:
            sweeps.setdefault(b.family, {})[lab] = {
                "fits": [f for f in doc["fits"] if f["controller"] == c],
                "levels": [r for r in doc["levels"] if r["controller"] == c],
            }
    h = json_value(headline(sweeps, s, labels, conds))
    earlier = sum(float(d["settings"]["wall_s"]) for d in done.values())
    settings = {
        "entrants": labels,
        "conditions": conds,
        "families": fams,
        "seeds": len(seed_list),
        "seed_range": [min(seed_list), max(seed_list)],
        "seed_list": seed_list,
        "distance_km": float(distance_km),
        "suite": {f: s["families"][f] for f in fams},
        "wall_s": time.perf_counter() - t0 + earlier,
        "n_boot": n_boot,
        "n_boot_fragility": n_boot_fragility,
        "command": command or "agents.evaluation.benchmark.run_benchmark(...)",
    }
    result = {"settings": settings, "headline": h, "sweeps": raw}
    if out is not None:
        atomic_write_text(out / "headline.md", headline_markdown(h, s, fams, conds, settings))
        atomic_write_text(
            out / "headline.json",
            json.dumps(json_value({"settings": settings, "headline": h}), indent=1) + "\n",
        )
        atomic_write_text(out / "headline.csv", headline_csv(h, fams))
    return result


def settings_seeds(settings: dict[str, Any]) -> list[int]:
    """The seeds of a run's settings (``seed_list``; runs written before it was recorded
    used the contiguous ``seed_range``)."""
    if settings.get("seed_list") is not None:
        return [int(s) for s in settings["seed_list"]]
    lo, hi = settings["seed_range"]
    return list(range(int(lo), int(hi) + 1))


LEVEL_FIELDS = (
    "controller",
    "condition",
    "level",
    "n_runs",
    "n_contacts",
    "p_contact",
    "p_contact_ci",
    "p_unsteady",
    "p_unsteady_ci",
    "contact_rate_per_100km",
    "contact_rate_per_100km_ci",
    "rms_gap_mm",
    "a_wz_m_s2",
    "a_wy_m_s2",
    "a_v_m_s2",
    "comfort",
)
"""The fields of a block's level row that the headline and a merge read."""


def block_problem(
    doc: Any, controllers: list[str], conditions: list[str], levels: list[float]
) -> str | None:
    """What makes a block's ``results.json`` content incomplete (a missing field, named;
    a missing level row or fit, named by controller, condition and level), or None."""
    if not isinstance(doc, dict):
        return "not a JSON object"
    for key, kind in (("settings", dict), ("levels", list), ("fits", list)):
        if not isinstance(doc.get(key), kind):
            return f"no {key!r} {'mapping' if kind is dict else 'list'}"
    if not _number(doc["settings"].get("wall_s")) or doc["settings"]["wall_s"] < 0:
        return "no 'settings.wall_s' (a number of seconds >= 0)"
    rows: dict[tuple[Any, Any, float], dict[str, Any]] = {}
    for i, r in enumerate(doc["levels"]):
        if not isinstance(r, dict):
            return f"levels[{i}] is not a mapping"
        missing = [f for f in LEVEL_FIELDS if f not in r]
        if missing:
            return f"levels[{i}] has no {missing[0]!r}"
        for f in LEVEL_FIELDS:
            if not _field_ok(f, r[f]):
                return f"levels[{i}].{f} = {r[f]!r} is not {_FIELD_KINDS[f][1]}"
        if r["n_contacts"] > r["n_runs"]:
            return f"levels[{i}] has more contacts ({r['n_contacts']}) than runs"
        rows[(r["controller"], r["condition"], float(r["level"]))] = r
    for c in controllers:
        for cond in conditions:
            for lv in levels:
                if not any(k[0] == c and k[1] == cond and _in(lv, [k[2]]) for k in rows):
                    return f"no level row for controller {c!r}, condition {cond!r}, level {lv:g}"
            fit = [
                f
                for f in doc["fits"]
                if isinstance(f, dict) and f.get("controller") == c and f.get("condition") == cond
            ]
            if not fit:
                return f"no fit for controller {c!r}, condition {cond!r} in 'fits'"
            if not isinstance(fit[0].get("fit"), dict) or "status" not in fit[0]["fit"]:
                return f"the fit of controller {c!r}, condition {cond!r} has no 'fit.status'"
            for k in ("theta", "beta"):
                v = fit[0]["fit"].get(k)
                if v is not None and not _number(v):
                    return f"the fit of controller {c!r}, condition {cond!r}: {k} = {v!r}"
    return None


def _number(x: Any) -> bool:
    return not isinstance(x, bool) and isinstance(x, int | float) and math.isfinite(x)


def _count(x: Any) -> bool:
    return not isinstance(x, bool) and isinstance(x, int) and x >= 0


def _probability(x: Any) -> bool:
    return _number(x) and 0.0 <= x <= 1.0


def _nonneg_or_none(x: Any) -> bool:
    return x is None or (_number(x) and x >= 0.0)


def _interval(x: Any) -> bool:
    return x is None or (
        isinstance(x, list) and len(x) == 2 and all(v is None or _number(v) for v in x)
    )


_FIELD_KINDS: dict[str, tuple[Any, str]] = {
    "controller": (lambda x: isinstance(x, str), "a name"),
    "condition": (lambda x: isinstance(x, str), "a condition name"),
    "level": (lambda x: _number(x) and x > 0, "a positive number"),
    "n_runs": (_count, "a count"),
    "n_contacts": (_count, "a count"),
    "p_contact": (_probability, "a probability"),
    "p_contact_ci": (_interval, "an interval [lo, hi]"),
    "p_unsteady": (lambda x: x is None or _probability(x), "a probability or null"),
    "p_unsteady_ci": (_interval, "an interval [lo, hi] or null"),
    "contact_rate_per_100km": (lambda x: _number(x) and x >= 0, "a rate >= 0"),
    "contact_rate_per_100km_ci": (_interval, "an interval [lo, hi]"),
    "rms_gap_mm": (_nonneg_or_none, "a number >= 0 or null"),
    "a_wz_m_s2": (_nonneg_or_none, "a number >= 0 or null"),
    "a_wy_m_s2": (_nonneg_or_none, "a number >= 0 or null"),
    "a_v_m_s2": (_nonneg_or_none, "a number >= 0 or null"),
    "comfort": (lambda x: x is None or isinstance(x, str), "a comfort class or null"),
}
"""What each of :data:`LEVEL_FIELDS` must hold (check, description for the message)."""


def _field_ok(field: str, value: Any) -> bool:
    return bool(_FIELD_KINDS[field][0](value))


def _finished_block(
    sub: Path | None,
    controllers: list[str],
    conditions: list[str],
    levels: list[float],
    seeds: list[int],
    distance_km: float,
    fixed: dict[str, Any] | None,
    *,
    actuators: str | None = None,
    n_boot: int | None = None,
    n_boot_fragility: int | None = None,
) -> dict[str, Any] | None:
    """The results of a finished block in ``sub`` (for ``resume``); None if the block is
    unfinished — no ``results.json``, or one that is unreadable or incomplete (then a line on
    stderr names the file and what is wrong, and the block runs again); ValueError naming
    the file and the setting if a complete block was run with other settings."""
    if sub is None:
        return None
    f = sub / "results.json"
    if not f.is_file():
        if sub.exists():
            print(
                f"--resume: {sub} has no results.json (an unfinished block): it runs again",
                file=sys.stderr,
            )
        return None
    try:
        doc = json.loads(f.read_text(), parse_constant=_no_constant)
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        problem = f"unreadable ({type(exc).__name__}: {exc})"
    else:
        problem = block_problem(doc, controllers, conditions, levels)
    if problem is not None:
        print(
            f"--resume: {f} is damaged or incomplete: {problem}; the block runs again",
            file=sys.stderr,
        )
        return None
    st = doc["settings"]
    want: dict[str, Any] = {
        "controllers": controllers,
        "conditions": conditions,
        "levels": levels,
        "seeds": seeds,
        "distance_km": float(distance_km),
        "fixed_disturbances": dict(fixed or {}),
    }
    if actuators is not None:
        want["env_kwargs"] = {"actuators": actuators}
    if n_boot is not None:
        want["n_boot_sts"] = n_boot
    if n_boot_fragility is not None:
        want["n_boot_fragility"] = n_boot_fragility
    for k, v in want.items():
        if st.get(k) != v:
            raise ValueError(
                f"--resume: {f} was run with {k}={st.get(k)!r}, this run asks "
                f"{v!r} (resume with that run's options, or use another --out)"
            )
    doc["levels"] = [canonical(r) for r in doc["levels"]]  # a block written before a rename
    return doc


def merge_runs(
    sources: Sequence[str | Path],
    out_dir: str | Path,
    *,
    overwrite: bool = False,
    figures: bool = True,
    n_boot_fragility: int = 1000,
    command: str | None = None,
) -> dict[str, Any]:
    """Merge benchmark runs of different entrants (same suite, conditions, seeds and
    distance) into one, as if they had run together: the level rows are pooled and every
    fragility function is refitted in the merged entrant order (the fits' bootstrap
    generators are seeded by entrant and condition index, so the result is the joint run's).
    Lets the baselines run while an agent trains."""
    from agents.evaluation.outputs import entries, output_lock, prepare_output_dir

    # validate everything before anything is deleted or written
    srcs = [Path(d) for d in sources]
    if len(srcs) < 2:
        raise ValueError("--merge needs at least two runs")
    if (
        isinstance(n_boot_fragility, bool)
        or not isinstance(n_boot_fragility, int)
        or n_boot_fragility < 1
    ):
        raise ValueError(f"--n-boot-fragility must be an integer >= 1, got {n_boot_fragility!r}")
    real = [p.resolve() for p in srcs]
    if len(set(real)) != len(real):
        raise ValueError(f"--merge: a run is given twice: {[str(p) for p in srcs]}")
    dest = Path(out_dir).resolve()
    for p, r in zip(srcs, real, strict=True):
        if r == dest or r in dest.parents or dest in r.parents:
            raise ValueError(
                f"--merge: the output {out_dir} must not be (inside) a merged run "
                f"({p}): a destination is never one of the sources"
            )
    docs = [_read_json(p / "headline.json", "--merge") for p in srcs]
    for p, d in zip(srcs, docs, strict=True):
        _check_merge_settings(p / "headline.json", d["settings"])
    s0 = docs[0]["settings"]
    for d, src in zip(docs[1:], sources[1:], strict=True):
        s = d["settings"]
        for key in (
            "conditions",
            "families",
            "seeds",
            "seed_range",
            "distance_km",
            "suite",
            "n_boot",
            "n_boot_fragility",
        ):
            if s.get(key) != s0.get(key):
                raise ValueError(f"--merge: {src} differs from {sources[0]} in {key!r}")
        if settings_seeds(s) != settings_seeds(s0):
            raise ValueError(f"--merge: {src} differs from {sources[0]} in 'seed_list'")
    labels = [lab for d in docs for lab in d["settings"]["entrants"]]
    if len(set(labels)) != len(labels):
        raise ValueError(f"--merge: entrants repeat across the runs: {labels}")
    parts_of: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for fam in s0["families"]:
        for src, d in zip(srcs, docs, strict=True):
            for act, doc in _merge_blocks(src, d["settings"], fam, s0["conditions"]).items():
                parts_of.setdefault((fam, act), []).append(doc)
    # write the merged run next to the destination, then move it in
    dest_dir = Path(out_dir)
    with output_lock(dest_dir, "merge output directory"):  # one run per directory
        if entries(dest_dir) and not overwrite:
            prepare_output_dir(dest_dir, overwrite=False)  # raises the usual refusal
        import shutil
        import tempfile

        out = Path(tempfile.mkdtemp(prefix=f".{dest_dir.name}.merging-", dir=dest_dir.parent))
        try:
            result = _merge_into(
                out, docs, sources, labels, parts_of, figures, n_boot_fragility, command
            )
            owned = ("headline.md", "headline.json", "headline.csv", *s0["families"])
            final = prepare_output_dir(dest_dir, overwrite=overwrite, owned=owned)
            for name in owned:
                if (out / name).exists():
                    os.replace(out / name, final / name)
        finally:
            shutil.rmtree(out, ignore_errors=True)
    return result


def _check_merge_settings(f: Path, st: Any) -> None:
    """The settings of a run to merge: an object whose entrants, conditions and families
    are non-empty lists of names and whose seeds and wall time are numbers."""
    if not isinstance(st, dict):
        raise ValueError(f"--merge: {f}: 'settings' must be an object, got {_kind(st)}")
    for key in ("entrants", "conditions", "families"):
        v = st.get(key)
        if not isinstance(v, list) or not v or not all(isinstance(x, str) for x in v):
            raise ValueError(f"--merge: {f}: settings.{key} must be a list of names, got {v!r}")
    if not _number(st.get("wall_s")):
        raise ValueError(f"--merge: {f}: settings.wall_s must be a number of seconds")
    try:
        settings_seeds(st)
    except (KeyError, TypeError, ValueError):
        raise ValueError(f"--merge: {f}: settings has no seed_list or seed_range") from None


def _merge_blocks(
    src: Path, st: dict[str, Any], fam: str, conditions: list[str]
) -> dict[str, dict[str, Any]]:
    """{actuators: block} of ``src`` for the family ``fam``, each complete; between them
    they must fly exactly the run's entrants, each once (a block that is missing, or one
    relabelled or copied from another run, is refused naming the file)."""
    blocks: dict[str, dict[str, Any]] = {}
    labels: list[str] = []
    for act in (LEVITATION, GUIDED):
        f = src / fam / act.replace("+", "-") / "results.json"
        if not f.exists():
            continue
        doc = _read_json(f, "--merge")
        ctrls = doc["settings"].get("controllers") if isinstance(doc["settings"], dict) else None
        if not isinstance(ctrls, list) or not ctrls or not all(isinstance(c, str) for c in ctrls):
            raise ValueError(f"--merge: {f}: settings.controllers must be a list of names")
        levels = doc["settings"].get("levels")
        if not isinstance(levels, list) or not all(_number(x) for x in levels):
            raise ValueError(f"--merge: {f}: settings.levels must be a list of numbers")
        problem = block_problem(doc, ctrls, conditions, levels)
        if problem is not None:
            raise ValueError(f"--merge: {f} is incomplete: {problem}")
        labels += [entrant_label(c, act) for c in ctrls]
        blocks[act] = doc
    if sorted(labels) != sorted(st["entrants"]) or len(set(labels)) != len(labels):
        raise ValueError(
            f"--merge: {src / fam} holds blocks for the entrants {labels}, but its run lists "
            f"{st['entrants']} (a missing, unfinished or relabelled block: finish the run "
            "with --resume, or merge the runs as written)"
        )
    return blocks


def _read_json(path: Path, flag: str) -> dict[str, Any]:
    """A JSON file of a finished run, or ValueError naming the file."""
    if not path.is_file():
        raise ValueError(f"{flag}: {path} not found (not a finished benchmark run)")
    try:
        doc = json.loads(path.read_text(), parse_constant=_no_constant)
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ValueError(f"{flag}: {path} is damaged ({exc})") from None
    if not isinstance(doc, dict) or "settings" not in doc:
        raise ValueError(f"{flag}: {path} has no 'settings' (not a benchmark result)")
    return doc


def _merge_into(
    out: Path,
    docs: list[dict[str, Any]],
    sources: Sequence[str | Path],
    labels: list[str],
    parts_of: dict[tuple[str, str], list[dict[str, Any]]],
    figures: bool,
    n_boot_fragility: int,
    command: str | None,
) -> dict[str, Any]:
    from agents.evaluation.fragility import _fit_all, to_json, write_outputs
    from agents.evaluation.outputs import atomic_write_text

    s0 = docs[0]["settings"]
    conds, fams = s0["conditions"], s0["families"]
    sweeps: dict[str, dict[str, dict[str, Any]]] = {}
    wall = sum(float(d["settings"]["wall_s"]) for d in docs)
    for fam in fams:
        for act in (LEVITATION, GUIDED):
            parts = parts_of.get((fam, act), [])
            if not parts:
                continue
            ctrls = [c for p in parts for c in p["settings"]["controllers"]]
            rows = [canonical(r) for p in parts for r in p["levels"]]  # older names too
            settings = dict(parts[0]["settings"])
            settings.update(
                controllers=ctrls,
                command=command or settings.get("command"),
                wall_s=sum(float(p["settings"]["wall_s"]) for p in parts),
            )
            res = {
                "settings": settings,
                "levels": rows,
                "fits": _fit_all(rows, ctrls, conds, n_boot_fragility),
                "paths": {},
            }
            sub = out / fam / act.replace("+", "-")
            sub.mkdir(parents=True, exist_ok=True)
            res["paths"] = write_outputs(res, sub, figures)
            fits_json = to_json(res)["fits"]
            for c in ctrls:
                lab = entrant_label(c, act)
                sweeps.setdefault(fam, {})[lab] = {
                    "fits": [f for f in fits_json if f["controller"] == c],
                    "levels": [r for r in rows if r["controller"] == c],
                }
    suite = {"families": s0["suite"]}
    order = [lab for lab in labels if any(lab in v for v in sweeps.values())]
    h = json_value(headline(sweeps, suite, order, conds))
    settings = {
        **s0,
        "entrants": order,
        "wall_s": wall,
        "command": command or "agents.evaluation.benchmark.merge_runs(...)",
        "merged_from": [str(x) for x in sources],
    }
    atomic_write_text(out / "headline.md", headline_markdown(h, suite, fams, conds, settings))
    atomic_write_text(
        out / "headline.json",
        json.dumps(json_value({"settings": settings, "headline": h}), indent=1) + "\n",
    )
    atomic_write_text(out / "headline.csv", headline_csv(h, fams))
    return {"settings": settings, "headline": h}
