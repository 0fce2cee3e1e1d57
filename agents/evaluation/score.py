"""Score one controller against the published benchmark, comparable by construction.

:func:`score` flies only the new controller — on the published evaluation seeds ×
conditions × families, with the published search settings
(:mod:`agents.evaluation.capacity_benchmark`) — and pairs its per-seed capacities with
every published entrant's (:mod:`agents.evaluation.published`) in every family
(:func:`agents.evaluation.capacity_stats.compare_paired`: paired bootstrap interval of the
ratio of median capacities, Wilcoxon test, ±5 % equivalence).

Before it flies anything it checks comparability:

* the fingerprint of the code here must equal the published one in every compared
  component (:data:`agents.evaluation.published.COMPARED`): otherwise
  :class:`ComparabilityError` names the components, unless ``allow_mismatch`` (then
  stamped into the result);
* a published entrant (``lqr``) is re-flown on the first :data:`GUARD_SEEDS` seeds of the
  first condition and family: its capacities must equal the published ones bit for bit.

``quick``: the roughness family on the first :data:`QUICK_SEEDS` seeds only (stated in the
result; a verdict the fewer seeds cannot decide says "undecided").

The result (:func:`render_markdown`, JSON, :func:`plot_score`) holds per condition ×
family: θ with its interval, the placement among the entrants by median capacity, a
verdict against every published entrant, P(unsteady) at the suite's levels and what set
each capacity (the kind of the first contact of the run at the capacity: levitation gap,
guidance gap or both); and a one-line leaderboard entry.

**Ride comfort** (:func:`comfort_cells`): per condition the controller also flies one run
per seed of the scope (the scenario's own irregularity, the published distance:
:func:`agents.evaluation.comparisons.comfort.a_wz`, the ISO 2631-1 W_k-weighted RMS heave
acceleration a_wz) and is paired with every published entrant's a_wz on the same seeds
(:func:`agents.evaluation.published.load_published_comfort`;
:func:`agents.evaluation.comparisons.comfort.compare`: a run that touched is left out of
both sides, the geometric mean of the per-seed ratios with its paired bootstrap interval,
Wilcoxon test, ±5 % equivalence): ``smoother`` (lower a_wz), ``equivalent``, ``rougher``
or ``undecided``. ``quick`` flies the comfort runs on its seeds too.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from agents.evaluation import capacity_stats as cs
from agents.evaluation.capacity import contact_kinds
from agents.evaluation.published import (
    BENCHMARK_VERSION,
    PublishedDataError,
    differences,
    fingerprint,
    load_published,
    load_published_comfort,
    published_seeds,
)

GUARD_ENTRANT = "lqr"
GUARD_SEEDS = 2
QUICK_SEEDS = 8
QUICK_FAMILIES = ("roughness",)


class ComparabilityError(ValueError):
    """The local code cannot be compared with the published table (message says why)."""


@dataclass(frozen=True)
class ScoreSpec:
    """What to score: a controller (registry name, ``module:factory`` or a ``model.zip``),
    the full published scope or the ``quick`` one, and whether a fingerprint mismatch is
    accepted (``allow_mismatch``: stamped into the result) and the guard re-flight run."""

    controller: str
    quick: bool = False
    allow_mismatch: bool = False
    guard: bool = True


def scope(published: dict[str, Any], quick: bool) -> tuple[list[str], list[str], list[int]]:
    """(conditions, families, seeds) a score flies."""
    st = published["settings"]
    seeds = published_seeds(published)
    if quick:
        return list(st["conditions"]), list(QUICK_FAMILIES), seeds[:QUICK_SEEDS]
    return list(st["conditions"]), list(st["families"]), seeds


def check_fingerprint(published: dict[str, Any], allow_mismatch: bool) -> dict[str, Any]:
    """The local fingerprint; :class:`ComparabilityError` naming the differing components
    unless ``allow_mismatch``."""
    local = fingerprint(published["settings"])
    diff = differences(local, published["fingerprint"])
    if diff and not allow_mismatch:
        raise ComparabilityError(
            f"this installation differs from the published benchmark {BENCHMARK_VERSION} "
            f"in: {', '.join(diff)} (a changed model, condition, disturbance, search, seeds "
            "or distance: its capacities are not comparable; pass --allow-mismatch to score "
            "anyway, stamped into the result)"
        )
    return {**local, "differs_in": diff}


def guard(published: dict[str, Any], seeds: int = GUARD_SEEDS) -> dict[str, Any]:
    """Re-fly :data:`GUARD_ENTRANT` on the first ``seeds`` seeds of the first condition and
    family; :class:`ComparabilityError` showing the difference unless bit-identical."""
    from agents.evaluation import capacity_benchmark as cb
    from agents.evaluation.benchmark import load_suite
    from agents.evaluation.capacity import run_task

    st = published["settings"]
    cond, fam = st["conditions"][0], st["families"][0]
    cell = published["cells"][cond][fam][GUARD_ENTRANT]
    want = list(zip(cell["seeds"][:seeds], cell["capacity"][:seeds], strict=True))
    (task,), _ = cb.plan(
        [GUARD_ENTRANT], [cond], [fam], [s for s, _ in want], st["distance_km"],
        load_suite(), rows=st["rows"], ratio=st["ratio"], step=st["step"],
        check_above=st["check_above"],
    )  # fmt: skip
    res = run_task(type(task)(**{**task.__dict__, "sts_stride": 0}))
    got = [(s.seed, s.capacity) for s in res.searches]
    if got != want:
        raise ComparabilityError(
            f"the published {GUARD_ENTRANT!r} re-flown here ({cond}, {fam}) finds the "
            f"capacities {got}, the published table {want}: this installation flies "
            "differently, its scores would not be comparable"
        )
    return {"entrant": GUARD_ENTRANT, "condition": cond, "family": fam, "capacities": got}


def controller_name(entry: str) -> str:
    """The ``name`` of the controller ``entry`` builds (its label in the results)."""
    from agents.controllers.registry import make_controller

    ctrl = make_controller(entry)
    return str(getattr(ctrl, "name", None) or entry)


def score(
    spec: ScoreSpec,
    *,
    workers: int = 1,
    backend: str = "local",
    address: str | None = None,
    progress: bool = True,
    published: dict[str, Any] | None = None,
    comfort: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Score ``spec.controller`` (module docstring); returns the result document.
    ``published`` / ``comfort``: the published capacities and ride comfort (default: the
    package data)."""
    from agents.evaluation.backends import shared_pool
    from agents.evaluation.entrants import entrant_actuators, entrant_label

    pub = published if published is not None else load_published()
    ride = comfort if comfort is not None else load_published_comfort(published=pub)
    fp = check_fingerprint(pub, spec.allow_mismatch)
    checked = guard(pub) if spec.guard else None
    conds, fams, seeds = scope(pub, spec.quick)
    st = pub["settings"]
    name = controller_name(spec.controller)
    km = float(ride["distance_km"])
    where = {"workers": workers, "backend": backend, "address": address}
    with shared_pool(workers if backend == "local" else 1):  # one pool for both parts
        res, mine, comfort_wall_s = _fly(
            spec.controller, pub, conds, fams, seeds, km, progress, where
        )
    lab = entrant_label(*entrant_actuators(spec.controller))
    cells = [
        _cell(pub, res, cond, fam, lab, name) for cond in conds for fam in fams
    ]  # fmt: skip
    return {
        "benchmark": BENCHMARK_VERSION,
        "controller": name,
        "entry": spec.controller,
        "quick": spec.quick,
        "scope": {"conditions": conds, "families": fams, "seeds": [seeds[0], seeds[-1]]},
        "fingerprint": fp,
        "published_fingerprint": pub["fingerprint"]["digest"],
        "allow_mismatch": bool(fp["differs_in"]),
        "guard": checked,
        "cells": cells,
        "leaderboard": leaderboard_entry(name, cells, fp, spec.quick),
        "comfort": comfort_result(ride, mine, seeds, st["entrants"], comfort_wall_s),
        "wall_s": res["settings"]["wall_s"] + comfort_wall_s,
    }


