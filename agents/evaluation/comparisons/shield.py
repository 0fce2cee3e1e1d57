"""The published effect of the safety filter (:mod:`agents.controllers.shield`): capacity
with and without it, how often it acts, what it costs in ride comfort.

``hyperloop compare shield --capacity reports/shield/headline.json … --out
docs/benchmark/shield`` writes ``shield.json`` and ``shield.md`` from

* **capacity** — ``hyperloop capacity`` runs (their ``headline.json``, on the same seeds and
  settings, combined as ``hyperloop compare target`` combines them) whose entrants are
  the controllers and their ``shielded:`` versions: per condition the median capacity θ of
  both and the ratio shielded / bare paired on the common seeds
  (:func:`agents.evaluation.capacity_stats.compare_paired`), and every learned agent, bare
  and shielded, against every classical entrant of its actuator set (does the filter lift
  a learned agent above the classical designs?);
* **interventions** — flown here: every shielded controller on the same evaluation seeds
  at the scenario's own irregularity (``nominal``) and with the roughness scaled to each
  ``--severity``; per run set the filter's counters (:attr:`Shield.stats
  <agents.controllers.shield.Shield.stats>`: the fraction of vehicle-steps whose action it
  changed, and of those where no action kept the prediction inside the bound) and the
  contacts of the bare and the shielded controller;
* **comfort** — flown here: ISO 2631-1 a_wz of the bare and the shielded controller on the
  same runs (:func:`agents.evaluation.comparisons.comfort.a_wz`, the scenario's own
  irregularity), paired ratio shielded / bare (:func:`~agents.evaluation.comparisons.
  comfort.compare`; below 1: smoother).

Every number in ``shield.md`` comes from this command (nothing typed by hand); it takes the
settings it was run with into both files.
"""

from __future__ import annotations

import json
import math
import platform
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from agents.controllers.registry import SHIELD_PREFIX, controller_spec, unshielded
from agents.evaluation import engine
from agents.evaluation.capacity_stats import compare_paired, on_common_seeds
from agents.evaluation.entrants import entrant_actuators, entrant_label
from agents.evaluation.outputs import atomic_write_text, output_lock
from agents.evaluation.seeds import EVAL_SEED0, check_evaluation_seeds

PAPER = ("paper-1000-straight", "paper-1000-curved", "paper-2000-straight", "paper-2000-curved")
FILES = ("shield.json", "shield.md")
FAMILY = "roughness"


def shielded(label: str) -> str:
    return f"{SHIELD_PREFIX}{label}"


VERDICT_OF_A = {"A above B": "above", "B above A": "below"}


def _paired(caps: dict[str, Any], a: str, b: str) -> dict[str, Any] | None:
    """``a`` against ``b`` on their common seeds (ratio θ_a/θ_b, 95 % interval, verdict
    for ``a``: above, below, equivalent or undecided); None if either did not fly."""
    if a not in caps or b not in caps:
        return None
    ra, rb = caps[a], caps[b]
    r = compare_paired(
        *on_common_seeds(
            (ra["capacity"], ra["censored"], ra["seeds"]),
            (rb["capacity"], rb["censored"], rb["seeds"]),
            a,
            b,
        )
    )
    out = {k: r[k] for k in ("ratio", "lo", "hi", "p_value", "n")}
    out["verdict"] = VERDICT_OF_A.get(r["verdict"], r["verdict"])
    return out


def capacity_effect(runs: Sequence[Path], labels: Sequence[str]) -> dict[str, Any]:
    """Per condition, from the capacity runs ``runs`` (headline.json files flown on the
    same seeds and settings, combined as ``hyperloop compare target`` combines them):
    θ of each entrant with and without the filter, the paired ratio shielded / bare, and
    each learned agent, bare and shielded, against each classical entrant of its actuator
    set, bare and shielded."""
    from agents.evaluation.comparisons.target import load_capacities

    caps, _ = load_capacities(list(runs))
    theta: dict[tuple[str, str], dict[str, Any]] = {}
    for path in runs:
        for c in json.loads(Path(path).read_text())["headline"]["capacities"]:
            if c["family"] == FAMILY:
                theta.setdefault((c["condition"], c["entrant"]), c)
    learned = [lab for lab in labels if _kind(lab) == "learned"]
    classical = [lab for lab in labels if _kind(lab) != "learned"]
    out: dict[str, Any] = {"pairs": [], "learned_vs_classical": []}
    for cond, have in caps.items():
        for lab in labels:
            bare, sh = theta.get((cond, lab)), theta.get((cond, shielded(lab)))
            if bare is None or sh is None:
                continue
            out["pairs"].append(
                {
                    "condition": cond,
                    "entrant": lab,
                    "theta": bare["theta"],
                    "theta_ci": bare["theta_ci"],
                    "theta_shielded": sh["theta"],
                    "theta_shielded_ci": sh["theta_ci"],
                    "shielded_vs_bare": _paired(have, shielded(lab), lab),
                }
            )
        for lab in learned:
            act = entrant_actuators(lab)[1]
            for ref in (c for c in classical if entrant_actuators(c)[1] == act):
                out["learned_vs_classical"].append(
                    {
                        "condition": cond,
                        "learned": lab,
                        "classical": ref,
                        "bare": _paired(have, lab, ref),
                        "shielded": _paired(have, shielded(lab), ref),
                        "both_shielded": _paired(have, shielded(lab), shielded(ref)),
                    }
                )
    return out


