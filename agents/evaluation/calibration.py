"""Calibrate the benchmark suite's severity levels on the passive and PID baselines
(``hyperloop calibrate``).

For every family of :data:`GRIDS` it runs the fragility sweep
(:func:`agents.evaluation.fragility.fragility`) of the passive and PID baselines — never a
learned agent — over the four paper conditions on the calibration seeds (from
:data:`~agents.evaluation.seeds.CALIBRATION_SEED0`, disjoint from the training,
validation and evaluation seeds), fits the lognormal fragility functions and chooses three
levels per family: the geometric-mean median capacity of the passive baseline over the
conditions ("low"), of PID ("high"), and their geometric middle ("mid"), each rounded to
two significant digits and clipped to the grid. Families the passive vehicle does not feel
(a coil fault, a sensor dropout act on active control only) are calibrated on PID alone,
on top of a fixed roughness. The chosen levels, the fits and each baseline's contact
probability per 10 km at each level (with the band check: 0.05–0.95 per 10 km, or a
P(unsteady) in 1e-4–0.5) go to the suite file (``agents/evaluation/benchmark_suite.json``
in a checkout) and to ``calibration.md`` / ``calibration.json`` of the output folder, the
sweeps of each family to its ``calibration/<family>/`` folder.

The suite is calibrated once; it is never re-tuned to an agent. :func:`run` calibrates,
:func:`rewrite_suite` rewrites the suite file from a ``calibration.json`` without a run,
:func:`calibration_markdown` renders the report.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from agents.evaluation.outputs import atomic_write_text
from agents.evaluation.seeds import CALIBRATION_SEED0
from agents.evaluation.settings import check_setting

GRIDS: dict[str, dict[str, Any]] = {
    # family: severity grid, baselines, fixed disturbances
    "roughness": {
        "levels": [0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.8],
        "controllers": ["passive", "pid"],
    },
    "pier_settlement": {
        "levels": [0.5e-3, 1e-3, 2e-3, 3e-3, 4e-3, 6e-3],
        "controllers": ["passive", "pid"],
    },
    "joint_steps": {
        "levels": [0.25e-3, 0.5e-3, 1e-3, 1.5e-3, 2e-3, 3e-3],
        "controllers": ["passive", "pid"],
    },
    "thermal_camber": {
        "levels": [2e-3, 4e-3, 6e-3, 8e-3, 12e-3],
        "controllers": ["passive", "pid"],
    },
    # felt only under active control: PID alone, on a guideway as rough as the passive
    # capacity (0.2; below PID's roughness capacity at every paper condition)
    "actuator_fault": {
        "levels": [0.25, 0.5, 0.75, 0.9, 1.0],
        "controllers": ["pid"],
        "fixed": {"roughness": 0.2},
    },
    "sensor_dropout": {
        "levels": [0.05, 0.1, 0.2, 0.4, 0.6, 0.8],
        "controllers": ["pid"],
        "fixed": {"roughness": 0.2},
    },
}
"""Per family: the calibration grid, the baselines and the fixed disturbances."""

DEFAULT_SEEDS = 8
DEFAULT_DISTANCE_KM = 5.0
N_BOOT = 50
"""Bootstrap replicates of the sweeps' STS intervals."""
N_BOOT_FIT = 200
"""Bootstrap replicates of the fragility fits' intervals."""
SWEEPS = "calibration"
"""The folder of the output folder that holds each family's sweep (``<family>/``)."""
FILES = ("calibration.md", "calibration.json")
"""What a calibration writes into the output folder (besides :data:`SWEEPS`)."""
COMMAND = "hyperloop calibrate"

_FAMILY_KEYS = ("grid", "fixed", "controllers", "capacity", "geometric_capacity", "levels")


class CalibrationError(ValueError):
    """A calibration or suite file the calibration cannot use (the message names the file
    and the field)."""


