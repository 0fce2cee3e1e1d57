"""``hyperloop headline``: regenerate the benchmark headline — run ``hyperloop capacity``
with the headline's settings (or take a finished run, ``--from``) and publish it into
``docs/benchmark/`` and the README's headline block
(:mod:`agents.evaluation.headline_publish`). Run it from a checkout."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from agents.cli.common import new_parser
from agents.cli.options import add_settings
from agents.evaluation.capacity_benchmark import DEFAULT_DISTANCE_KM, DEFAULT_SEEDS

FORWARDED = ("seeds", "distance_km", "workers", "out", "overwrite", "resume")
"""The shared settings a new run passes on to ``hyperloop capacity``."""


def build_parser(prog: str = "hyperloop headline") -> argparse.ArgumentParser:
    ap = new_parser(prog, __doc__.split("\n\n")[0].replace("``", ""))
    ap.add_argument(
        "--from",
        dest="src",
        type=Path,
        default=None,
        help="a finished `hyperloop capacity` output folder (no new run)",
    )
    add_settings(  # forwarded to hyperloop capacity
        ap, FORWARDED, seeds=DEFAULT_SEEDS, distance_km=DEFAULT_DISTANCE_KM,
        out=Path("reports") / "capacity",
    )  # fmt: skip
    ap.add_argument(
        "--allow-partial",
        action="store_true",
        help="publish a run that does not cover the four paper conditions",
    )
    ap.add_argument(
        "--comfort",
        action="store_true",
        help="only fly the published entrants' ride comfort (a_wz on the published seeds, "
        "conditions and distance, each entrant and condition one task on --workers "
        "processes) and write it beside the published capacities (the package data that "
        "hyperloop score pairs with); no capacity run",
    )
    ap.add_argument(
        "--root",
        type=Path,
        default=Path("."),
        help="the checkout to publish into (its docs/benchmark/ and README.md)",
    )
    return ap


def main(argv: Sequence[str] | None = None, prog: str = "hyperloop headline") -> int:
    import sys

    from agents.cli import capacity
    from agents.evaluation import headline_publish as hp
    from agents.evaluation.published import PUBLISHED_FILE

    ap = build_parser(prog)
    args = ap.parse_args(argv)
    if args.comfort and args.src is not None:
        ap.error("--comfort flies the comfort runs of the published table: no --from")
    readme = args.root / "README.md"
    if not readme.is_file():
        print(f"{prog}: error: {readme} not found (run from a checkout or pass --root)",
              file=sys.stderr)  # fmt: skip
        return 2
    if args.comfort:
        return _publish_comfort(args.root, prog, argv, args.workers)
    src = args.src
    if src is None:
        flags = ["--out", str(args.out), "--seeds", str(args.seeds)]
        flags += ["--distance-km", str(args.distance_km), "--workers", str(args.workers)]
        flags += ["--overwrite"] * args.overwrite + ["--resume"] * args.resume
        rc = capacity.main(flags, prog="hyperloop capacity")
        if rc:
            return rc
        src = args.out
    try:
        doc = hp.check_source(src, args.allow_partial)
        package_data = args.root / PUBLISHED_FILE.relative_to(PUBLISHED_FILE.parents[3])
        hp.publish(src, doc, args.root / "docs" / "benchmark", readme, package_data)
    except hp.PublishError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    print(f"docs/benchmark/, README.md and the published benchmark data updated from {src}")
    return 0


def _publish_comfort(root: Path, prog: str, argv: Sequence[str] | None, workers: int) -> int:
    """``--comfort``: the published entrants' ride comfort into the checkout's package
    data (:func:`agents.evaluation.published.comfort_data`)."""
    import sys

    from agents.cli.common import argv_of
    from agents.evaluation import published as pm

    def in_root(path: Path) -> Path:
        return root / path.relative_to(pm.PUBLISHED_FILE.parents[3])

    target = in_root(pm.COMFORT_FILE)
    try:
        pub = pm.load_published(in_root(pm.PUBLISHED_FILE))
        command = " ".join([prog, *argv_of(argv)])
        doc = pm.comfort_data(
            pub, command=command, log=lambda line: print(line, flush=True), workers=workers
        )
    except ValueError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    pm.write_published_comfort(doc, target)
    print(f"{target} written ({doc['wall_s']:.0f} s)")
    return 0