def _kind(label: str) -> str:
    spec = controller_spec(entrant_actuators(label)[0])
    return spec.kind if spec is not None else "baseline"


def interventions(
    label: str, condition: str, seeds: Sequence[int], km: float, severity: float | None
) -> dict[str, Any]:
    """Fly ``label`` bare and shielded on ``seeds`` (``severity``: the roughness scaled to
    it, None: the scenario's own irregularity); the filter's counters and both contacts."""
    from agents.evaluation.rollout import episode_config

    base, act = entrant_actuators(label)
    cfg = episode_config(condition, km, None, {"actuators": act})
    dist = None if severity is None else {FAMILY: float(severity)}
    jobs = [engine.Job(int(s), dist) for s in seeds]
    res: dict[str, Any] = {"condition": condition, "entrant": label, "severity": severity}
    for name, key in ((base, "bare"), (shielded(base), "shielded")):
        ctrl = engine.build_controller(name, cfg)
        sched = engine.Jobs(jobs)
        rows = min(len(jobs), 32) if engine.is_batched(ctrl) else 1
        engine.run(ctrl, cfg, rows, sched)
        res[f"contacts_{key}"] = sum(bool(e is not None and e.terminated) for e in sched.ends)
        if key == "shielded":
            res["counters"] = ctrl.counters()
    return res


@dataclass(frozen=True)
class InterventionTask:
    """:func:`interventions` of one entrant on one condition at one severity."""

    label: str
    condition: str
    seeds: tuple[int, ...]
    km: float
    severity: float | None


@dataclass(frozen=True)
class InterventionResult:
    value: dict[str, Any]
    steps: int = 0  # not counted: no progress bar follows these


def run_interventions(task: InterventionTask, progress: Any = None) -> InterventionResult:
    """Run one :class:`InterventionTask` (module level: the workers of
    :func:`~agents.evaluation.backends.run_blocks` call it)."""
    t = task
    return InterventionResult(interventions(t.label, t.condition, t.seeds, t.km, t.severity))


def shielded_label(label: str) -> str:
    """The entrant label of ``label`` with the filter (the same actuators)."""
    base, act = entrant_actuators(label)
    return entrant_label(shielded(base), act)


def comfort_effect(label: str, condition: str, seeds: Sequence[int], km: float) -> dict[str, Any]:
    """a_wz of ``label`` and its shielded version on the same runs, paired."""
    from agents.evaluation.comparisons.comfort import a_wz

    bare = a_wz(label, condition, list(seeds), km)
    sh = a_wz(shielded_label(label), condition, list(seeds), km)
    return comfort_row(label, condition, bare, sh)


def comfort_row(
    label: str, condition: str, bare: list[float | None], sh: list[float | None]
) -> dict[str, Any]:
    """The comfort effect of the filter from the a_wz per seed of ``label`` (``bare``) and
    of its shielded version (``sh``) on the same runs."""
    from agents.evaluation.comparisons.comfort import compare

    kept = [v for v in bare if v is not None]
    kept_sh = [v for v in sh if v is not None]
    return {
        "condition": condition,
        "entrant": label,
        "a_wz_mean_m_s2": float(np.mean(kept)) if kept else None,
        "a_wz_mean_shielded_m_s2": float(np.mean(kept_sh)) if kept_sh else None,
        "shielded_vs_bare": compare(sh, bare),
    }