@dataclass(frozen=True)
class CalibrationSpec:
    """What a calibration computes: ``seeds`` calibration seeds from
    :data:`CALIBRATION_SEED0`, ``distance_km`` per run, the ``families`` of ``grids``;
    checked on construction (``ValueError`` naming the flag)."""

    seeds: int = DEFAULT_SEEDS
    distance_km: float = DEFAULT_DISTANCE_KM
    families: tuple[str, ...] = tuple(GRIDS)
    grids: Mapping[str, Mapping[str, Any]] = field(default_factory=lambda: GRIDS)

    def __post_init__(self) -> None:
        if isinstance(self.seeds, bool) or not isinstance(self.seeds, int) or self.seeds < 1:
            raise ValueError(f"--seeds must be an integer >= 1, got {self.seeds!r}")
        v = self.distance_km
        check_setting("distance_km", v, required=True)
        if not self.families:
            raise ValueError("--families: name at least one family")
        unknown = [f for f in self.families if f not in self.grids]
        if unknown:
            raise ValueError(
                f"--families: unknown {unknown}; calibrated families: {list(self.grids)}"
            )
        from agents.evaluation.evaluate import check_settling, episode_configs
        from hyperloop_env.scenarios import PAPER_SCENARIOS

        cfgs = episode_configs(PAPER_SCENARIOS, v, "repelling", None, "--distance-km")
        check_settling(cfgs, 1.0, v, ("--distance-km", "--settle-s"))

    @property
    def seed_list(self) -> list[int]:
        return list(range(CALIBRATION_SEED0, CALIBRATION_SEED0 + self.seeds))

    def command(self) -> str:
        """The command line a report names (the settings that change the results)."""
        return f"{COMMAND} --seeds {self.seeds} --distance-km {self.distance_km}"


def _round2(x: float) -> float:
    return float(f"{x:.2g}")


def calibrate_family(
    family: str,
    grid: Mapping[str, Any],
    seeds: int,
    km: float,
    out: Path,
    *,
    workers: int = 1,
    backend: str = "local",
    address: str | None = None,
    figures: bool = True,
) -> dict[str, Any]:
    """Calibrate one family (module docstring) on ``seeds`` calibration seeds × ``km``;
    its sweep goes to ``out / family`` (replaced)."""
    from agents.evaluation.benchmark_report import capacity_estimate
    from agents.evaluation.fragility import fragility
    from hyperloop_env.scenarios import PAPER_SCENARIOS

    res = fragility(
        grid["controllers"],
        list(PAPER_SCENARIOS),
        family,
        grid["levels"],
        seeds=list(range(CALIBRATION_SEED0, CALIBRATION_SEED0 + seeds)),
        distance_km=km,
        fixed=grid.get("fixed"),
        n_boot=N_BOOT,
        n_boot_fragility=N_BOOT_FIT,
        backend=backend,
        workers=workers,
        address=address,
        out_dir=out / family,
        overwrite=True,
        figures=figures,
        progress=False,
    )
    caps: dict[str, dict[str, float]] = {}
    for f in res["fits"]:
        caps.setdefault(f["controller"], {})[f["condition"]] = capacity_estimate(f["fit"])
    geo = {
        c: float(np.exp(np.mean(np.log([v for v in d.values() if v > 0])))) for c, d in caps.items()
    }
    lo_g, hi_g = min(grid["levels"]), max(grid["levels"])
    if "passive" in geo:
        low, high = geo["passive"], geo["pid"]
    else:  # PID only: its capacity and a level on each side
        low, high = geo["pid"] / 1.5, geo["pid"] * 1.5
    mid = math.sqrt(low * high)
    levels = sorted({_round2(min(max(v, lo_g), hi_g)) for v in (low, mid, high)})
    band = []
    scale = 10.0 / km
    for r in res["levels"]:
        p10 = 1.0 - (1.0 - r["p_contact"]) ** scale  # per run of km → per 10 km
        pu = r.get("p_unsteady")
        in_band = (0.05 <= p10 <= 0.95) or (pu is not None and 1e-4 <= pu <= 0.5)
        band.append(
            {
                "controller": r["controller"],
                "condition": r["condition"],
                "level": r["level"],
                "p_contact_run": r["p_contact"],
                "p_contact_10km": p10,
                "p_unsteady": pu,
                "in_band": bool(in_band),
            }
        )
    return {
        "family": family,
        "grid": list(grid["levels"]),
        "fixed": dict(grid.get("fixed", {})),
        "controllers": list(grid["controllers"]),
        "capacity": caps,
        "geometric_capacity": geo,
        "levels": levels,
        "band": band,
        "report": str(out / family / "report.md"),
    }


