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
import shutil
import sys
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


def readme_text(readme: Path, doc: dict) -> str:
    """README.md with its headline block replaced by :func:`readme_block` of ``doc``."""
    text = readme.read_text()
    if START not in text or END not in text:
        raise SystemExit(f"{readme}: no {START} … {END} block")
    head, rest = text.split(START, 1)
    _, tail = rest.split(END, 1)
    return head + START + "\n" + readme_block(doc) + END + tail


def check_source(src: Path, allow_partial: bool = False) -> dict:
    """The source's headline.json, after checking that every file is there, that it
    covers the four paper conditions and that the README block, the cost table and the
    figures can be made from it (``SystemExit`` naming the file and the problem
    otherwise; nothing in docs/ or README.md is touched)."""
    from hyperloop_env.scenarios import PAPER_SCENARIOS

    for name in FILES:
        if not (src / name).is_file():
            raise SystemExit(
                f"{src / name}: missing; not a finished `python -m agents.capacity` "
                "run (docs/benchmark left as it was)"
            )
    f = src / "headline.json"
    try:
        doc = json.loads(f.read_text())
        conds = doc["settings"]["conditions"]
        doc["headline"]["capacities"]
    except (ValueError, KeyError, TypeError) as exc:
        raise SystemExit(f"{f}: not a capacity headline ({exc!r})") from None
    if not allow_partial and sorted(conds) != sorted(PAPER_SCENARIOS):
        raise SystemExit(
            f"{f}: covers {conds}, not the four paper "
            "conditions; pass --allow-partial to publish it anyway"
        )
    if not (src / "figures").is_dir() or not any((src / "figures").glob("*.png")):
        raise SystemExit(f"{src / 'figures'}: no figures (docs/benchmark left as it was)")
    try:
        readme_block(doc)
        if doc["settings"].get("tasks"):
            cost_table(doc)
    except (ValueError, KeyError, TypeError, IndexError, AttributeError) as exc:
        raise SystemExit(
            f"{f}: incomplete, the README block or the cost table cannot be made from it "
            f"({type(exc).__name__}: {exc}); docs/benchmark left as it was"
        ) from None
    return doc


def publish(src: Path, doc: dict) -> None:
    """Copy the report into docs/benchmark/ and update the README's block. Everything is
    made first (the staged files, the cost table, the new README); then the files are
    moved in with SIGINT and SIGTERM held back, the README last."""
    from agents.evaluation.outputs import atomic_write_text, publish_report

    DOCS.mkdir(parents=True, exist_ok=True)
    readme = readme_text(ROOT / "README.md", doc)
    names = ["figures", *(["cost.md"] if doc["settings"].get("tasks") else []), *FILES]
    with publish_report(DOCS, names) as staging:
        for name in FILES:
            shutil.copy2(src / name, staging / name)
        (staging / "figures").mkdir()
        for png in sorted((src / "figures").glob("*.png")):
            shutil.copy2(png, staging / "figures" / png.name)
        if "cost.md" in names:  # what each entrant cost (README, "The run behind")
            (staging / "cost.md").write_text(cost_table(doc))
    atomic_write_text(ROOT / "README.md", readme)


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
