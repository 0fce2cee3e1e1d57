#!/usr/bin/env python
"""Mutation testing with a curated list: does the default test suite notice a wrong line?

    python scripts/mutation.py                    # every mutant of scripts/mutants.toml
    python scripts/mutation.py --only ID [ID ...] # some of them
    python scripts/mutation.py --list             # the list, nothing run

Each mutant (``scripts/mutants.toml``: file, exact original text, replacement, test files) is
applied alone to a temporary copy of the repository (the files git knows, tracked and
untracked-but-not-ignored; the working tree is never touched), the copy's own test files
of the mutant are run with ``python -m pytest -x -q`` (the default suite: ``-m 'not slow'``
from pyproject.toml), and the original is restored byte for byte (and its mtime) before the
next one. A mutant is *killed* when a test fails or errors, *survived* when they pass.

numba caches compiled functions on disk (``cache=True``) keyed by the source file of the
function, and a kernel that calls a function of another file is not recompiled when only
that other file changes. So every mutant in ``hyperloop_env/`` (but the pure-Python
``sts/``) runs with an empty ``NUMBA_CACHE_DIR``; the others share one warmed by the
baseline run. The baseline (no mutation) must pass first.

The score is killed / (all − listed equivalent). The report goes to ``docs/mutation.md``
(``--report``; a ``--only`` run writes none unless given one); run it outside the
default suite (it takes about an hour on 2 cores).
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MUTANTS = ROOT / "scripts" / "mutants.toml"
REPORT = ROOT / "docs" / "mutation.md"


@dataclass
class Mutant:
    id: str
    file: str
    original: str
    replacement: str
    tests: list[str]
    note: str = ""
    equivalent: str | None = None
    fresh_cache: bool = True


@dataclass
class Outcome:
    mutant: Mutant
    status: str  # killed | survived | timeout | error (could not apply)
    killed_by: str = ""
    seconds: float = 0.0
    tail: list[str] = field(default_factory=list)


def load_mutants(path: Path = MUTANTS) -> list[Mutant]:
    data = tomllib.loads(path.read_text())
    groups: dict[str, list[str]] = data.get("groups", {})
    out: list[Mutant] = []
    seen: set[str] = set()
    for m in data["mutant"]:
        tests = m["tests"]
        tests = groups[tests] if isinstance(tests, str) else list(tests)
        fresh = m.get("fresh_cache")
        if fresh is None:
            fresh = m["file"].startswith("hyperloop_env/") and not m["file"].startswith(
                "hyperloop_env/sts/"
            )
        mut = Mutant(
            m["id"],
            m["file"],
            m["original"],
            m["replacement"],
            tests,
            m.get("note", ""),
            m.get("equivalent"),
            bool(fresh),
        )
        if mut.id in seen:
            raise ValueError(f"duplicate mutant id {mut.id!r}")
        seen.add(mut.id)
        out.append(mut)
    return out


def check_mutant(m: Mutant, root: Path) -> str | None:
    """Why ``m`` cannot be applied to the tree at ``root`` (None: it can)."""
    p = root / m.file
    if not p.exists():
        return f"{m.file} does not exist"
    n = p.read_text().count(m.original)
    if n != 1:
        return f"original text occurs {n} times in {m.file} (must be exactly once)"
    if m.original == m.replacement:
        return "replacement equals the original"
    missing = [t for t in m.tests if not (root / t).exists()]
    if missing:
        return f"test files missing: {missing}"
    return None


def copy_repo(dest: Path) -> None:
    """The files git knows (tracked + untracked, not ignored) into ``dest``."""
    files = (
        subprocess.run(
            ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
            cwd=ROOT,
            capture_output=True,
            check=True,
        )
        .stdout.decode()
        .split("\0")
    )
    for f in files:
        if not f:
            continue
        src = ROOT / f
        if not src.is_file():
            continue  # deleted in the working tree
        dst = dest / f
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, dst)


def run_pytest(copy: Path, tests: list[str], cache_dir: Path, timeout: float) -> tuple[int, str]:
    env = dict(os.environ)
    env["NUMBA_CACHE_DIR"] = str(cache_dir)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    env.pop("PYTHONPATH", None)
    cmd = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *tests]
    # own session: on a timeout or an interrupt the whole test process group is ended
    proc = subprocess.Popen(
        cmd,
        cwd=copy,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    try:
        out, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        _kill_group(proc)
        out, _ = proc.communicate()
        return -1, out or ""
    except BaseException:
        _kill_group(proc)
        raise
    return proc.returncode, out


def _kill_group(proc: subprocess.Popen) -> None:
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait()


_FAILED = re.compile(r"^(FAILED|ERROR) (\S+)")


def first_failure(output: str) -> str:
    for line in output.splitlines():
        m = _FAILED.match(line)
        if m:
            return m.group(2)
    return ""


def apply_and_run(m: Mutant, copy: Path, shared_cache: Path, timeout: float) -> Outcome:
    why = check_mutant(m, copy)
    if why:
        return Outcome(m, "error", why)
    path = copy / m.file
    original = path.read_bytes()
    st = path.stat()
    text = original.decode()
    t0 = time.perf_counter()
    try:
        path.write_text(text.replace(m.original, m.replacement, 1))
        if m.fresh_cache:
            with tempfile.TemporaryDirectory(prefix="numba-mutant-") as cache:
                rc, out = run_pytest(copy, m.tests, Path(cache), timeout)
        else:
            rc, out = run_pytest(copy, m.tests, shared_cache, timeout)
    finally:
        path.write_bytes(original)
        os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns))
    secs = time.perf_counter() - t0
    tail = out.strip().splitlines()[-3:]
    if rc == -1:
        return Outcome(m, "timeout", "(timeout)", secs, tail)
    if rc == 0:
        return Outcome(m, "survived", "", secs, tail)
    if rc in (1, 2):  # tests failed / collection or import error
        return Outcome(m, "killed", first_failure(out) or f"pytest exit {rc}", secs, tail)
    return Outcome(m, "error", f"pytest exit {rc}: " + " | ".join(tail), secs, tail)


def score(outcomes: list[Outcome]) -> tuple[int, int, float]:
    counted = [o for o in outcomes if not o.mutant.equivalent and o.status != "error"]
    killed = sum(o.status in ("killed", "timeout") for o in counted)
    return killed, len(counted), (killed / len(counted) if counted else float("nan"))


MUTMUT_NOTE = """## mutmut