def _f(x: Any, digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    return f"{x:.{digits}g}"


def _ratio(v: dict[str, Any] | None) -> str:
    if not v or v.get("ratio") is None:
        return "—"
    verdict = VERDICT_OF_A.get(v["verdict"], v["verdict"])
    return f"{_f(v['ratio'])} [{_f(v['lo'])}, {_f(v['hi'])}] {verdict}"


def render(result: dict[str, Any]) -> str:
    """``shield.md`` from ``shield.json``'s content (level-4 headings: it is included in
    ``docs/safety.md``)."""
    s = result["settings"]
    lines = [
        f"Generated {s['date']} on {s['machine']} by `{s['command']}`.",
        "",
        f"Filter: `shielded:<name>`, margin {s['margin_mm']:g} mm (bound = clearance − "
        f"margin), horizon {s['horizon_steps']} control steps. Capacity: "
        f"{', '.join(f'`{c}`' for c in s['capacity'])} "
        f"({s['capacity_seeds']} seeds, {FAMILY}). Interventions and comfort: "
        f"{len(s['seeds'])} seeds ({s['seeds'][0]}–{s['seeds'][-1]}) × "
        f"{s['distance_km']:g} km.",
        "",
        "#### Capacity with and without the filter (θ: median capacity, roughness severity; "
        "ratio shielded / bare paired on common seeds, 95 % interval)",
        "",
        "| condition | entrant | θ bare | θ shielded | shielded / bare |",
        "|---|---|---|---|---|",
    ]
    for p in result["capacity"]["pairs"]:
        lines.append(
            f"| {p['condition']} | {p['entrant']} | {_f(p['theta'])} | "
            f"{_f(p['theta_shielded'])} | {_ratio(p['shielded_vs_bare'])} |"
        )
    lines += [
        "",
        "#### Learned agents against the classical designs of their actuator set "
        "(ratio learned / classical, paired, 95 % interval; verdict for the learned agent)",
        "",
        "| condition | learned | classical | both bare | learned shielded, classical bare | "
        "both shielded |",
        "|---|---|---|---|---|---|",
    ]
    for p in result["capacity"]["learned_vs_classical"]:
        lines.append(
            f"| {p['condition']} | {p['learned']} | {p['classical']} | {_ratio(p['bare'])} | "
            f"{_ratio(p['shielded'])} | {_ratio(p['both_shielded'])} |"
        )
    lines += [
        "",
        "#### How often the filter acts (share of vehicle-steps changed, and where no action "
        "kept the prediction inside the bound — changed or not; contacts of the runs)",
        "",
        "| condition | entrant | roughness | changed | infeasible | contacts bare | "
        "contacts shielded |",
        "|---|---|---|---:|---:|---:|---:|",
    ]
    for r in result["interventions"]:
        c = r["counters"]
        sev = "nominal" if r["severity"] is None else f"{r['severity']:g}"
        lines.append(
            f"| {r['condition']} | {r['entrant']} | {sev} | {100 * c['changed_fraction']:.3g} % "
            f"| {100 * c['infeasible_fraction']:.3g} % | {r['contacts_bare']} | "
            f"{r['contacts_shielded']} |"
        )
    lines += [
        "",
        "#### Ride comfort (ISO 2631-1 a_wz, the scenario's own irregularity; ratio shielded / "
        "bare paired, below 1 smoother; verdict for the shielded controller: above = rougher)",
        "",
        "| condition | entrant | a_wz bare [m/s²] | a_wz shielded [m/s²] | shielded / bare |",
        "|---|---|---|---|---|",
    ]
    for r in result["comfort"]:
        lines.append(
            f"| {r['condition']} | {r['entrant']} | {_f(r['a_wz_mean_m_s2'], 4)} | "
            f"{_f(r['a_wz_mean_shielded_m_s2'], 4)} | {_ratio(r['shielded_vs_bare'])} |"
        )
    return "\n".join(lines) + "\n"


def run(
    capacity: Path | Sequence[Path],
    out: Path,
    *,
    conditions: Sequence[str] = PAPER,
    seeds: int = 8,
    seed0: int = EVAL_SEED0,
    distance_km: float = 3.0,
    severities: Sequence[float] = (0.3,),
    command: str = "",
    overwrite: bool = False,
    workers: int = 1,
) -> dict[str, Any]:
    """The study (module docstring): reads ``capacity`` (one or more headline.json of
    capacity runs on the same seeds), writes ``shield.json`` and ``shield.md`` into
    ``out``, which it holds for the run (:func:`~agents.evaluation.outputs.output_lock`:
    another run there is refused, naming its pid). The intervention runs and the comfort
    runs are tasks on ``workers`` processes of one pool (the same results whatever the
    number)."""
    from agents.evaluation.backends import check_backend, shared_pool

    check_backend("local", workers)
    with output_lock(out, "shield study output directory"), shared_pool(workers):
        return _study(
            capacity, Path(out), conditions, seeds, seed0, distance_km, severities, command,
            overwrite, workers,
        )  # fmt: skip


def _fly_study(
    labels: list[str],
    conditions: Sequence[str],
    seeds: list[int],
    km: float,
    severities: Sequence[float],
    workers: int,
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """The intervention rows (per condition, entrant and severity) and the comfort rows
    (per condition and entrant), in that order, flown as tasks on ``workers`` processes."""
    from agents.evaluation.backends import results_in_order
    from agents.evaluation.comparisons.comfort import ride_table

    tasks = [
        InterventionTask(lab, cond, tuple(seeds), km, sev)
        for cond in conditions
        for lab in labels
        for sev in (None, *severities)
    ]
    inter = [r.value for r in results_in_order(tasks, run_interventions, workers)]
    both = [x for lab in labels for x in (lab, shielded_label(lab))]
    per, _ = ride_table(conditions, both, seeds, km, workers=workers)
    comfort = [
        comfort_row(lab, cond, per[cond][lab], per[cond][shielded_label(lab)])
        for cond in conditions
        for lab in labels
    ]
    return inter, comfort


def _study(
    capacity: Path | Sequence[Path],
    out: Path,
    conditions: Sequence[str],
    seeds: int,
    seed0: int,
    distance_km: float,
    severities: Sequence[float],
    command: str,
    overwrite: bool,
    workers: int = 1,
) -> dict[str, Any]:
    from agents.controllers.shield import ShieldDesign

    if not isinstance(seeds, int) or isinstance(seeds, bool) or seeds < 2:
        raise ValueError(f"seeds must be an int >= 2, got {seeds!r}")
    if not (
        isinstance(distance_km, int | float) and math.isfinite(distance_km) and distance_km > 0
    ):
        raise ValueError(f"distance_km must be a finite number > 0, got {distance_km!r}")
    for v in severities:
        if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
            raise ValueError(f"severities must be finite numbers > 0, got {v!r}")
    out = Path(out)
    files = [out / name for name in FILES]
    if not overwrite and any(f.exists() for f in files):
        raise FileExistsError(f"{out} holds a shield study (pass --overwrite)")
    runs = [Path(capacity)] if isinstance(capacity, str | Path) else [Path(p) for p in capacity]
    heads = [json.loads(p.read_text()) for p in runs]
    entrants = [e for h in heads for e in h["settings"]["entrants"]]
    labels = [e for e in dict.fromkeys(entrants) if not e.startswith(SHIELD_PREFIX)]
    labels = [e for e in labels if shielded(e) in entrants]
    if not labels:
        raise ValueError(
            f"{', '.join(map(str, runs))}: no entrant flew with and without the filter"
        )
    seed_list = list(range(int(seed0), int(seed0) + seeds))
    check_evaluation_seeds([shielded(unshielded(e)) for e in labels], seed_list)
    t0 = time.perf_counter()
    inter, comfort = _fly_study(labels, conditions, seed_list, distance_km, severities, workers)
    d = ShieldDesign()
    result = {
        "settings": {
            "date": time.strftime("%Y-%m-%d"),
            "machine": f"{platform.machine()}, {platform.processor() or platform.system()}",
            "command": command,
            "capacity": [str(p) for p in runs],
            "capacity_seeds": heads[0]["settings"]["seeds"],
            "entrants": labels,
            "conditions": list(conditions),
            "seeds": seed_list,
            "distance_km": distance_km,
            "severities": list(severities),
            "margin_mm": d.margin_mm,
            "horizon_steps": d.horizon_steps,
            "wall_s": time.perf_counter() - t0,
        },
        "capacity": capacity_effect(runs, labels),
        "interventions": inter,
        "comfort": comfort,
    }
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(files[0], json.dumps(result, indent=1) + "\n")
    atomic_write_text(files[1], render(result))
    return result


def render_only(out: Path) -> Path:
    """Rewrite ``shield.md`` from the ``shield.json`` in ``out`` (no flights)."""
    doc = json.loads((Path(out) / FILES[0]).read_text())
    path = Path(out) / FILES[1]
    atomic_write_text(path, render(doc))
    return path
