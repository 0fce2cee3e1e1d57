"""Merge finished benchmark runs of different entrants into one, as if they had run
together (:func:`merge_runs`)."""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from agents.controllers.registry import GUIDED, LEVITATION
from agents.evaluation.benchmark_blocks import _number, block_problem, settings_seeds
from agents.evaluation.benchmark_report import headline, headline_csv, headline_markdown
from agents.evaluation.benchmark_suite import _kind, _no_constant
from agents.evaluation.entrants import entrant_label
from agents.evaluation.vocabulary import canonical
from hyperloop_env.json_values import json_value


def merge_runs(
    sources: Sequence[str | Path],
    out_dir: str | Path,
    *,
    overwrite: bool = False,
    figures: bool = True,
    n_boot_fragility: int = 1000,
    command: str | None = None,
) -> dict[str, Any]:
    """Merge benchmark runs of different entrants (same suite, conditions, seeds and
    distance) into one, as if they had run together: the level rows are pooled and every
    fragility function is refitted in the merged entrant order (the fits' bootstrap
    generators are seeded by entrant and condition index, so the result is the joint run's).
    Lets the baselines run while an agent trains."""
    from agents.evaluation.outputs import entries, output_lock, prepare_output_dir

    # validate everything before anything is deleted or written
    srcs = [Path(d) for d in sources]
    if len(srcs) < 2:
        raise ValueError("--merge needs at least two runs")
    if (
        isinstance(n_boot_fragility, bool)
        or not isinstance(n_boot_fragility, int)
        or n_boot_fragility < 1
    ):
        raise ValueError(f"--n-boot-fragility must be an integer >= 1, got {n_boot_fragility!r}")
    real = [p.resolve() for p in srcs]
    if len(set(real)) != len(real):
        raise ValueError(f"--merge: a run is given twice: {[str(p) for p in srcs]}")
    dest = Path(out_dir).resolve()
    for p, r in zip(srcs, real, strict=True):
        if r == dest or r in dest.parents or dest in r.parents:
            raise ValueError(
                f"--merge: the output {out_dir} must not be (inside) a merged run "
                f"({p}): a destination is never one of the sources"
            )
    docs = [_read_json(p / "headline.json", "--merge") for p in srcs]
    for p, d in zip(srcs, docs, strict=True):
        _check_merge_settings(p / "headline.json", d["settings"])
    s0 = docs[0]["settings"]
    for d, src in zip(docs[1:], sources[1:], strict=True):
        s = d["settings"]
        for key in (
            "conditions",
            "families",
            "seeds",
            "seed_range",
            "distance_km",
            "suite",
            "n_boot",
            "n_boot_fragility",
        ):
            if s.get(key) != s0.get(key):
                raise ValueError(f"--merge: {src} differs from {sources[0]} in {key!r}")
        if settings_seeds(s) != settings_seeds(s0):
            raise ValueError(f"--merge: {src} differs from {sources[0]} in 'seed_list'")
    labels = [lab for d in docs for lab in d["settings"]["entrants"]]
    if len(set(labels)) != len(labels):
        raise ValueError(f"--merge: entrants repeat across the runs: {labels}")
    parts_of: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for fam in s0["families"]:
        for src, d in zip(srcs, docs, strict=True):
            for act, doc in _merge_blocks(src, d["settings"], fam, s0["conditions"]).items():
                parts_of.setdefault((fam, act), []).append(doc)
    # write the merged run next to the destination, then move it in
    dest_dir = Path(out_dir)
    with output_lock(dest_dir, "merge output directory"):  # one run per directory
        if entries(dest_dir) and not overwrite:
            prepare_output_dir(dest_dir, overwrite=False)  # raises the usual refusal
        import shutil
        import tempfile

        out = Path(tempfile.mkdtemp(prefix=f".{dest_dir.name}.merging-", dir=dest_dir.parent))
        try:
            result = _merge_into(
                out, docs, sources, labels, parts_of, figures, n_boot_fragility, command
            )
            owned = ("headline.md", "headline.json", "headline.csv", *s0["families"])
            final = prepare_output_dir(dest_dir, overwrite=overwrite, owned=owned)
            for name in owned:
                if (out / name).exists():
                    os.replace(out / name, final / name)
        finally:
            shutil.rmtree(out, ignore_errors=True)
    return result


def _check_merge_settings(f: Path, st: Any) -> None:
    """The settings of a run to merge: an object whose entrants, conditions and families
    are non-empty lists of names and whose seeds and wall time are numbers."""
    if not isinstance(st, dict):
        raise ValueError(f"--merge: {f}: 'settings' must be an object, got {_kind(st)}")
    for key in ("entrants", "conditions", "families"):
        v = st.get(key)
        if not isinstance(v, list) or not v or not all(isinstance(x, str) for x in v):
            raise ValueError(f"--merge: {f}: settings.{key} must be a list of names, got {v!r}")
    if not _number(st.get("wall_s")):
        raise ValueError(f"--merge: {f}: settings.wall_s must be a number of seconds")
    try:
        settings_seeds(st)
    except (KeyError, TypeError, ValueError):
        raise ValueError(f"--merge: {f}: settings has no seed_list or seed_range") from None


