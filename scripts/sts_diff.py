"""Two capacity tasks' per-level STS side by side (files of
``python speed/bench_capacity_task.py --sts-json PATH``, e.g. from two checkouts).

    python scripts/sts_diff.py A.json B.json [--rel 1e-3]

Prints every cell whose chosen law (or any other non-numeric field) differs, every
P(unsteady) value (``p_unsteady``, ``p_unsteady_fit``, their intervals) that differs by
more than ``--rel`` relative, and a summary: the values that differ at all and the largest
relative difference. Exit status 1 if a law or another non-numeric field differs.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any


def _walk(a: Any, b: Any, path: str, out: dict[str, Any], rel: float) -> None:
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            _walk(a.get(k), b.get(k), f"{path}/{k}", out, rel)
    elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (u, v) in enumerate(zip(a, b, strict=True)):
            _walk(u, v, f"{path}/{i}", out, rel)
    elif isinstance(a, int | float) and isinstance(b, int | float) and not isinstance(a, bool):
        if a != b and "p_unsteady" in path:
            r = abs(a - b) / max(abs(a), abs(b))
            out["n"] += 1
            out["worst"] = max(out["worst"], r)
            if r > rel:
                print(f"{path}: {a!r} vs {b!r} ({r:.2e} relative)")
    elif a != b:
        out["other"] += 1
        print(f"DIFFERS {path}: {a!r} vs {b!r}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("a", type=Path)
    ap.add_argument("b", type=Path)
    ap.add_argument("--rel", type=float, default=1e-3, help="print P values differing more")
    args = ap.parse_args(argv)
    docs = []
    for p in (args.a, args.b):
        try:
            docs.append(json.loads(p.read_text()))
        except (OSError, ValueError) as exc:
            raise SystemExit(f"error: {p}: {exc}") from None
    out = {"n": 0, "worst": 0.0, "other": 0}
    _walk(docs[0], docs[1], "", out, args.rel)
    print(
        f"P(unsteady) values differing: {out['n']}, largest relative difference "
        f"{out['worst']:.2e}; other fields differing (laws, units): {out['other']}"
    )
    return 1 if out["other"] else 0


if __name__ == "__main__":
    sys.exit(main())
