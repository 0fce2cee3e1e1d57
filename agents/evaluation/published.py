"""The published benchmark as package data, and the fingerprint that makes a new entrant
comparable with it.

:data:`BENCHMARK_VERSION` names the published table; its file
(``agents/evaluation/published/<version>.json``, shipped in the wheel) holds, per paper
condition × family × entrant, the per-seed capacities on the evaluation seeds, the
censoring, the median-capacity fit and the paper's P(unsteady) at the suite's levels, with
the run's settings and its :func:`fingerprint`. ``hyperloop headline`` writes it from the
headline it publishes (:func:`compact`, :func:`write_published`).

**The fingerprint** covers what determines a capacity: the model parameters of every
condition (vehicle, magnets, guideway, irregularity, integrator, actuators; the resolved
parameters of each condition's env configuration, with both actuator sets), the
definitions of the families' disturbances, the search settings, the seeds (and the
entrants flown on fewer of them) and the distance. Each component is a SHA-256 of its
canonical JSON; :func:`differences` names the components two fingerprints disagree on. The
package version and the commit that produced a run are recorded as provenance, not
compared (a comparable code change is allowed; a changed number is not: ``hyperloop
score`` also re-flies a published entrant before it scores anything).

**Published ride comfort** (:data:`COMFORT_FILE`, shipped next to the capacities): the
ISO 2631-1 W_k-weighted RMS heave acceleration a_wz [m/s²] of every published entrant on
the published evaluation seeds, conditions and distance — one run per entrant, condition
and seed on the scenario's own irregularity, flown by
:func:`agents.evaluation.comparisons.comfort.a_wz` (None: the run touched). ``hyperloop
headline --comfort`` writes it (:func:`comfort_data`, :func:`write_published_comfort`),
recording its command, date and machine; :func:`load_published_comfort` reads it, checked
against the published capacities (same fingerprint, entrants, conditions, seeds and
distance).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import platform
import subprocess
from collections.abc import Callable, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from agents.evaluation.outputs import atomic_write_text

BENCHMARK_VERSION = "hyperloop-suspension-v1"
PUBLISHED_DIR = Path(__file__).with_name("published")
PUBLISHED_FILE = PUBLISHED_DIR / f"{BENCHMARK_VERSION}.json"
COMFORT_FILE = PUBLISHED_DIR / f"{BENCHMARK_VERSION}-comfort.json"
"""The published entrants' ride comfort (module docstring)."""
ACTUATOR_SETS = ("levitation", "levitation+guidance")
COMPARED = ("model", "conditions", "disturbances", "searches", "seeds", "distance_km")
"""The fingerprint's components that must agree (the others are provenance)."""


class PublishedDataError(ValueError):
    """The published data file is missing or damaged (the message names the file)."""


