#!/usr/bin/env python
"""Regenerate the benchmark headline: per-seed capacities of every entrant, the verdict
matrix, docs/benchmark/ and the README's headline block.

    python scripts/headline.py [--seeds 32] [--distance-km 3] [--workers 2]
    python scripts/headline.py --from reports/capacity     # reuse a finished run

The run itself is ``python -m agents.capacity`` (:mod:`agents.evaluation.capacity_benchmark`:
the registry's entrants, ``mpc`` on the first 16 seeds only, the four paper conditions,
the families roughness, pier settlement and thermal camber, evaluation seeds from
1 000 000) into ``reports/capacity`` (``--overwrite`` replaces an older run). Then
``headline.md/json/csv``, the figures and ``cost.md`` (each entrant's worker time,
:func:`agents.evaluation.capacity_benchmark.cost_table`) go to ``docs/benchmark/`` and the
block between ``<!-- headline:start -->`` and ``<!-- headline:end -->`` of README.md is replaced by
:func:`agents.evaluation.capacity_benchmark.readme_block` of ``docs/benchmark/headline.json``
(``tests/test_readme_headline.py`` checks that the two agree).

A source is validated before anything in docs/ is touched: it must hold headline.md,
headline.json (with the four paper conditions) and headline.csv, else nothing is written.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from agents.evaluation.capacity_benchmark import (  # noqa: E402
    DEFAULT_DISTANCE_KM,
    DEFAULT_SEEDS,
    cost_table,
    readme_block,
)
from agents.evaluation.capacity_benchmark import main as capacity_main  # noqa: E402

DOCS = ROOT / "docs" / "benchmark"
START, END = "<!-- headline:start -->", "<!-- headline:end -->"
FILES = ("headline.md", "headline.json", "headline.csv")


def update_readme(readme: Path, doc: dict) -> None:
    text = readme.read_text()
    if START not in text or END not in text:
        raise SystemExit(f"{readme}: no {START} … {END} block")
    head, rest = text.split(START, 1)
    _, tail = rest.split(END, 1)
    tmp = readme.with_name(readme.name + ".tmp")
    tmp.write_text(head + START + "\n" + readme_block(doc) + END + tail)
    os.replace(tmp, readme)


def check_source(src: Path, allow_partial: bool = False) -> dict:
    """The source's headline.json, after checking that every file is there and that it
    covers the four paper conditions (``SystemExit`` naming the problem otherwise)."""
    from hyperloop_env.scenarios import PAPER_SCENARIOS

    for name in FILES:
        if not (src / name).is_file():
            raise SystemExit(
                f"{src / name}: missing; not a finished `python -m agents.capacity` "
                "run (docs/benchmark left as it was)"
            )
    try:
        doc = json.loads((src / "headline.json").read_text())
        conds = doc["settings"]["conditions"]
        doc["headline"]["capacities"]
    except (ValueError, KeyError, TypeError) as exc:
        raise SystemExit(f"{src / 'headline.json'}: not a capacity headline ({exc})") from None
    if not allow_partial and sorted(conds) != sorted(PAPER_SCENARIOS):
        raise SystemExit(
            f"{src / 'headline.json'}: covers {conds}, not the four paper "
            "conditions; pass --allow-partial to publish it anyway"
        )
    return doc


def publish(src: Path, doc: dict) -> None:
    DOCS.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=".headline-", dir=DOCS))
    for name in FILES:
        shutil.copy2(src / name, staging / name)
    (staging / "figures").mkdir()
    for png in sorted((src / "figures").glob("*.png")):
        shutil.copy2(png, staging / "figures" / png.name)
    for name in FILES:
        os.replace(staging / name, DOCS / name)
    old = DOCS / "figures"
    if old.exists():
        shutil.rmtree(old)
    os.replace(staging / "figures", old)
    shutil.rmtree(staging)
    if doc["settings"].get("tasks"):  # what each entrant cost (README, "The run behind")
        tmp = DOCS / "cost.md.tmp"
        tmp.write_text(cost_table(doc))
        os.replace(tmp, DOCS / "cost.md")
    update_readme(ROOT / "README.md", doc)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--from",
        dest="src",
        type=Path,
        default=None,
        help="a finished `python -m agents.capacity` output directory",
    )
    ap.add_argument("--out", type=Path, default=Path("reports") / "capacity")
    ap.add_argument("--seeds", type=int, default=DEFAULT_SEEDS)
    ap.add_argument("--distance-km", type=float, default=DEFAULT_DISTANCE_KM)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--overwrite", action="store_true")
    ap.add_argument(
        "--allow-partial",
        action="store_true",
        help="publish a run that does not cover the four paper conditions",
    )
    args = ap.parse_args(argv)
    src = args.src
    if src is None:
        rc = capacity_main(
            [
                "--out",
                str(args.out),
                "--seeds",
                str(args.seeds),
                "--distance-km",
                str(args.distance_km),
                "--workers",
                str(args.workers),
                *(["--overwrite"] if args.overwrite else []),
            ]
        )
        if rc:
            return rc
        src = args.out
    doc = check_source(src, args.allow_partial)
    publish(src, doc)
    print(f"docs/benchmark/ and README.md updated from {src}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