def _fly(
    entry: str,
    pub: dict[str, Any],
    conds: list[str],
    fams: list[str],
    seeds: list[int],
    km: float,
    progress: bool,
    where: dict[str, Any],
) -> tuple[dict[str, Any], dict[str, list[float | None]], float]:
    """The controller's capacity runs (the published settings) and its comfort runs
    (:func:`~agents.evaluation.comparisons.comfort.ride_table`): ``(capacity result,
    {condition: a_wz per seed}, the comfort runs' wall time [s])``."""
    from agents.evaluation import capacity_benchmark as cb
    from agents.evaluation.comparisons.comfort import ride_table

    st = pub["settings"]
    res = cb.run(
        [entry], conds, fams, seeds, st["distance_km"], rows=st["rows"], ratio=st["ratio"],
        step=st["step"], check_above=st["check_above"], n_boot=st["n_boot"],
        progress=progress, figures=False, entrant_seeds={}, **where,
    )  # fmt: skip
    per, wall_s = ride_table(conds, [entry], seeds, km, **where)
    return res, {c: per[c][entry] for c in conds}, wall_s


def _cell(
    pub: dict[str, Any], res: dict[str, Any], cond: str, fam: str, lab: str, name: str
) -> dict[str, Any]:
    mine = res["analysis"][cond][fam]["entrants"][lab]
    fit = mine["fit"]
    arrays = (np.array(mine["capacity"]), np.array(mine["censored"]), mine["seeds"])
    verdicts = []
    for other, e in pub["cells"][cond][fam].items():
        theirs = (np.array(e["capacity"]), np.array(e["censored"]), e["seeds"])
        v = cs.compare_paired(*cs.on_common_seeds(arrays, theirs, name, other), seed=0)
        verdicts.append(
            {
                "entrant": other,
                **{k: v[k] for k in ("verdict", "ratio", "lo", "hi", "p_value", "n")},
            }
        )
    return {
        "condition": cond,
        "family": fam,
        "theta": fit.get("theta"),
        "theta_ci": fit.get("theta_ci"),
        "median_empirical": fit.get("median_empirical"),
        "n_censored": int(sum(mine["censored"])),
        "placement": placement(pub["cells"][cond][fam], fit),
        "verdicts": verdicts,
        "sts_at_levels": [
            {
                "severity": s["severity"],
                "p_unsteady": s["gap"]["p_unsteady"],
                "p_unsteady_guidance": s["guidance"]["p_unsteady"],
            }
            for s in mine.get("sts_at_levels") or []
        ],  # fmt: skip
        "contact_at_capacity": contact_kinds(res["capacities"][cond][fam][lab]),
    }


