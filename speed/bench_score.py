"""How long ``hyperloop score`` takes: the quick scope and, with ``--full``, the published
scope (4 conditions × 3 families × 32 seeds), for a controller of the LQR's cost.

    python speed/bench_score.py [--controller lqr] [--full] [--workers 2]

Each run is ``hyperloop score CONTROLLER`` in a fresh process (numba's cache warm: run it
once before timing on a new machine), into a temporary folder. Prints the date, the
machine's CPU count and load average before and after, and the wall time of each scope.
"""

from __future__ import annotations

import argparse
import datetime
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _time(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if done.returncode:
        sys.exit(done.stderr[-2000:])
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--controller", default="lqr")
    ap.add_argument("--full", action="store_true", help="also the full published scope")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    args = ap.parse_args(argv)
    print(f"{datetime.date.today()}, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.2f}")
    scopes = [("quick", ["--quick"])] + ([("full", [])] if args.full else [])
    for name, extra in scopes:
        with tempfile.TemporaryDirectory() as tmp:
            cmd = [sys.executable, "-m", "agents.cli", "score", args.controller, *extra]
            cmd += ["--out", str(Path(tmp) / "s"), "--no-progress", "--no-figures"]
            cmd += ["--workers", str(args.workers)]
            wall = _time(cmd)
        print(f"{name}: {wall:.1f} s ({args.controller}, {args.workers} workers)")
    print(f"load after {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
