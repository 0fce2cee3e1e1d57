"""What a call of a compiled kernel costs before it runs: numba's type dispatch vs the entry.

    python speed/bench_dispatch.py [--calls 20000] [--rounds 7]

A kernel that does nothing, with 1, 6 and 11 array arguments and an int, called through
its numba dispatcher and through its specialisation
(:func:`hyperloop_env.physics.entry.compiled_entry`), in turn, ``--rounds`` times
``--calls`` calls each: the best round's time per call (µs) and the difference.
"""

from __future__ import annotations

import argparse
import os
import sys
import timeit
from pathlib import Path

import numba as nb
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from hyperloop_env.physics.entry import compiled_entry  # noqa: E402


@nb.njit(_nrt=False)
def _one(a, k):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    return k


@nb.njit(_nrt=False)
def _six(a, b, c, d, e, f, k):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    return k


@nb.njit(_nrt=False)
def _eleven(a, b, c, d, e, f, g, h, i, j, l, k):  # type: ignore[no-untyped-def]  # noqa: E741  # pragma: no cover
    return k


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=20000)
    ap.add_argument("--rounds", type=int, default=7)
    args = ap.parse_args(argv)
    print(f"os.cpu_count() = {os.cpu_count()}, load average {os.getloadavg()}")
    x2, x1 = np.zeros((4, 64)), np.zeros(8)
    i1, f32 = np.zeros(8, dtype=np.int64), np.zeros((64, 4), dtype=np.float32)
    pool = [x2, i1, x1, x2, x2, x1, x2, x2, x2, f32, x2]
    print("array arguments | dispatcher us | entry us | difference us")
    for fn, n in ((_one, 1), (_six, 6), (_eleven, 11)):
        a = (*pool[:n], 0)
        entry = compiled_entry(fn, *a)
        best = {"dispatcher": np.inf, "entry": np.inf}
        for _ in range(args.rounds):
            for name, f in (("dispatcher", fn), ("entry", entry)):
                t = timeit.timeit(lambda f=f, a=a: f(*a), number=args.calls) / args.calls * 1e6
                best[name] = min(best[name], t)
        d, e = best["dispatcher"], best["entry"]
        print(f"{n:>15} | {d:>13.3f} | {e:>8.3f} | {d - e:>13.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