def _median(e: dict[str, Any]) -> float:
    for k in ("theta", "median_empirical"):
        if e.get(k) is not None:
            return float(e[k])
    return float(np.median(e["capacity"]))


def placement(entrants: dict[str, dict[str, Any]], fit: dict[str, Any]) -> dict[str, Any]:
    """The new controller's rank by median capacity among the published entrants (1 =
    highest) and the entrants just above and below it."""
    mine = _median({**fit, "capacity": [0.0]})
    ranked = sorted(((_median(e), lab) for lab, e in entrants.items()), reverse=True)
    above = [lab for m, lab in ranked if m > mine]
    below = [lab for m, lab in ranked if m <= mine]
    return {
        "rank": len(above) + 1,
        "of": len(ranked) + 1,
        "just_above": above[-1] if above else None,
        "just_below": below[0] if below else None,
    }


SYMBOL = {"A above B": ">", "B above A": "<", "equivalent": "=", "undecided": "?"}


def leaderboard_entry(
    name: str, cells: Sequence[dict[str, Any]], fp: dict[str, Any], quick: bool
) -> dict[str, Any]:
    """One line of the leaderboard: the median capacity per cell and how many published
    entrants the controller is resolved above, below, equivalent to or undecided against."""
    counts = Counter(SYMBOL[v["verdict"]] for c in cells for v in c["verdicts"])
    return {
        "controller": name,
        "benchmark": BENCHMARK_VERSION,
        "fingerprint": fp["digest"],
        "quick": quick,
        "theta": {f"{c['condition']}/{c['family']}": c["theta"] for c in cells},
        "above": counts[">"],
        "below": counts["<"],
        "equivalent": counts["="],
        "undecided": counts["?"],
    }