mutmut 3.8.1 (`pip install mutmut`, in a separate virtualenv with
`--system-site-packages`; `[tool.mutmut]` with `source_paths = ["hyperloop_env", "agents"]`,
`only_mutate = ["hyperloop_env/sts/estimators.py"]` and
`pytest_add_cli_args_test_selection = ["tests/env/test_sts.py"]` on a copy of the
repository) works on the pure-Python parts: on `hyperloop_env/sts/estimators.py` alone it
generated 382 mutants; in 14 minutes on the shared 2-core machine it ran 146 of them (127
killed, 19 survived) before it was stopped. The survivors seen were of the kind a curated
list avoids on purpose — an argument name inside an error message (`"XXclearance_mXX"`),
`>=` vs `>` on a float boundary no signal reaches, a `math.isfinite(tau)` guard on a value
that is finite there, `n < 2` vs `n <= 2` in a size check covered by other validation. It
cannot mutate the numba kernels (its trampolines replace the functions numba compiles, and
numba's file cache would hide cross-file edits anyway), and a full run over STS,
controllers and the reward plumbing would be several thousand mutants (hours here, each
needing triage). So the habit is this curated list (every entry a mutation that would
change a benchmark number or a documented behaviour); mutmut is a useful occasional sweep
of one pure-Python module (`mutmut run`, then `mutmut results` / `mutmut show NAME`).
"""


def write_report(outcomes: list[Outcome], path: Path, wall_s: float, argv: list[str]) -> None:
    killed, n, s = score(outcomes)
    lines = [
        "# Mutation testing: the last report",
        "",
        f"Written by `python scripts/{Path(__file__).name}"
        + (" " + " ".join(argv) if argv else "")
        + f"` on {dt.date.today().isoformat()} "
        f"(wall time {wall_s / 60:.0f} min, `os.cpu_count() = {os.cpu_count()}`). The mutants "
        "are listed in `scripts/mutants.toml`; each ran alone on a temporary copy of the "
        "repository with its test files (`pytest -x`, the default suite), mutants in "
        "`hyperloop_env/` with an empty `NUMBA_CACHE_DIR`.",
        "",
        f"**Mutation score: {killed}/{n} = {100 * s:.0f} %** (killed / mutants not listed as "
        "equivalent).",
        "",
        "| mutant | file | mutation | result | killed by (first failing test) | s |",
        "|---|---|---|---|---|---:|",
    ]
    for o in outcomes:
        m = o.mutant
        res = o.status
        if m.equivalent:
            res += " (listed equivalent)"
        by = f"`{o.killed_by}`" if o.killed_by else ""
        lines.append(f"| `{m.id}` | `{m.file}` | {m.note} | {res} | {by} | {o.seconds:.0f} |")
    eq = [o for o in outcomes if o.mutant.equivalent]
    if eq:
        lines += ["", "## Equivalent mutants", ""]
        for o in eq:
            lines.append(f"* `{o.mutant.id}` ({o.status}): {o.mutant.equivalent}")
    surv = [o for o in outcomes if o.status == "survived" and not o.mutant.equivalent]
    errs = [o for o in outcomes if o.status == "error"]
    lines += ["", "## Survivors", ""]
    lines += [f"* `{o.mutant.id}`: {o.mutant.note}" for o in surv] or ["None."]
    if errs:
        lines += ["", "## Not applied", ""]
        lines += [f"* `{o.mutant.id}`: {o.killed_by}" for o in errs]
    lines += ["", MUTMUT_NOTE.strip()]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="+", metavar="ID", help="run only these mutants")
    ap.add_argument("--list", action="store_true", help="list the mutants and exit")
    ap.add_argument("--mutants", type=Path, default=MUTANTS, help="the mutant list (TOML)")
    ap.add_argument(
        "--report",
        type=Path,
        default=None,
        help=f"Markdown report path (default {REPORT.relative_to(ROOT)}; with --only, none "
        "unless given: a partial run does not replace the full report)",
    )
    ap.add_argument("--no-report", action="store_true", help="print only")
    ap.add_argument("--timeout", type=float, default=1200.0, help="seconds per mutant")
    ap.add_argument(
        "--skip-baseline", action="store_true", help="do not run the unmutated tests first"
    )
    args = ap.parse_args(argv)
    # SIGTERM (kill PID) unwinds like Ctrl-C: the mutated file is restored, the tests ended
    signal.signal(signal.SIGTERM, lambda *_: (_ for _ in ()).throw(KeyboardInterrupt()))
    mutants = load_mutants(args.mutants)
    if args.only:
        unknown = set(args.only) - {m.id for m in mutants}
        if unknown:
            ap.error(f"unknown mutant id(s) {sorted(unknown)}")
        mutants = [m for m in mutants if m.id in args.only]
    bad = [(m.id, why) for m in mutants if (why := check_mutant(m, ROOT))]
    if args.list or bad:
        for m in mutants:
            tag = " [equivalent]" if m.equivalent else ""
            print(f"{m.id:42s} {m.file}: {m.note}{tag}")
        for mid, why in bad:
            print(f"error: {mid}: {why}", file=sys.stderr)
        return 1 if bad else 0
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="mutation-") as tmp:
        copy = Path(tmp) / "repo"
        shared = Path(tmp) / "numba-cache"
        copy_repo(copy)
        probe = subprocess.run(
            [
                sys.executable,
                "-c",
                "import hyperloop_env, agents; "
                "print(hyperloop_env.__file__); print(agents.__file__)",
            ],
            cwd=copy,
            capture_output=True,
            text=True,
            env={**os.environ, "NUMBA_CACHE_DIR": str(shared)},
        )
        if probe.returncode or any(not ln.startswith(str(copy)) for ln in probe.stdout.split()):
            print(
                f"error: the copy does not import its own packages:\n{probe.stdout}{probe.stderr}",
                file=sys.stderr,
            )
            return 2
        if not args.skip_baseline:
            tests = list(dict.fromkeys(t for m in mutants for t in m.tests))
            print(f"baseline: {len(tests)} test files ...", flush=True)
            t0 = time.perf_counter()
            rc, out = run_pytest(copy, tests, shared, 3 * args.timeout)
            print(f"baseline: exit {rc} in {time.perf_counter() - t0:.0f} s", flush=True)
            if rc != 0:
                print("\n".join(out.splitlines()[-30:]), file=sys.stderr)
                print("error: the unmutated tests do not pass", file=sys.stderr)
                return 2
        outcomes = []
        for i, m in enumerate(mutants, 1):
            o = apply_and_run(m, copy, shared, args.timeout)
            outcomes.append(o)
            eq = " (listed equivalent)" if m.equivalent else ""
            print(
                f"[{i}/{len(mutants)}] {m.id}: {o.status}{eq} {o.killed_by} ({o.seconds:.0f} s)",
                flush=True,
            )
    wall = time.perf_counter() - t_start
    killed, n, s = score(outcomes)
    print(f"mutation score: {killed}/{n} = {100 * s:.1f} %  ({wall / 60:.0f} min)")
    for o in outcomes:
        if o.status == "survived" and not o.mutant.equivalent:
            print(f"SURVIVED: {o.mutant.id}: {o.mutant.note}")
    if args.report is None and not args.only:
        args.report = REPORT
    if not args.no_report and args.report is not None:
        write_report(outcomes, args.report, wall, argv if argv is not None else sys.argv[1:])
        print(f"report: {args.report}")
    return 0 if all(o.status != "survived" or o.mutant.equivalent for o in outcomes) else 1


if __name__ == "__main__":
    sys.exit(main())
