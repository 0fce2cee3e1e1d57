"""The main job, ``python train.py`` (the preset ``default``: PPO's updates overlapped on a
second process, ``agents/training/overlap.py``), against the built-in defaults it started
from (``--preset agents/training/presets/defaults.json``: plain Stable-Baselines3 PPO on
one core), in turn: wall time, CPU use and what the agent learned.

    python speed/bench_main_job.py [--seeds 21 22 23] [--timesteps 1000000]
        [--out /tmp/main-job] [--extra=ARG ...] [--only main|defaults]

For each training seed it runs ``train.py --seed S --out OUT/<variant>-S --overwrite
--no-progress`` once as it is and once with ``--preset <defaults.json>`` (alternating which
goes first from seed to seed), each as a child process, and prints per run: the whole
command's wall time, its CPU use (children's user + system time over wall time, as
``/usr/bin/time`` reports it), the training's wall time (``training_log.json``), and the
trained agent's mean RMS gap excursion over the final report's four paper conditions
(``report/summary.csv``) and its contacts. Then the paired differences (main − defaults) of
the RMS gap over the seeds, and the ratio of the wall times pair by pair. Seeds other than
the default 0 keep the comparison off the run the defaults were chosen on; the report's
evaluation seeds are its own (outside the training range).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULTS = ROOT / "agents" / "training" / "presets" / "defaults.json"


def _children_cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(seed: int, main: bool, out: Path, timesteps: int, extra: list[str]) -> dict:
    """One ``train.py`` run; its times and its agent's RMS gap (module docstring)."""
    run_dir = out / f"{'main' if main else 'defaults'}-{seed}"
    cmd = [
        sys.executable,
        str(ROOT / "train.py"),
        "--seed",
        str(seed),
        "--timesteps",
        str(timesteps),
        "--out",
        str(run_dir),
        "--overwrite",
        "--no-progress",
        *([] if main else ["--preset", str(DEFAULTS)]),
        *extra,
    ]
    cpu0, t0 = _children_cpu_s(), time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - t0, _children_cpu_s() - cpu0
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{proc.stdout[-2000:]}{proc.stderr[-2000:]}")
    log = json.loads((run_dir / "training_log.json").read_text())
    gaps, contacts = [], 0
    with open(run_dir / "report" / "summary.csv", newline="") as f:
        for row in csv.DictReader(f):
            if row["controller"] == str(run_dir):
                gaps.append(float(row["rms_gap_mm"]))
                contacts += int(row["n_contact_episodes"])
    if not gaps:
        raise SystemExit(f"{run_dir}/report/summary.csv has no row for the trained agent")
    return {
        "seed": seed,
        "main": main,
        "wall_s": wall,
        "cpu_percent": 100.0 * cpu / wall,
        "training_s": float(log["wall_time_s"]),
        "rms_gap_mm": statistics.fmean(gaps),
        "contacts": contacts,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[21, 22, 23])
    ap.add_argument("--timesteps", type=int, default=1_000_000)
    ap.add_argument("--out", type=Path, default=Path("/tmp/main-job"))
    ap.add_argument(
        "--extra",
        action="append",
        default=[],
        help="one more train.py argument (repeatable: --extra=--preset --extra=FILE)",
    )
    ap.add_argument(
        "--only",
        choices=("main", "defaults"),
        help="run only this variant (no paired comparison)",
    )
    args = ap.parse_args(argv)
    print(
        f"{time.strftime('%Y-%m-%d %H:%M')}, os.cpu_count() = {os.cpu_count()}, "
        f"load average {os.getloadavg()}",
        flush=True,
    )
    rows = []
    for k, seed in enumerate(args.seeds):
        order = (k % 2 == 0, k % 2 == 1)  # alternate which variant runs first
        for main in order if args.only is None else (args.only == "main",):
            r = run(seed, main, args.out, args.timesteps, args.extra)
            rows.append(r)
            print(
                f"seed {seed:>4} {'main    ' if main else 'defaults'}: "
                f"{r['wall_s']:6.1f} s wall at {r['cpu_percent']:3.0f} % CPU, training "
                f"{r['training_s']:5.1f} s; agent: mean RMS gap {r['rms_gap_mm']:.3f} mm, "
                f"{r['contacts']} contact episode(s)  (load {os.getloadavg()[0]:.1f})",
                flush=True,
            )
    if args.only is not None:
        return 0
    by = {(r["seed"], r["main"]): r for r in rows}
    diffs = [by[s, True]["rms_gap_mm"] - by[s, False]["rms_gap_mm"] for s in args.seeds]
    ratios = [by[s, True]["wall_s"] / by[s, False]["wall_s"] for s in args.seeds]
    print(
        "main - defaults, mean RMS gap [mm], seed by seed: "
        + ", ".join(f"{d:+.3f}" for d in diffs)
        + f"; wall time main / defaults: {', '.join(f'x{x:.2f}' for x in ratios)} "
        f"(median x{statistics.median(ratios):.2f})"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