def _digest(x: Any) -> str:
    text = json.dumps(x, sort_keys=True, default=str, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _condition_params(condition: str, distance_km: float) -> dict[str, Any]:
    from agents.evaluation.rollout import episode_config

    out = {}
    for act in ACTUATOR_SETS:
        cfg = episode_config(condition, distance_km, None, {"actuators": act})
        base = dataclasses.asdict(cfg.resolve().base)
        out[act] = {"config": cfg.to_kwargs(), "params": base}
    return out


def fingerprint(settings: dict[str, Any]) -> dict[str, Any]:
    """The fingerprint of a capacity run with these ``settings`` (``headline.json``'s
    ``settings``: conditions, families, searches, seeds, distance), computed with the code
    installed here (module docstring)."""
    from hyperloop_env.disturbances import make_disturbance
    from hyperloop_env.physics.params import ModelParams

    conds, fams = settings["conditions"], settings["families"]
    dist = float(settings["distance_km"])
    seeds = settings.get("seed_list") or list(
        range(settings["seed_range"][0], settings["seed_range"][1] + 1)
    )
    parts = {
        "model": _digest(dataclasses.asdict(ModelParams())),
        "conditions": _digest({c: _condition_params(c, dist) for c in conds}),
        "disturbances": _digest(
            {f: repr(make_disturbance(f, settings["searches"][f]["start"])) for f in fams}
        ),
        "searches": _digest({f: settings["searches"][f] for f in fams}),
        "seeds": _digest([seeds, settings.get("entrant_seeds") or {}]),
        "distance_km": _digest(dist),
    }
    return {
        **parts,
        "digest": _digest([parts[k] for k in COMPARED]),
        "benchmark": BENCHMARK_VERSION,
        "package_version": _package_version(),
        "commit": _commit(),
    }


def differences(a: dict[str, Any], b: dict[str, Any]) -> list[str]:
    """The compared components (:data:`COMPARED`) on which two fingerprints disagree."""
    return [k for k in COMPARED if a.get(k) != b.get(k)]


def _package_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("hyperloop-suspension-gym")
    except PackageNotFoundError:  # pragma: no cover - a checkout on sys.path only
        return "unknown"


def _commit() -> str | None:
    """The commit of the checkout this package runs from (None outside a git checkout)."""
    root = Path(__file__).resolve().parents[2]
    try:
        done = subprocess.run(
            ["git", "-C", str(root), "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            timeout=10,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip() or None if done.returncode == 0 else None


# --------------------------------------------------------------------------------------
# the published data
# --------------------------------------------------------------------------------------

SETTINGS_KEPT = (
    "entrants",
    "seed_list",
    "conditions",
    "families",
    "seeds",
    "seed_range",
    "entrant_seeds",
    "distance_km",
    "ratio",
    "step",
    "check_above",
    "rows",
    "n_boot",
    "searches",
)


def compact(doc: dict[str, Any], run_commit: str | None = None) -> dict[str, Any]:
    """The published data of a capacity headline (``headline.json`` content): its settings,
    its fingerprint (the run's own; for a run that recorded none, the one the code here
    gives — valid because the published capacities re-fly bit for bit with it,
    ``tests/test_published_capacities.py``), the commit that flew it (``run_commit``, where
    known) and, per condition × family × entrant, what a new entrant is paired with."""
    st = {k: doc["settings"][k] for k in SETTINGS_KEPT if k in doc["settings"]}
    cells: dict[str, Any] = {}
    for cond, fams in doc["analysis"].items():
        for fam, cell in fams.items():
            for lab, e in cell["entrants"].items():
                fit = e.get("fit") or {}
                cells.setdefault(cond, {}).setdefault(fam, {})[lab] = {
                    "seeds": e["seeds"],
                    "capacity": e["capacity"],
                    "censored": e["censored"],
                    "theta": fit.get("theta"),
                    "theta_ci": fit.get("theta_ci"),
                    "median_empirical": fit.get("median_empirical"),
                    "sts_at_levels": [
                        {
                            "severity": s["severity"],
                            "p_unsteady": s["gap"]["p_unsteady"],
                            "p_unsteady_guidance": s["guidance"]["p_unsteady"],
                        }
                        for s in e.get("sts_at_levels") or []
                    ],
                }
    return {
        "benchmark": BENCHMARK_VERSION,
        "settings": st,
        "fingerprint": doc["settings"].get("fingerprint") or fingerprint(st),
        "run_commit": run_commit or (doc["settings"].get("fingerprint") or {}).get("commit"),
        "cells": cells,
    }


def write_published(
    doc: dict[str, Any], path: Path = PUBLISHED_FILE, run_commit: str | None = None
) -> Path:
    """Write the published data of the headline ``doc`` (atomically)."""
    text = json.dumps(compact(doc, run_commit), indent=0, sort_keys=True)
    atomic_write_text(path, text + "\n")
    return path


def load_published(path: str | Path = PUBLISHED_FILE) -> dict[str, Any]:
    """The published data, checked (:class:`PublishedDataError` naming the file and the
    problem)."""
    p = Path(path)
    try:
        doc = json.loads(p.read_text())
    except FileNotFoundError:
        raise PublishedDataError(f"{p}: no published benchmark data here") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise PublishedDataError(f"{p}: unreadable ({exc})") from None
    problem = _problem(doc)
    if problem:
        raise PublishedDataError(f"{p}: {problem}")
    return doc


def _problem(doc: Any) -> str | None:
    if not isinstance(doc, dict):
        return "not a JSON object"
    for key in ("benchmark", "settings", "fingerprint", "cells"):
        if key not in doc:
            return f"no {key!r}"
    st = doc["settings"]
    for key in ("conditions", "families", "entrants", "searches", "seed_range", "distance_km"):
        if key not in st:
            return f"no 'settings.{key}'"
    for cond in st["conditions"]:
        for fam in st["families"]:
            for lab in st["entrants"]:
                e = doc["cells"].get(cond, {}).get(fam, {}).get(lab)
                if e is None:
                    return f"no cell for {cond} × {fam} × {lab}"
                if not _capacities_ok(e):
                    return f"the capacities of {cond} × {fam} × {lab} are not per-seed numbers"
    return None


def _capacities_ok(e: dict[str, Any]) -> bool:
    caps, seeds, cens = e.get("capacity"), e.get("seeds"), e.get("censored")
    if not (isinstance(caps, list) and isinstance(seeds, list) and isinstance(cens, list)):
        return False
    if not len(caps) == len(seeds) == len(cens) or not caps:
        return False
    return all(isinstance(c, int | float) and math.isfinite(c) and c > 0 for c in caps)


def published_seeds(doc: dict[str, Any]) -> list[int]:
    if doc["settings"].get("seed_list"):
        return [int(s) for s in doc["settings"]["seed_list"]]
    lo, hi = doc["settings"]["seed_range"]
    return list(range(int(lo), int(hi) + 1))


def entrant_cells(doc: dict[str, Any], conditions: Sequence[str], families: Sequence[str]):  # noqa: ANN201
    """(condition, family, {entrant: cell}) over the given conditions and families."""
    for cond in conditions:
        for fam in families:
            yield cond, fam, doc["cells"][cond][fam]


# --------------------------------------------------------------------------------------
# the published ride comfort
# --------------------------------------------------------------------------------------


def machine() -> dict[str, Any]:
    """What a published run was flown on (provenance: CPUs, platform, Python)."""
    return {
        "cpus": os.cpu_count(),
        "processor": platform.machine(),
        "platform": platform.platform(),
        "python": platform.python_version(),
    }


def comfort_data(
    published: dict[str, Any],
    *,
    command: str | None = None,
    log: Callable[[str], None] | None = None,
    workers: int = 1,
) -> dict[str, Any]:
    """Fly the ride comfort of every entrant of the published table ``published`` on its
    seeds, conditions and distance (each entrant and condition one task on ``workers``
    processes: :func:`~agents.evaluation.comparisons.comfort.ride_table`, the same values
    whatever the number) and return the document :data:`COMFORT_FILE` holds. Refused
    (``ValueError`` naming the components) if the code here does not give the published
    fingerprint: the runs would not be the published benchmark's. ``log`` gets one line
    per condition."""
    from agents.evaluation.backends import check_backend
    from agents.evaluation.comparisons.comfort import SETTLE_S, ride_table

    check_backend("local", workers)

    st = published["settings"]
    diff = differences(fingerprint(st), published["fingerprint"])
    if diff:
        raise ValueError(
            f"this installation differs from the published benchmark {BENCHMARK_VERSION} "
            f"in: {', '.join(diff)}: its comfort runs would not be the published ones"
        )
    seeds, km = published_seeds(published), float(st["distance_km"])
    per, elapsed = ride_table(st["conditions"], st["entrants"], seeds, km, workers=workers, log=log)
    return {
        "benchmark": BENCHMARK_VERSION,
        "quantity": "a_wz_m_s2: ISO 2631-1 W_k-weighted RMS heave acceleration [m/s²] of "
        "one run per entrant, condition and seed (the scenario's own irregularity), after "
        f"the {SETTLE_S:g} s settling time; null: the run touched",
        "command": command or "agents.evaluation.published.comfort_data(load_published())",
        "date": datetime.now(UTC).isoformat(timespec="seconds"),
        "machine": machine(),
        "workers": workers,
        "wall_s": round(elapsed, 1),
        "package_version": _package_version(),
        "commit": _commit(),
        "fingerprint": published["fingerprint"]["digest"],
        "entrants": list(st["entrants"]),
        "conditions": list(st["conditions"]),
        "seeds": seeds,
        "distance_km": km,
        "settle_s": SETTLE_S,
        "a_wz_m_s2": per,
    }


def write_published_comfort(doc: dict[str, Any], path: Path = COMFORT_FILE) -> Path:
    """Write a :func:`comfort_data` document (atomically)."""
    atomic_write_text(path, json.dumps(doc, indent=0, sort_keys=True) + "\n")
    return path


def load_published_comfort(
    path: str | Path = COMFORT_FILE, published: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The published ride comfort, checked (:class:`PublishedDataError` naming the file and
    the field): per condition and entrant one a_wz per seed, each a finite number > 0 or
    null; with ``published`` (the published capacities), also flown for its fingerprint,
    entrants, conditions, seeds and distance."""
    p = Path(path)
    try:
        doc = json.loads(p.read_text())
    except FileNotFoundError:
        raise PublishedDataError(f"{p}: no published ride comfort here") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise PublishedDataError(f"{p}: unreadable ({exc})") from None
    problem = _comfort_problem(doc) or (
        _comfort_mismatch(doc, published) if published is not None else None
    )
    if problem:
        raise PublishedDataError(f"{p}: {problem}")
    return doc


def _comfort_problem(doc: Any) -> str | None:
    if not isinstance(doc, dict):
        return "not a JSON object"
    for key in ("benchmark", "fingerprint", "entrants", "conditions", "seeds", "distance_km",
                "settle_s", "a_wz_m_s2", "command", "date", "machine"):  # fmt: skip
        if key not in doc:
            return f"no {key!r}"
    if doc["benchmark"] != BENCHMARK_VERSION:
        return f"benchmark is {doc['benchmark']!r}, not {BENCHMARK_VERSION!r}"
    seeds = doc["seeds"]
    if not isinstance(seeds, list) or not seeds or not all(type(s) is int for s in seeds):
        return "'seeds' is not a list of integers"
    for key in ("entrants", "conditions"):
        if not isinstance(doc[key], list) or not all(isinstance(x, str) for x in doc[key]):
            return f"{key!r} is not a list of names"
    per = doc["a_wz_m_s2"]
    for cond in doc["conditions"]:
        for lab in doc["entrants"]:
            where = f"a_wz_m_s2.{cond}.{lab}"
            vals = per.get(cond, {}).get(lab) if isinstance(per, dict) else None
            if not isinstance(vals, list):
                return f"no {where}"
            if len(vals) != len(seeds):
                return f"{where} has {len(vals)} values for {len(seeds)} seeds"
            for k, v in enumerate(vals):
                ok = v is None or (
                    isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                    and v > 0
                )  # fmt: skip
                if not ok:
                    return f"{where}[{k}] is {v!r}, not a finite number > 0 or null"
    return None


def _comfort_mismatch(doc: dict[str, Any], published: dict[str, Any]) -> str | None:
    st = published["settings"]
    want = {
        "fingerprint": published["fingerprint"]["digest"],
        "seeds": published_seeds(published),
        "distance_km": float(st["distance_km"]),
    }
    for key, value in want.items():
        if doc[key] != value:
            return (
                f"{key} is {doc[key]!r}, the published capacities' {value!r} (flown for "
                "another benchmark: regenerate it with hyperloop headline --comfort)"
            )
    for key in ("entrants", "conditions"):
        missing = [x for x in st[key] if x not in doc[key]]
        if missing:
            return f"{key} lacks the published {', '.join(missing)}"
    return None
