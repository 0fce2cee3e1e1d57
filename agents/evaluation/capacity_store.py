"""The run directory of the capacity benchmark: an interrupt loses at most the tasks in
flight, and a report appears only whole.

Layout of ``--out`` (held by :func:`agents.evaluation.outputs.output_lock` for the run)::

    run.json            what the run computes: every task (entrant × condition, its
                        controller, episode configuration, searches, seeds, rows) —
                        written before the first flight
    tasks/<i>.json      task i's results, written atomically the moment it finishes
    headline.md/.json/.csv, capacities.json, figures/
                        the report, built from the task files and published whole
                        (:func:`agents.evaluation.outputs.publish_report`)

``--resume`` reads ``run.json`` (refused if it is missing, damaged, or the run asks for
other tasks: the message names the file and the first difference), keeps every task file
that is complete and belongs to its task, flies the others again (a line on stderr names
each damaged file) and builds the report. The report of a fresh run is built from the same
JSON records a resumed one reads, so the two are identical whatever was interrupted, and
whatever the number of workers.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

from agents.evaluation.capacity import CapacityTask, TaskResult
from agents.evaluation.outputs import OutputDirError, atomic_write_text, entries
from hyperloop_env.json_values import json_value

RUN_FILE = "run.json"
TASKS_DIR = "tasks"
KIND = "hyperloop capacity run"
VERSION = 1
CENSORED = (None, "right", "left")


def task_spec(task: CapacityTask) -> dict[str, Any]:
    """Everything that determines a task's results, as plain JSON values."""
    return _plain(
        {
            "key": list(task.key),
            "controller": task.controller,
            "controller_kwargs": task.controller_kwargs,
            "config": task.config.to_kwargs(),
            "families": [asdict(f) for f in task.families],
            "seeds": list(task.seeds),
            "rows": task.rows,
            "sts_stride": task.sts_stride,
            "settle_s": task.settle_s,
            "n_boot": task.n_boot,
        }
    )


def task_record(res: TaskResult) -> dict[str, Any]:
    """A finished task as the JSON record the report is built from (fresh or resumed)."""
    return _plain(
        {
            "key": list(res.key),
            "controller": res.controller,
            "searches": [s.to_dict() for s in res.searches],
            "sts": res.sts,
            "steps": res.steps,
            "run_steps": res.run_steps,
            "wall_s": res.wall_s,
            "sts_s": res.sts_s,
        }
    )


def _plain(x: Any) -> Any:
    """``x`` as it reads back from its JSON file (NaN kept as NaN)."""
    return json.loads(json.dumps(json_value(x, non_finite="keep")))


# --------------------------------------------------------------------------------------
# the run directory
# --------------------------------------------------------------------------------------


def open_run(out: Path, specs: Sequence[dict[str, Any]], resume: bool) -> float:
    """Check ``out`` (already prepared or locked by the caller) for this run and write its
    ``run.json``; returns the wall time [s] earlier attempts of a resumed run spent.
    ``resume`` into an empty directory starts the run; into one that holds no
    ``run.json`` of a capacity run (a user's files, another tool's run) it is refused."""
    f = out / RUN_FILE
    earlier = 0.0
    if resume and entries(out):
        doc = _read_run(f)
        if doc["tasks"] != list(specs):
            raise OutputDirError(f"--resume: {f} {_first_difference(doc['tasks'], specs)}")
        earlier = float(doc.get("wall_s", 0.0))
    write_run(out, specs, earlier)
    return earlier


def write_run(out: Path, specs: Sequence[dict[str, Any]], wall_s: float) -> None:
    doc = {"kind": KIND, "version": VERSION, "wall_s": wall_s, "tasks": list(specs)}
    atomic_write_text(out / RUN_FILE, json.dumps(doc, indent=1) + "\n")


