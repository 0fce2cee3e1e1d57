"""Choose the PID pole-placement design (ω, ζ, ρ) and store it in agents/pid_gains.json.

Method: every design of a small grid is turned into gains by pole placement on the
per-unit model (:func:`agents.controllers.pid.design_pid`), rejected unless the discrete closed loop
of the full 14-state vertical model with coil lag is stable with margin (spectral radius
< ``--max-radius`` for both magnet orientations, see
:func:`agents.controllers.pid.closed_loop_spectral_radius`), then scored by the mean RMS gap
excursion (after ``--settle-s``) of short nonlinear closed-loop runs (``--distance-km`` per
scenario, seed ``--seed``) on the scenarios that the passive vehicle survives. The heave-weighted
ISO 2631-1 comfort of each design is recorded beside the score (not optimised: see the
report). The best design is written with the command line that produced it.

    python scripts/tune_pid.py                      # default grid, writes agents/pid_gains.json
    python scripts/tune_pid.py --dry-run            # print the table only
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import shlex
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from agents.controllers.base import control_context  # noqa: E402
from agents.controllers.pid import (  # noqa: E402
    GAINS_FILE,
    PIDController,
    PIDDesign,
    closed_loop_spectral_radius,
    design_pid,
)
from agents.evaluation.rollout import run_episode  # noqa: E402
from hyperloop_env.comfort import weighted_rms  # noqa: E402
from hyperloop_env.config import build_config  # noqa: E402

DEFAULT_SCENARIOS = ("paper-1000-straight", "paper-1000-curved", "paper-2000-straight")


def _floats(text: str) -> list[float]:
    return [float(x) for x in text.split(",") if x.strip()]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--omega", type=_floats, default=[60, 80, 100, 130], help="ω grid [rad/s]")
    ap.add_argument("--zeta", type=_floats, default=[0.7, 1.0], help="ζ grid")
    ap.add_argument("--rho", type=_floats, default=[0.1, 0.2], help="integral ratio ρ grid")
    ap.add_argument("--deriv-ratio", type=float, default=5.0, help="derivative filter ratio")
    ap.add_argument("--scenarios", nargs="+", default=list(DEFAULT_SCENARIOS))
    ap.add_argument("--distance-km", type=float, default=1.0)
    ap.add_argument("--seed", type=int, default=100)
    ap.add_argument("--settle-s", type=float, default=0.5)
    ap.add_argument("--max-radius", type=float, default=0.995)
    ap.add_argument("--out", type=Path, default=GAINS_FILE)
    ap.add_argument("--dry-run", action="store_true")
    args = ap.parse_args(argv)
    if args.distance_km <= 0:
        ap.error("--distance-km must be > 0")

    ctxs = {
        mag: control_context(build_config("paper-1000-straight", magnet=mag).base)
        for mag in ("repelling", "attracting")
    }
    rows = []
    t0 = time.perf_counter()
    for w, z, r in itertools.product(args.omega, args.zeta, args.rho):
        design = PIDDesign(w, z, r, args.deriv_ratio)
        row: dict = {"omega_rad_s": w, "zeta": z, "integral_ratio": r}
        try:
            radii = {
                m: closed_loop_spectral_radius(c, design_pid(c, design)) for m, c in ctxs.items()
            }
        except ValueError as exc:  # e.g. a non-positive Kp
            row.update(score_rms_gap_mm=math.inf, status=f"rejected ({exc})")
            rows.append(row)
            continue
        row["radius"] = radii
        if max(radii.values()) >= args.max_radius:
            row.update(score_rms_gap_mm=math.inf, status="rejected (closed-loop radius)")
            rows.append(row)
            continue
        rms, awz, contacts = [], [], 0
        for sc in args.scenarios:
            ep = run_episode(
                lambda env, d=design: PIDController(env, design=d), sc, args.seed, args.distance_km
            )
            n0 = int(round(args.settle_s / ep.dt_s))
            g = ep.gap_m[n0:]
            contacts += int(ep.terminated)
            if len(g):
                rms.append(float(np.sqrt(np.mean(g * g))))
                awz.append(weighted_rms(ep.acc_m_s2[:, 0], ep.dt_s, "k", args.settle_s))
        score = math.inf if contacts or not rms else 1e3 * float(np.mean(rms))
        row.update(
            score_rms_gap_mm=score,
            a_wz_m_s2=float(np.mean(awz)) if awz else math.nan,
            contacts=contacts,
            status="ok" if contacts == 0 else "contact",
        )
        rows.append(row)
        print(
            f"omega={w:6.1f} zeta={z:4.2f} rho={r:4.2f} radius={max(radii.values()):.4f} "
            f"rms_gap={score:7.4f} mm a_wz={row['a_wz_m_s2']:.3f} m/s2 contacts={contacts}",
            flush=True,
        )
    ok = [r for r in rows if math.isfinite(r["score_rms_gap_mm"])]
    if not ok:
        print("no design passed", file=sys.stderr)
        return 1
    best = min(ok, key=lambda r: r["score_rms_gap_mm"])
    design = PIDDesign(best["omega_rad_s"], best["zeta"], best["integral_ratio"], args.deriv_ratio)
    print(f"best: {design} ({time.perf_counter() - t0:.1f} s)")
    if args.dry_run:
        return 0
    gains = {m: design_pid(c, design).__dict__ for m, c in ctxs.items()}
    cmd = "python scripts/tune_pid.py " + " ".join(shlex.quote(a) for a in (argv or sys.argv[1:]))
    payload = {
        "method": "pole placement on the per-unit model (agents/controllers/pid.py), design "
        "chosen by grid search: closed-loop radius check + min mean RMS gap on short "
        "nonlinear runs",
        "command": cmd.strip(),
        "design": design.__dict__,
        "gains_paper_defaults": gains,
        "search": {
            "scenarios": args.scenarios,
            "distance_km": args.distance_km,
            "seed": args.seed,
            "settle_s": args.settle_s,
            "max_radius": args.max_radius,
            "rows": [
                {
                    k: (v if not (isinstance(v, float) and not math.isfinite(v)) else None)
                    for k, v in r.items()
                }
                for r in rows
            ],
        },
    }
    args.out.write_text(json.dumps(payload, indent=2) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
