"""Where a buffer starts against the cache lines, and what it costs a batched product.

    python speed/bench_alignment.py [--rows 64] [--repeats 8]

The MPC's condensed prediction ``Z = LW·ξ̃`` (96 × 30 per row, the rows of the batch
innermost: :func:`agents.controllers.lqr.accumulate_rows`) into an output whose data start
0, 16, 32 and 48 bytes past a 64-byte cache line, ``--repeats`` fresh outputs each, in
turn; then into outputs from ``np.zeros`` as NumPy's allocator places them. Printed: the
median time of one product per placement (µs) and, for ``np.zeros``, each output's offset
and time. The products are the same bit for bit at every placement (checked).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from agents.controllers.lqr import accumulate_rows  # noqa: E402
from hyperloop_env.physics.arrays import CACHE_LINE_BYTES, aligned_zeros  # noqa: E402


def placed(shape: tuple[int, int], offset: int) -> np.ndarray:
    """Zeros of ``shape`` whose data start ``offset`` bytes past a cache line."""
    n = shape[0] * shape[1]
    buf = aligned_zeros(n + CACHE_LINE_BYTES // 8)
    return buf[offset // 8 : offset // 8 + n].reshape(shape)


def median_us(fn, calls: int = 600) -> float:  # type: ignore[no-untyped-def]
    t = np.empty(calls)
    for k in range(calls):
        t0 = time.perf_counter_ns()
        fn()
        t[k] = time.perf_counter_ns() - t0
    return float(np.median(t)) / 1e3


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=64, help="rows of the batch (default 64)")
    ap.add_argument("--repeats", type=int, default=8, help="fresh outputs per placement")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(0)
    LW = rng.standard_normal((96, 30))
    xi = aligned_zeros((30, args.rows))
    xi[:] = rng.standard_normal((30, args.rows))
    want = np.zeros((96, args.rows))
    accumulate_rows(LW, xi, want)  # compile and the reference
    print(f"os.cpu_count() = {os.cpu_count()}, load average {os.getloadavg()}")
    print(f"Z = LW·xi, LW 96 x 30, {args.rows} rows; median µs of one product:")
    for offset in (0, 16, 32, 48):
        times = []
        for _ in range(args.repeats):
            Z = placed(want.shape, offset)
            times.append(median_us(lambda Z=Z: accumulate_rows(LW, xi, Z)))
            if not np.array_equal(Z, want):
                raise SystemExit(f"offset {offset}: the product differs")
        print(f"  {offset:2d} bytes past a cache line: {np.median(times):6.1f} µs")
    keep, row = [], []
    for _ in range(args.repeats):
        Z = np.zeros(want.shape)
        keep.append(Z)
        t = median_us(lambda Z=Z: accumulate_rows(LW, xi, Z))
        row.append(f"{Z.ctypes.data % CACHE_LINE_BYTES}: {t:.1f}")
    print("  np.zeros, offset: µs  " + ", ".join(row))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
