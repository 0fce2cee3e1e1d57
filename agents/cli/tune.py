"""``hyperloop tune``: choose what the project ships from a scan or a search.

* ``hyperloop tune agent`` — a training preset from a finished agent search (the search
  itself runs with ``hyperloop train --tune``), or the results of a stopped search
  (``--collect``): :mod:`agents.training.tune`;
* ``hyperloop tune pid`` — the PID baseline's pole-placement design, written to
  ``agents/controllers/pid_gains.json``: :mod:`agents.training.tune_pid`;
* ``hyperloop tune preview`` — ``lqr-preview``'s preview weight α on validation seeds,
  written to ``agents/controllers/lqr_preview_weight.json``:
  :mod:`agents.training.tune_preview`.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from agents.cli.common import argv_of, new_parser, run
from agents.cli.options import add_settings, settings_from_args
from agents.invocation import command_line

PID_SETTINGS = ("distance_km", "settle_s")
PID_SETTLE_S = 0.5
"""The PID scan's settling time [s] (its runs are short)."""
PREVIEW_SETTINGS = ("distance_km", "workers")


def comma_floats(text: str) -> list[float]:
    """A comma-separated list of numbers: ``60,80,100``."""
    try:
        return [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected numbers separated by commas, got {text!r}"
        ) from None


def _commas(values: Sequence[float]) -> str:
    return ",".join(f"{v:g}" for v in values)