def fitting_grid(levels: list[float], lo_g: float, hi_g: float) -> list[float]:
    """The fragility grid of a family: the suite levels and two more on each side, ×/÷ 1.34
    and ×/÷ 1.8 of the outer levels (so a controller better or worse than the baselines
    still has levels around its capacity), two significant digits, inside the family's
    valid range (``lo_g``/``hi_g`` only bound the calibration grid and are not used)."""
    lo, hi = min(levels), max(levels)
    pts = {_round2(lo / 1.8), _round2(lo / 1.34), *levels, _round2(hi * 1.34), _round2(hi * 1.8)}
    return sorted(p for p in pts if p > 0)


def suite_from_calibration(
    cal: dict[str, Any], seeds: int, km: float, wall_s: float | None
) -> dict[str, Any]:
    """The suite file's content from the calibration results (``seeds`` and ``km``: the
    calibration's settings)."""
    fams, excluded = {}, {}
    for f, c in cal.items():
        caps = [v for d in c["capacity"].values() for v in d.values()]
        inside = [v for v in caps if math.isfinite(v) and v < max(c["grid"])]
        if not inside:  # no baseline's capacity lies inside the grid: not a benchmark level
            excluded[f] = (
                "no baseline reaches the measurable band on the calibration grid "
                f"{c['grid']} (capacities {c['capacity']}); see "
                "docs/benchmark/calibration.md"
            )
            continue
        fams[f] = {
            "levels": c["levels"],
            "grid": fitting_grid(c["levels"], min(c["grid"]), max(c["grid"])),
            "fixed": c["fixed"],
            "calibrated_on": c["controllers"],
            "geometric_capacity": c["geometric_capacity"],
        }
    return {
        "description": "benchmark suite: severity levels per disturbance family, calibrated "
        f"on the passive and PID baselines by {COMMAND} "
        "(never on a learned agent); levels = low, mid, high; grid = the "
        "fragility fitting grid",
        "calibration": {
            "seeds": [CALIBRATION_SEED0, CALIBRATION_SEED0 + seeds - 1],
            "distance_km": km,
            "wall_s": wall_s,
        },
        "families": fams,
        "excluded": excluded,
    }


def calibration_markdown(cal: dict[str, Any], command: str, wall_s: float) -> str:
    """``calibration.md``: the levels per family and each baseline's contact probability
    per 10 km at the grid levels, with the band check."""
    md = [
        "# Benchmark suite calibration",
        "",
        f"Command: `{command}` ({wall_s:.0f} s)",
        "",
        "| family | baselines | fixed | passive θ (geo. mean) | PID θ (geo. mean) | suite levels |",
        "|---|---|---|---:|---:|---|",
    ]
    for f, c in cal.items():
        g = c["geometric_capacity"]
        md.append(
            f"| {f} | {', '.join(c['controllers'])} | {c['fixed'] or ''} "
            f"| {g.get('passive', float('nan')):.3g} | {g['pid']:.3g} "
            f"| {', '.join(f'{v:g}' for v in c['levels'])} |"
        )
    md += [
        "",
        "Contact probability per 10 km (from the calibration runs) at the grid levels; "
        "✓ = in the measurable band (0.05–0.95 per 10 km, or P(unsteady) 1e-4–0.5):",
        "",
    ]
    for f, c in cal.items():
        md += [
            f"## {f}",
            "",
            "| controller | condition | level | P(contact) per run "
            "| per 10 km | P(unsteady) | band |",
            "|---|---|---:|---:|---:|---:|---|",
        ]
        for b in c["band"]:
            pu = "n/a" if b["p_unsteady"] is None else f"{b['p_unsteady']:.2g}"
            md.append(
                f"| {b['controller']} | {b['condition']} | {b['level']:g} "
                f"| {b['p_contact_run']:.2f} | {b['p_contact_10km']:.2f} | {pu} "
                f"| {'✓' if b['in_band'] else ''} |"
            )
        md.append("")
    return "\n".join(md) + "\n"


