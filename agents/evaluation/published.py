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
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import subprocess
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from agents.evaluation.outputs import atomic_write_text

BENCHMARK_VERSION = "hyperloop-suspension-v1"
PUBLISHED_DIR = Path(__file__).with_name("published")
PUBLISHED_FILE = PUBLISHED_DIR / f"{BENCHMARK_VERSION}.json"
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
