#!/usr/bin/env python
"""Regenerate the benchmark headline: run the suite, copy the results to docs/benchmark/
and rewrite the README's headline table.

    python scripts/headline.py [--seeds 8] [--distance-km 4] [--workers 2]
    python scripts/headline.py --from reports/benchmark     # reuse a finished run

The run itself is ``python -m agents.benchmark`` (the families of ``HEADLINE_FAMILIES``:
roughness, pier settlement, thermal camber; the entrants passive,
pid, lqr, ppo, pid+g, lqr+g, ppo-guidance, the four paper conditions, evaluation seeds from
1 000 000) into ``reports/benchmark`` (``--overwrite`` replaces an older run). Then
``headline.md/json/csv`` and the fragility figures go to ``docs/benchmark/`` and the block
between ``<!-- headline:start -->`` and ``<!-- headline:end -->`` of README.md is replaced
by :func:`agents.evaluation.benchmark.readme_table` of ``docs/benchmark/headline.json``
(``tests/test_readme_headline.py`` checks that the two agree).
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from agents.evaluation.benchmark import (  # noqa: E402
    DEFAULT_DISTANCE_KM,
    DEFAULT_SEEDS,
    HEADLINE_FAMILIES,
    readme_table,
    target_lines,
)
from agents.evaluation.benchmark import main as benchmark_main  # noqa: E402

DOCS = ROOT / "docs" / "benchmark"
START, END = "<!-- headline:start -->", "<!-- headline:end -->"


def readme_block(doc: dict) -> str:
    fams = doc["settings"]["families"]
    targets = target_lines(doc["headline"], fams)
    return readme_table(doc["headline"], fams) + (
        "\nTargets (checked from `docs/benchmark/headline.json` by "
        "`agents.evaluation.benchmark.target_lines`):\n\n" + targets if targets else "")


def update_readme(readme: Path, doc: dict) -> None:
    text = readme.read_text()
    if START not in text or END not in text:
        raise SystemExit(f"{readme}: no {START} … {END} block")
    head, rest = text.split(START, 1)
    _, tail = rest.split(END, 1)
    readme.write_text(head + START + "\n" + readme_block(doc) + END + tail)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--from", dest="src", type=Path, default=None,
                    help="a finished `python -m agents.benchmark` output directory")
    ap.add_argument("--out", type=Path, default=ROOT / "reports" / "benchmark")
    ap.add_argument("--seeds", type=int, default=DEFAULT_SEEDS)
    ap.add_argument("--distance-km", type=float, default=DEFAULT_DISTANCE_KM)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--overwrite", action="store_true")
    args = ap.parse_args(argv)
    src = args.src
    if src is None:
        rc = benchmark_main(["--out", str(args.out), "--seeds", str(args.seeds),
                             "--distance-km", str(args.distance_km),
                             "--workers", str(args.workers),
                             "--families", *HEADLINE_FAMILIES,
                             *(["--overwrite"] if args.overwrite else [])])
        if rc:
            return rc
        src = args.out
    DOCS.mkdir(parents=True, exist_ok=True)
    for name in ("headline.md", "headline.json", "headline.csv"):
        shutil.copy2(src / name, DOCS / name)
    figs = DOCS / "figures"
    if figs.exists():
        shutil.rmtree(figs)
    for png in sorted(src.glob("*/*/figures/*.png")):
        fam, act = png.parts[-4], png.parts[-3]
        dest = figs / f"{fam}-{act}-{png.name}"
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(png, dest)
    doc = json.loads((DOCS / "headline.json").read_text())
    update_readme(ROOT / "README.md", doc)
    print(f"docs/benchmark/ and README.md updated from {src}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