def _read_json(path: Path, what: str) -> Any:
    try:
        return json.loads(Path(path).read_text())
    except FileNotFoundError:
        raise CalibrationError(f"{path}: no such file ({what})") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise CalibrationError(f"{path}: not a readable JSON {what} ({exc})") from None


def read_calibration(path: str | Path) -> dict[str, Any]:
    """A ``calibration.json`` (family → its calibration); :class:`CalibrationError` naming
    the file and the missing field."""
    cal = _read_json(Path(path), "calibration")
    if not isinstance(cal, dict) or not cal:
        raise CalibrationError(f"{path}: a calibration is a JSON object of families")
    for fam, c in cal.items():
        if not isinstance(c, dict):
            raise CalibrationError(f"{path}: {fam!r} is not an object")
        for key in _FAMILY_KEYS:
            if key not in c:
                raise CalibrationError(f"{path}: family {fam!r} has no {key!r}")
        if "pid" not in c["geometric_capacity"]:
            raise CalibrationError(f"{path}: family {fam!r}: no 'pid' in 'geometric_capacity'")
    return cal


def _suite_families(path: Path) -> dict[str, Any]:
    """The families of an existing suite file ({} if there is none)."""
    if not path.exists():
        return {}
    suite = _read_json(path, "benchmark suite")
    fams = suite.get("families", {}) if isinstance(suite, dict) else None
    if not isinstance(fams, dict):
        raise CalibrationError(f"{path}: 'families' must be a mapping")
    return fams


def rewrite_suite(
    calibration_file: str | Path, suite_file: str | Path, seeds: int, km: float
) -> dict[str, Any]:
    """No runs: write the suite file from a ``calibration.json`` (``seeds`` and ``km``:
    the settings that calibration ran with); returns the suite."""
    suite = suite_from_calibration(read_calibration(calibration_file), seeds, km, None)
    atomic_write_text(suite_file, json.dumps(suite, indent=1) + "\n")
    return suite


def run(
    spec: CalibrationSpec,
    out_dir: str | Path,
    suite_file: str | Path,
    *,
    workers: int = 1,
    backend: str = "local",
    address: str | None = None,
    figures: bool = True,
    command: str | None = None,
    log: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Calibrate ``spec.families`` (module docstring) into ``out_dir``: each family's
    sweep in ``calibration/<family>/`` (replaced), ``calibration.md`` and
    ``calibration.json`` (the families of an earlier calibration there kept, those run now
    replaced), and the suite file (its families not calibrated now kept, excluded ones
    removed). ``log`` gets one line per family. Returns ``{"calibration", "suite",
    "paths"}``."""
    out = Path(out_dir)
    suite_path = Path(suite_file)
    prev_file = out / "calibration.json"  # families calibrated by an earlier invocation
    prev = read_calibration(prev_file) if prev_file.exists() else {}
    old = _suite_families(suite_path)  # both read first: a bad file stops before the runs
    t0 = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    cal: dict[str, Any] = {}
    for fam in spec.families:
        t = time.perf_counter()
        cal[fam] = calibrate_family(
            fam,
            spec.grids[fam],
            spec.seeds,
            spec.distance_km,
            out / SWEEPS,
            workers=workers,
            backend=backend,
            address=address,
            figures=figures,
        )
        if log is not None:
            log(f"{fam}: levels {cal[fam]['levels']} ({time.perf_counter() - t:.0f} s)")
    if prev:
        cal = {**{k: v for k, v in prev.items() if k not in cal}, **cal}
        cal = {f: cal[f] for f in [*GRIDS, *spec.grids, *cal] if f in cal}
    wall = time.perf_counter() - t0
    suite = suite_from_calibration(cal, spec.seeds, spec.distance_km, wall)
    suite["families"] = {
        **{k: v for k, v in old.items() if k not in suite["excluded"]},
        **suite["families"],
    }
    atomic_write_text(suite_path, json.dumps(suite, indent=1) + "\n")
    md = calibration_markdown(cal, command or spec.command(), wall)
    atomic_write_text(out / "calibration.md", md)
    atomic_write_text(out / "calibration.json", json.dumps(cal, indent=1, default=str) + "\n")
    return {
        "calibration": cal,
        "suite": suite,
        "paths": {"suite": suite_path, **{name: out / name for name in FILES}},
    }
