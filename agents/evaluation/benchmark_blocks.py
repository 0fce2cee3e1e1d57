"""A finished block of a benchmark run (one family × actuator set: its ``results.json``),
checked field by field before a resume or a merge reads it."""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from agents.evaluation.benchmark_suite import _no_constant
from agents.evaluation.vocabulary import canonical


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


def _in(x: float, levels: Sequence[float]) -> bool:
    return any(abs(x - v) <= 1e-12 * max(1.0, abs(v)) for v in levels)