def _read_run(f: Path) -> dict[str, Any]:
    hint = "(resume into the folder of an interrupted capacity run, or choose a new --out)"
    if not f.is_file():
        raise OutputDirError(f"--resume: {f.parent} is not a capacity run: no {f.name} {hint}")
    try:
        doc = json.loads(f.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise OutputDirError(f"--resume: {f} is unreadable ({exc}) {hint}") from None
    if not isinstance(doc, dict) or doc.get("kind") != KIND or doc.get("version") != VERSION:
        raise OutputDirError(f"--resume: {f} is not the record of a capacity run {hint}")
    if not isinstance(doc.get("tasks"), list):
        raise OutputDirError(f"--resume: {f} has no 'tasks' list {hint}")
    w = doc.get("wall_s", 0.0)
    if isinstance(w, bool) or not isinstance(w, int | float) or not math.isfinite(w) or w < 0:
        raise OutputDirError(f"--resume: {f}: 'wall_s' must be a number >= 0, got {w!r}")
    return doc


def _first_difference(old: list[Any], new: Sequence[dict[str, Any]]) -> str:
    tail = "resume with that run's options, or choose a new --out"
    if len(old) != len(new):
        return f"holds {len(old)} tasks, this run asks for {len(new)} ({tail})"
    for i, (a, b) in enumerate(zip(old, new, strict=True)):
        if a == b:
            continue
        if not isinstance(a, dict):
            return f"task {i} is not an object ({tail})"
        for k in b:
            if a.get(k) != b[k]:
                return f"was run with task {i} {k}={a.get(k)!r}; this run asks {b[k]!r} ({tail})"
    return f"differs from this run ({tail})"


def task_file(out: Path, i: int) -> Path:
    return out / TASKS_DIR / f"{i:04d}.json"


def save_task(out: Path, i: int, spec: dict[str, Any], record: dict[str, Any]) -> None:
    doc = {"task": spec, "result": record}
    atomic_write_text(task_file(out, i), json.dumps(doc, allow_nan=True) + "\n")


def finished_tasks(out: Path, specs: Sequence[dict[str, Any]]) -> dict[int, dict[str, Any]]:
    """{index: record} of the task files in ``out`` that are complete and belong to their
    task; a damaged one is named on stderr and its task runs again."""
    done = {}
    for i, spec in enumerate(specs):
        f = task_file(out, i)
        if not f.is_file():
            continue
        try:
            doc = json.loads(f.read_text())
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            problem: str | None = f"unreadable ({type(exc).__name__}: {exc})"
        else:
            problem = record_problem(doc, spec)
        if problem is not None:
            print(f"--resume: {f} is damaged: {problem}; the task runs again", file=sys.stderr)
            continue
        done[i] = doc["result"]
    return done


def record_problem(doc: Any, spec: dict[str, Any]) -> str | None:
    """What makes a task file unusable for the task ``spec``, or None."""
    if not isinstance(doc, dict) or not isinstance(doc.get("result"), dict):
        return "not an object with a 'result'"
    if doc.get("task") != spec:
        return "it belongs to another task"
    r = doc["result"]
    if r.get("key") != spec["key"] or r.get("controller") != spec["controller"]:
        return "its key or controller is not its task's"
    for k in ("steps", "run_steps", "wall_s", "sts_s"):
        if not _number(r.get(k), 0.0):
            return f"{k!r} is not a number >= 0"
    if not isinstance(r.get("sts"), dict):
        return "no 'sts' mapping"
    searches = r.get("searches")
    if not isinstance(searches, list):
        return "no 'searches' list"
    want = sorted((f["family"], s) for f in spec["families"] for s in spec["seeds"])
    got = []
    for j, s in enumerate(searches):
        problem = _search_problem(s)
        if problem:
            return f"searches[{j}]: {problem}"
        got.append((s["family"], s["seed"]))
    if sorted(got) != want:
        return "its searches are not one per family and seed of its task"
    return None


def _search_problem(s: Any) -> str | None:
    if not isinstance(s, dict):
        return "not an object"
    if not _number(s.get("capacity"), 0.0, strict=True):
        return f"capacity {s.get('capacity')!r} is not a positive number"
    if s.get("censored") not in CENSORED:
        return f"censored {s.get('censored')!r} is not one of {CENSORED}"
    if not isinstance(s.get("non_monotone"), bool) or not isinstance(s.get("runs"), list):
        return "no 'non_monotone' flag or 'runs' list"
    if not isinstance(s.get("family"), str) or not isinstance(s.get("seed"), int):
        return "no 'family' or 'seed'"
    return None


def _number(x: Any, low: float, strict: bool = False) -> bool:
    if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
        return False
    return x > low if strict else x >= low
