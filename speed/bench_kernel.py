"""Per-core speed of the bare batched physics kernel against an earlier commit's kernel.

    python speed/bench_kernel.py [--base c7715c1] [--batch 64] [--steps 200] [--rounds 15]

Both kernels run in this process on ONE thread (numba.set_num_threads(1)) on the same batch
(default parameters, seeds 0..N-1, constant nominal currents): the earlier commit's
``hyperloop_env/physics`` is extracted with ``git show`` into a temporary package (its
imports renamed), and the two kernels are timed in alternation, ``--steps`` control steps a
block, ``--rounds`` blocks each. Per core means the CPU time of this thread
(``time.thread_time``: time spent waiting for a busy core is not counted); wall-clock
figures are printed beside it. The ratio is taken block pair by block pair; the median is
the figure to quote (the spread says how noisy the machine was). The last lines compare the
two trajectories: identical bits, or the largest gap-excursion difference.

What is timed is ``BatchSimulator.step_full(commands)`` (the compiled batch kernel, no
Python command checks); compilation is cached on disk and done before timing.
"""

from __future__ import annotations

import argparse
import importlib
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

REPO = Path(__file__).resolve().parent.parent
PKG = "hyperloop_env/physics"


def extract_base(commit: str) -> str:
    """Write ``commit``'s physics package as a top-level package; return its module name."""
    sha = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", "--short=12", commit],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    name = f"_hl_physics_{sha}"
    root = Path(tempfile.gettempdir()) / "hyperloop_bench_kernel"
    dest = root / name
    if not (dest / "__init__.py").exists():
        files = subprocess.run(
            ["git", "-C", str(REPO), "ls-tree", "--name-only", sha, PKG + "/"],
            check=True,
            capture_output=True,
            text=True,
        ).stdout.split()
        tmp = root / (name + f".tmp{os.getpid()}")
        tmp.mkdir(parents=True, exist_ok=True)
        for f in files:
            if not f.endswith(".py"):
                continue
            src = subprocess.run(
                ["git", "-C", str(REPO), "show", f"{sha}:{f}"],
                check=True,
                capture_output=True,
                text=True,
            ).stdout
            src = re.sub(r"\bhyperloop_env\.physics\b", name, src)
            (tmp / Path(f).name).write_text(src)
        try:
            tmp.rename(dest)
        except OSError:  # another run extracted it meanwhile
            pass
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))
    return name


def make_batch(mod, n: int):  # noqa: ANN001, ANN201
    b = mod.BatchSimulator(mod.ModelParams(), n=n)
    b.reset(list(range(n)))
    cmd = b.full_commands(np.repeat(b.nominal_current_A[:, None], 4, axis=1)).copy()
    return b, cmd


def timed(b, cmd: np.ndarray, steps: int) -> tuple[float, float]:  # noqa: ANN001
    """(thread CPU seconds, wall seconds) of ``steps`` batch steps."""
    c, t = time.thread_time(), time.perf_counter()
    for _ in range(steps):
        b.step_full(cmd)
    return time.thread_time() - c, time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", default="c7715c1", help="commit of the reference kernel")
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--steps", type=int, default=200, help="control steps per timed block")
    ap.add_argument("--rounds", type=int, default=15, help="timed blocks per kernel")
    ap.add_argument("--check-steps", type=int, default=2000, help="steps of the comparison")
    args = ap.parse_args()

    numba.set_num_threads(1)
    import hyperloop_env.physics as new

    base = importlib.import_module(extract_base(args.base))
    print(
        f"cores: os.cpu_count() = {os.cpu_count()}; numba threads used = "
        f"{numba.get_num_threads()}; batch {args.batch}, {args.steps} steps a block, "
        f"{args.rounds} blocks each, base {args.base}"
    )
    bn, cn = make_batch(new, args.batch)
    bb, cb = make_batch(base, args.batch)
    timed(bn, cn, 20)  # compile / warm up
    timed(bb, cb, 20)
    cpu = {"new": [], "base": []}
    wall = {"new": [], "base": []}
    for r in range(args.rounds):
        order = (("new", bn, cn), ("base", bb, cb))
        for name, b, c in order if r % 2 == 0 else order[::-1]:
            tc, tw = timed(b, c, args.steps)
            cpu[name].append(tc)
            wall[name].append(tw)
    vs = args.batch * args.steps
    for clock, t in (("CPU", cpu), ("wall", wall)):
        ratios = [b / n for b, n in zip(t["base"], t["new"], strict=True)]
        print(
            f"{clock:4s}: base {vs / statistics.median(t['base']):8.0f}, this "
            f"{vs / statistics.median(t['new']):8.0f} vehicle-steps/s (medians); speed-up "
            f"pair by pair: median x{statistics.median(ratios):.2f} "
            f"[min x{min(ratios):.2f}, max x{max(ratios):.2f}]"
        )

    # same run from reset: are the trajectories the same?
    bn, cn = make_batch(new, args.batch)
    bb, cb = make_batch(base, args.batch)
    diff = 0.0
    same = True
    for _ in range(args.check_steps):
        mn = bn.step_full(cn)
        mb = bb.step_full(cb)
        if same and not np.array_equal(mn, mb, equal_nan=True):
            same = False
        gap = slice(0, 4)
        diff = max(diff, float(np.max(np.abs(mn[:, gap] - mb[:, gap]))))
    print(
        f"trajectories over {args.check_steps} steps: "
        + (
            "bit-identical records and states"
            if same and np.array_equal(bn.Y, bb.Y)
            else f"differ; largest gap-excursion difference {diff:.3e} m"
        )
    )


if __name__ == "__main__":
    main()