def _merge_blocks(
    src: Path, st: dict[str, Any], fam: str, conditions: list[str]
) -> dict[str, dict[str, Any]]:
    """{actuators: block} of ``src`` for the family ``fam``, each complete; between them
    they must fly exactly the run's entrants, each once (a block that is missing, or one
    relabelled or copied from another run, is refused naming the file)."""
    blocks: dict[str, dict[str, Any]] = {}
    labels: list[str] = []
    for act in (LEVITATION, GUIDED):
        f = src / fam / act.replace("+", "-") / "results.json"
        if not f.exists():
            continue
        doc = _read_json(f, "--merge")
        ctrls = doc["settings"].get("controllers") if isinstance(doc["settings"], dict) else None
        if not isinstance(ctrls, list) or not ctrls or not all(isinstance(c, str) for c in ctrls):
            raise ValueError(f"--merge: {f}: settings.controllers must be a list of names")
        levels = doc["settings"].get("levels")
        if not isinstance(levels, list) or not all(_number(x) for x in levels):
            raise ValueError(f"--merge: {f}: settings.levels must be a list of numbers")
        problem = block_problem(doc, ctrls, conditions, levels)
        if problem is not None:
            raise ValueError(f"--merge: {f} is incomplete: {problem}")
        labels += [entrant_label(c, act) for c in ctrls]
        blocks[act] = doc
    if sorted(labels) != sorted(st["entrants"]) or len(set(labels)) != len(labels):
        raise ValueError(
            f"--merge: {src / fam} holds blocks for the entrants {labels}, but its run lists "
            f"{st['entrants']} (a missing, unfinished or relabelled block: finish the run "
            "with --resume, or merge the runs as written)"
        )
    return blocks


def _read_json(path: Path, flag: str) -> dict[str, Any]:
    """A JSON file of a finished run, or ValueError naming the file."""
    if not path.is_file():
        raise ValueError(f"{flag}: {path} not found (not a finished benchmark run)")
    try:
        doc = json.loads(path.read_text(), parse_constant=_no_constant)
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ValueError(f"{flag}: {path} is damaged ({exc})") from None
    if not isinstance(doc, dict) or "settings" not in doc:
        raise ValueError(f"{flag}: {path} has no 'settings' (not a benchmark result)")
    return doc


def _merge_into(
    out: Path,
    docs: list[dict[str, Any]],
    sources: Sequence[str | Path],
    labels: list[str],
    parts_of: dict[tuple[str, str], list[dict[str, Any]]],
    figures: bool,
    n_boot_fragility: int,
    command: str | None,
) -> dict[str, Any]:
    from agents.evaluation.fragility import fit_all
    from agents.evaluation.fragility_report import to_json, write_outputs
    from agents.evaluation.outputs import atomic_write_text

    s0 = docs[0]["settings"]
    conds, fams = s0["conditions"], s0["families"]
    sweeps: dict[str, dict[str, dict[str, Any]]] = {}
    wall = sum(float(d["settings"]["wall_s"]) for d in docs)
    for fam in fams:
        for act in (LEVITATION, GUIDED):
            parts = parts_of.get((fam, act), [])
            if not parts:
                continue
            ctrls = [c for p in parts for c in p["settings"]["controllers"]]
            rows = [canonical(r) for p in parts for r in p["levels"]]  # older names too
            settings = dict(parts[0]["settings"])
            settings.update(
                controllers=ctrls,
                command=command or settings.get("command"),
                wall_s=sum(float(p["settings"]["wall_s"]) for p in parts),
            )
            res = {
                "settings": settings,
                "levels": rows,
                "fits": fit_all(rows, ctrls, conds, n_boot_fragility),
                "paths": {},
            }
            sub = out / fam / act.replace("+", "-")
            sub.mkdir(parents=True, exist_ok=True)
            res["paths"] = write_outputs(res, sub, figures)
            fits_json = to_json(res)["fits"]
            for c in ctrls:
                lab = entrant_label(c, act)
                sweeps.setdefault(fam, {})[lab] = {
                    "fits": [f for f in fits_json if f["controller"] == c],
                    "levels": [r for r in rows if r["controller"] == c],
                }
    suite = {"families": s0["suite"]}
    order = [lab for lab in labels if any(lab in v for v in sweeps.values())]
    h = json_value(headline(sweeps, suite, order, conds))
    settings = {
        **s0,
        "entrants": order,
        "wall_s": wall,
        "command": command or "agents.evaluation.benchmark.merge_runs(...)",
        "merged_from": [str(x) for x in sources],
    }
    atomic_write_text(out / "headline.md", headline_markdown(h, suite, fams, conds, settings))
    atomic_write_text(
        out / "headline.json",
        json.dumps(json_value({"settings": settings, "headline": h}), indent=1) + "\n",
    )
    atomic_write_text(out / "headline.csv", headline_csv(h, fams))
    return {"settings": settings, "headline": h}
