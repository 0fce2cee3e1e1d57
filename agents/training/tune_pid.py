"""The PID baseline's design: a grid scan of pole-placement designs (ω, ζ, ρ), the best
one stored in ``agents/controllers/pid_gains.json`` (``hyperloop tune pid``).

Method: every design of the grid is turned into gains by pole placement on the per-unit
model (:func:`agents.controllers.pid.design_pid`), rejected unless the discrete closed loop
of the full 14-state vertical model with coil lag is stable with margin (spectral radius
< ``max_radius`` for both magnet orientations,
:func:`agents.controllers.pid.closed_loop_spectral_radius`), then scored by the mean RMS
gap excursion (after ``settle_s``) of short nonlinear closed-loop runs (``distance_km``
per scenario, seed ``seed``) on the scenarios the passive vehicle survives; a design with a
contact scores infinity. The heave-weighted ISO 2631-1 comfort of each design is recorded
beside the score (not optimised). The best design is written with the command that
produced it (:func:`gains_document`).
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from agents.controllers.pid import GAINS_FILE, PIDDesign

__all__ = [
    "DEFAULT_SCENARIOS",
    "GAINS_FILE",
    "PIDScan",
    "gains_document",
    "scan",
    "write_gains",
]

DEFAULT_SCENARIOS = ("paper-1000-straight", "paper-1000-curved", "paper-2000-straight")
"""The scenarios the passive vehicle survives (its runs score a design)."""
MAGNETS = ("repelling", "attracting")
METHOD = (
    "pole placement on the per-unit model (agents/controllers/pid.py), design chosen by "
    "grid search: closed-loop radius check + min mean RMS gap on short nonlinear runs"
)


@dataclass(frozen=True)
class PIDScan:
    """What one scan flies: the design grid and the scoring runs."""

    omega: tuple[float, ...] = (60, 80, 100, 130)  # ω grid [rad/s]
    zeta: tuple[float, ...] = (0.7, 1.0)  # ζ grid
    rho: tuple[float, ...] = (0.1, 0.2)  # integral ratio ρ grid
    deriv_ratio: float = 5.0  # derivative filter cut-off / ω
    scenarios: tuple[str, ...] = DEFAULT_SCENARIOS
    distance_km: float = 1.0  # per scenario
    seed: int = 100
    settle_s: float = 0.5  # discarded at the start of every run [s]
    max_radius: float = 0.995  # closed-loop spectral radius a design must stay below

    def __post_init__(self) -> None:
        for name in ("omega", "zeta", "rho", "scenarios"):
            value = tuple(getattr(self, name))
            if not value:
                raise ValueError(f"the {name} grid is empty")
            object.__setattr__(self, name, value)
        if not (isinstance(self.distance_km, int | float) and self.distance_km > 0):
            raise ValueError(f"--distance-km must be > 0, got {self.distance_km!r}")


def scan(spec: PIDScan, on_row: Callable[[dict[str, Any]], None] | None = None) -> dict[str, Any]:
    """Score every design of ``spec``'s grid (module docstring). Returns ``{"rows": one
    row per design (ω, ζ, ρ, radii, score [mm] — inf if rejected or touched — comfort,
    contacts, status), "best": the best PIDDesign or None if no design passed, "wall_s"}``;
    ``on_row(row)`` is called after each design is scored (also a rejected one)."""
    from agents.controllers.pid import (
        PIDController,
        closed_loop_spectral_radius,
        design_pid,
    )
    from agents.evaluation.rollout import run_episode
    from hyperloop_env.comfort import weighted_rms

    ctxs = contexts()
    rows: list[dict[str, Any]] = []
    t0 = time.perf_counter()
    for w, z, r in itertools.product(spec.omega, spec.zeta, spec.rho):
        design = PIDDesign(w, z, r, spec.deriv_ratio)
        row: dict[str, Any] = {"omega_rad_s": w, "zeta": z, "integral_ratio": r}
        rows.append(row)
        try:
            radii = {
                m: closed_loop_spectral_radius(c, design_pid(c, design)) for m, c in ctxs.items()
            }
        except ValueError as exc:  # e.g. a non-positive Kp
            row.update(score_rms_gap_mm=math.inf, status=f"rejected ({exc})")
            _call(on_row, row)
            continue
        row["radius"] = radii
        if max(radii.values()) >= spec.max_radius:
            row.update(score_rms_gap_mm=math.inf, status="rejected (closed-loop radius)")
            _call(on_row, row)
            continue
        rms, awz, contacts = [], [], 0
        for sc in spec.scenarios:
            ep = run_episode(
                lambda env, d=design: PIDController(env, design=d), sc, spec.seed, spec.distance_km
            )
            n0 = int(round(spec.settle_s / ep.dt_s))
            g = ep.gap_m[n0:]
            contacts += int(ep.terminated)
            if len(g):
                rms.append(float(np.sqrt(np.mean(g * g))))
                awz.append(weighted_rms(ep.acc_m_s2[:, 0], ep.dt_s, "k", spec.settle_s))
        score = math.inf if contacts or not rms else 1e3 * float(np.mean(rms))
        row.update(
            score_rms_gap_mm=score,
            a_wz_m_s2=float(np.mean(awz)) if awz else math.nan,
            contacts=contacts,
            status="ok" if contacts == 0 else "contact",
        )
        _call(on_row, row)
    ok = [r for r in rows if math.isfinite(r["score_rms_gap_mm"])]
    best = None
    if ok:
        b = min(ok, key=lambda r: r["score_rms_gap_mm"])
        best = PIDDesign(b["omega_rad_s"], b["zeta"], b["integral_ratio"], spec.deriv_ratio)
    return {"rows": rows, "best": best, "wall_s": time.perf_counter() - t0}


def contexts() -> dict[str, Any]:
    """The plant of each magnet orientation (the paper's defaults) a design must stabilise."""
    from agents.controllers.base import control_context
    from hyperloop_env.config import build_config

    return {
        mag: control_context(build_config("paper-1000-straight", magnet=mag).base)
        for mag in MAGNETS
    }


def gains_document(
    spec: PIDScan, rows: Sequence[dict[str, Any]], best: PIDDesign, command: str
) -> dict[str, Any]:
    """The content of ``pid_gains.json``: the method, ``command``, the chosen design, its
    gains for both magnet orientations and the whole scan (non-finite numbers as null)."""
    from agents.controllers.pid import design_pid

    gains = {m: design_pid(c, best).__dict__ for m, c in contexts().items()}
    return {
        "method": METHOD,
        "command": command.strip(),
        "design": best.__dict__,
        "gains_paper_defaults": gains,
        "search": {
            "scenarios": list(spec.scenarios),
            "distance_km": spec.distance_km,
            "seed": spec.seed,
            "settle_s": spec.settle_s,
            "max_radius": spec.max_radius,
            "rows": [
                {
                    k: (v if not (isinstance(v, float) and not math.isfinite(v)) else None)
                    for k, v in r.items()
                }
                for r in rows
            ],
        },
    }


def write_gains(doc: dict[str, Any], out: str | Path = GAINS_FILE) -> Path:
    """Write ``doc`` (:func:`gains_document`) to ``out`` atomically; returns the path."""
    import json

    from agents.evaluation.outputs import atomic_write_text

    atomic_write_text(out, json.dumps(doc, indent=2) + "\n")
    return Path(out)


def _call(on_row: Callable[[dict[str, Any]], None] | None, row: dict[str, Any]) -> None:
    if on_row is not None:
        on_row(row)