COMFORT_VERDICT = {
    "A above B": "rougher",
    "B above A": "smoother",
    "equivalent": "equivalent",
    "undecided": "undecided",
}
"""A paired verdict on a_wz (this controller = A) as a ride: a higher a_wz is rougher."""


def _mean_touched(vals: Sequence[float | None]) -> dict[str, Any]:
    kept = [v for v in vals if v is not None]
    return {
        "a_wz_mean_m_s2": float(np.mean(kept)) if kept else None,
        "contacts": len(vals) - len(kept),
    }


def comfort_cells(
    published: dict[str, Any],
    mine: dict[str, list[float | None]],
    seeds: Sequence[int],
    entrants: Sequence[str],
) -> list[dict[str, Any]]:
    """Per condition of ``mine`` (condition → this controller's a_wz per seed of
    ``seeds``, None: touched): its mean a_wz and runs that touched, and its paired
    comparison with each of ``entrants`` on the same seeds, from the published ride
    comfort ``published`` (module docstring). :class:`PublishedDataError` if a seed,
    condition or entrant is not in it."""
    from agents.evaluation.comparisons.comfort import compare

    pos = {int(s): k for k, s in enumerate(published["seeds"])}
    missing = [int(s) for s in seeds if int(s) not in pos]
    if missing:
        raise PublishedDataError(f"the published ride comfort has no seeds {missing}")
    idx = [pos[int(s)] for s in seeds]
    out = []
    for cond, vals in mine.items():
        if len(vals) != len(idx):
            raise ValueError(f"{cond}: {len(vals)} a_wz values for {len(idx)} seeds")
        verdicts = []
        for lab in entrants:
            per = published["a_wz_m_s2"].get(cond, {}).get(lab)
            if per is None:
                raise PublishedDataError(f"the published ride comfort has no {cond} × {lab}")
            theirs = [per[k] for k in idx]
            v = compare(list(vals), theirs)
            verdicts.append(
                {
                    "entrant": lab,
                    **_mean_touched(theirs),
                    **{k: v[k] for k in ("n", "ratio", "lo", "hi", "p_value")},
                    "verdict": COMFORT_VERDICT[v["verdict"]],
                }
            )
        out.append(
            {"condition": cond, "a_wz_m_s2": list(vals), **_mean_touched(vals),
             "verdicts": verdicts}
        )  # fmt: skip
    return out


def comfort_result(
    published: dict[str, Any],
    mine: dict[str, list[float | None]],
    seeds: Sequence[int],
    entrants: Sequence[str],
    wall_s: float,
) -> dict[str, Any]:
    """A score's ride comfort: the scope, the published data it is paired with, the cells
    (:func:`comfort_cells`) and how many pairs end in each verdict."""
    cells = comfort_cells(published, mine, seeds, entrants)
    counts = Counter(v["verdict"] for c in cells for v in c["verdicts"])
    return {
        "seeds": [int(seeds[0]), int(seeds[-1])],
        "n_seeds": len(seeds),
        "published_seeds": len(published["seeds"]),
        "distance_km": float(published["distance_km"]),
        "settle_s": published.get("settle_s"),
        "published": {k: published.get(k) for k in ("command", "date", "machine")},
        "cells": cells,
        "summary": {w: counts[w] for w in ("smoother", "equivalent", "rougher", "undecided")},
        "wall_s": wall_s,
    }