def _mode(sub: Any, name: str, help: str, description: str) -> argparse.ArgumentParser:
    p = sub.add_parser(
        name,
        help=help,
        description=description,
        allow_abbrev=False,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.set_defaults(mode_parser=p)
    return p


def build_parser(prog: str = "hyperloop tune") -> argparse.ArgumentParser:
    ap = new_parser(
        prog,
        "Choose what the project ships: a training preset from an agent search, the PID\n"
        "baseline's design, the preview weight of lqr-preview.",
    )
    sub = ap.add_subparsers(dest="mode", required=True, metavar="{agent,pid,preview}")

    _agent_mode(sub)
    _pid_mode(sub)
    _preview_mode(sub)
    return ap


def _agent_mode(sub: Any) -> None:
    """``hyperloop tune agent``: a preset from a finished agent search."""
    a = _mode(
        sub,
        "agent",
        "a training preset from a finished agent search (hyperloop train --tune)",
        "Write a training preset from a finished agent search (hyperloop train --tune),\n"
        "or the results of a stopped search (--collect).",
    )
    a.add_argument(
        "results",
        type=Path,
        help="tune_results.json of the search (with --collect: its --tune-out)",
    )
    a.add_argument("--base", help="the preset the search started from")
    a.add_argument("--name", help="name of the new preset")
    a.add_argument(
        "--timesteps",
        type=int,
        default=None,
        help="the new preset's timesteps (default: the base's)",
    )
    a.add_argument(
        "--collect",
        type=int,
        metavar="TRIALS",
        default=None,
        help="write tune_results.json of a stopped search (its --tune-trials)",
    )
    a.add_argument("--tune-seed", type=int, default=0, help="the search's --tune-seed")


def _pid_mode(sub: Any) -> None:
    """``hyperloop tune pid``: the PID baseline's pole-placement scan."""
    from agents.controllers.pid import GAINS_FILE
    from agents.training import tune_pid as tp

    d = tp.PIDScan()
    p = _mode(
        sub,
        "pid",
        "the PID baseline's pole-placement design (agents/controllers/pid_gains.json)",
        "Scan pole-placement designs (ω, ζ, ρ) of the PID baseline: each is checked on\n"
        "the discrete closed loop (spectral radius, both magnet orientations) and scored\n"
        "by the mean RMS gap of short nonlinear runs; the best is written to --gains-file.",
    )
    for flag, values, what in (
        ("--omega", d.omega, "ω grid [rad/s]"),
        ("--zeta", d.zeta, "ζ grid"),
        ("--rho", d.rho, "integral ratio ρ grid"),
    ):
        p.add_argument(
            flag,
            type=comma_floats,
            default=list(values),
            metavar="X,Y,…",
            help=f"{what} (default: {_commas(values)})",
        )
    p.add_argument(
        "--deriv-ratio",
        type=float,
        default=d.deriv_ratio,
        help="derivative filter cut-off / ω (default: %(default)s)",
    )
    p.add_argument(
        "--conditions",
        "--scenarios",
        dest="scenarios",
        nargs="+",
        default=list(d.scenarios),
        metavar="SCENARIO",
        help=f"scenarios of the scoring runs (default: {' '.join(d.scenarios)}, those the "
        "passive vehicle survives)",
    )
    p.add_argument(
        "--seed", type=int, default=d.seed, help="seed of the scoring runs (default: %(default)s)"
    )
    p.add_argument(
        "--max-radius",
        type=float,
        default=d.max_radius,
        help="closed-loop spectral radius a design must stay below (default: %(default)s)",
    )
    add_settings(p, PID_SETTINGS, distance_km=d.distance_km)
    p.set_defaults(settle_s=PID_SETTLE_S)
    p.epilog = f"--settle-s is {PID_SETTLE_S:g} s here unless given (the runs are short)."
    p.add_argument(
        "--gains-file",
        type=Path,
        default=GAINS_FILE,
        metavar="PATH",
        help="where the design is written (default: the package's pid_gains.json)",
    )
    p.add_argument("--dry-run", action="store_true", help="print the table, write nothing")


def _preview_mode(sub: Any) -> None:
    """``hyperloop tune preview``: lqr-preview's preview weight scan."""
    from agents.training import tune_preview as tv

    v = _mode(
        sub,
        "preview",
        "lqr-preview's preview weight α on validation seeds",
        "Scan the preview weight α of lqr-preview: per α the paired roughness capacity\n"
        "ratio against lqr on validation seeds (never evaluation seeds) at the four paper\n"
        "conditions; the best is written to --weight-file.",
    )
    v.add_argument(
        "--weights",
        type=comma_floats,
        default=list(tv.DEFAULT_WEIGHTS),
        metavar="X,Y,…",
        help=f"the α values, in [0, 2] (default: {_commas(tv.DEFAULT_WEIGHTS)})",
    )
    v.add_argument(
        "--validation-seeds",
        type=int,
        default=tv.DEFAULT_SEEDS,
        metavar="N",
        help="validation seeds per condition, >= 2 (default: %(default)s)",
    )
    add_settings(v, PREVIEW_SETTINGS, distance_km=tv.DEFAULT_DISTANCE_KM)
    v.add_argument(
        "--weight-file",
        type=Path,
        default=tv.WEIGHT_FILE,
        metavar="PATH",
        help="where the scan is written (default: the package's lqr_preview_weight.json)",
    )
    v.add_argument("--dry-run", action="store_true", help="print the table, write nothing")


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop tune") -> int:
    ap = build_parser(prog)
    a = ap.parse_args(argv)
    args = argv_of(argv)
    cmd = command_line(prog, args)
    mode = {"agent": _agent, "pid": _pid, "preview": _preview}[a.mode]
    # errors and interrupts name the mode: "hyperloop tune pid: error: …"
    return mode(a, a.mode_parser, a.mode_parser.prog, args[args.index(a.mode) + 1 :], cmd)


def _agent(
    a: argparse.Namespace, ap: argparse.ArgumentParser, prog: str, args: list[str], cmd: str
) -> int:
    from agents.training.tune import collect_search, preset_from_search

    if a.collect is not None:
        rc, doc = run(prog, args, lambda: collect_search(a.results, a.collect, a.tune_seed))
        if rc:
            return rc
        print(
            f"wrote {a.results / 'tune_results.json'}: {doc['trials_finished']} of "
            f"{a.collect} trials finished, best #{doc['best']['index']} "
            f"(score {doc['best']['score']:.3f})"
        )
        return 0
    if not a.base or not a.name:
        ap.error("--base and --name are required (unless --collect)")
    rc, path = run(prog, args, lambda: preset_from_search(a.results, a.base, a.name, a.timesteps))
    if rc:
        return rc
    print(f"wrote {path}")
    return 0


def _pid(
    a: argparse.Namespace, ap: argparse.ArgumentParser, prog: str, args: list[str], cmd: str
) -> int:
    from agents.training import tune_pid as tp

    try:
        st = settings_from_args(a, PID_SETTINGS)
        spec = tp.PIDScan(
            omega=tuple(a.omega),
            zeta=tuple(a.zeta),
            rho=tuple(a.rho),
            deriv_ratio=a.deriv_ratio,
            scenarios=tuple(a.scenarios),
            distance_km=st.distance_km,
            seed=a.seed,
            settle_s=st.settle_s,
            max_radius=a.max_radius,
        )
    except ValueError as exc:
        ap.error(str(exc))

    def show(row: dict[str, Any]) -> None:
        if row["status"] not in ("ok", "contact"):
            return  # rejected before flying
        print(
            f"omega={row['omega_rad_s']:6.1f} zeta={row['zeta']:4.2f} "
            f"rho={row['integral_ratio']:4.2f} radius={max(row['radius'].values()):.4f} "
            f"rms_gap={row['score_rms_gap_mm']:7.4f} mm a_wz={row['a_wz_m_s2']:.3f} m/s2 "
            f"contacts={row['contacts']}",
            flush=True,
        )

    rc, res = run(prog, args, lambda: tp.scan(spec, show))
    if rc:
        return rc
    best = res["best"]
    if best is None:
        print("no design passed", file=sys.stderr)
        return 1
    print(f"best: {best} ({res['wall_s']:.1f} s)")
    if a.dry_run:
        return 0
    doc = tp.gains_document(spec, res["rows"], best, cmd)
    print(f"wrote {tp.write_gains(doc, a.gains_file)}")
    return 0


def _preview(
    a: argparse.Namespace, ap: argparse.ArgumentParser, prog: str, args: list[str], cmd: str
) -> int:
    from agents.training import tune_preview as tv

    try:
        st = settings_from_args(a, PREVIEW_SETTINGS)
        tv.check(a.weights, a.validation_seeds)
    except ValueError as exc:
        ap.error(str(exc))

    def show(row: dict[str, Any]) -> None:
        print(
            f"alpha {row['weight']:.3g}: score {row['score']:+.4f}  "
            + "  ".join(f"{k} {v['ratio']:.3f}" for k, v in row["conditions"].items()),
            flush=True,
        )

    rc, doc = run(
        prog,
        args,
        lambda: tv.scan(a.weights, a.validation_seeds, st.distance_km, cmd, show, st.workers),
    )
    if rc:
        return rc
    best = max(doc["scan"], key=lambda r: r["score"])
    print(f"best alpha {best['weight']:.3g} (score {best['score']:+.4f})")
    if not a.dry_run:
        print(f"wrote {tv.write_weight(doc, a.weight_file)}")
    return 0
