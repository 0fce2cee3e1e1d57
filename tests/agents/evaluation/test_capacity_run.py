"""The capacity benchmark's run directory: one run per folder, resumable per task with the
result of an uninterrupted run, reports published whole, clear refusals before anything is
created (:mod:`agents.evaluation.capacity_store`)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from agents.cli.capacity import main as capacity_main
from agents.evaluation import capacity_store as store
from agents.evaluation.capacity_report import readme_block
from agents.evaluation.outputs import OutputDirError

ROOT = Path(__file__).resolve().parents[3]
SEEDS = ["--seed-list", "1000000", "1000001", "1000002"]
ARGS = [
    "--entrants",
    "passive",
    "pid",
    "--conditions",
    "paper-2000-straight",
    "paper-2000-curved",
    "--families",
    "roughness",
    *SEEDS,
    "--distance-km",
    "0.2",
    "--ratio",
    "1.1",
    "--n-boot-fit",
    "50",
    "--no-figures",
    "--quiet",
]
TIMING = ("wall_s", "sts_s", "command", "workers", "commit")  # commit: provenance


def _exit_code(argv: list[str]) -> int:
    """The exit status of ``hyperloop capacity argv`` (a refusal is ``SystemExit(2)``)."""
    try:
        return capacity_main(argv)
    except SystemExit as e:
        return int(e.code or 0)


def _main(out: Path, *extra: str) -> int:
    return _exit_code([*ARGS, "--out", str(out), *extra])


def _strip(x: Any) -> Any:
    """A report without what depends on the clock or on how it was run."""
    if isinstance(x, dict):
        return {k: _strip(v) for k, v in x.items() if k not in TIMING}
    if isinstance(x, list):
        return [_strip(v) for v in x]
    return x


def _report(out: Path) -> tuple[Any, Any, str]:
    h = json.loads((out / "headline.json").read_text())
    c = json.loads((out / "capacities.json").read_text())
    return _strip(h), _strip(c), (out / "headline.csv").read_text()


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("ref") / "run"
    assert _main(out, "--workers", "1") == 0  # in this process: compared with 2 workers
    return out


def test_a_busy_folder_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], folder_holder
) -> None:  # noqa: ANN001
    """Another process holds the folder (as a running capacity run does): refused, naming
    the folder and the holder's pid; the holder's folder is left alone."""
    out = tmp_path / "run"
    holder = folder_holder(out)
    assert _main(out) == 2
    err = capsys.readouterr().err
    assert "in use by another run" in err and str(out) in err and f"pid {holder.pid}" in err
    assert sorted(p.name for p in out.iterdir()) == [".lock"]


def test_an_interrupt_keeps_finished_tasks_and_resume_gives_the_same_report(
    tmp_path: Path, reference: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:  # noqa: ANN001
    from agents.evaluation import backends

    real = backends.run_blocks

    def one_then_ctrl_c(*a: Any, **kw: Any):  # noqa: ANN202
        gen = real(*a, **kw)
        yield next(gen)
        gen.close()
        raise KeyboardInterrupt

    out = tmp_path / "run"
    monkeypatch.setattr(backends, "run_blocks", one_then_ctrl_c)
    assert _main(out) == 130
    err = capsys.readouterr().err
    assert "interrupted" in err and "--resume" in err and "Traceback" not in err
    assert sorted(p.name for p in out.iterdir()) == ["run.json", "tasks"]  # no report
    kept = [p.name for p in (out / "tasks").iterdir()]  # the first task to finish
    assert len(kept) == 1 and kept[0] in ("0000.json", "0001.json", "0002.json", "0003.json")
    monkeypatch.setattr(backends, "run_blocks", real)
    assert _main(out) == 2  # a plain rerun is refused, pointing to --resume
    assert "--resume to continue it" in capsys.readouterr().err
    flown: list[int] = []
    monkeypatch.setattr(
        backends,
        "run_blocks",
        lambda specs, **kw: (flown.append(len(specs)), real(specs, **kw))[1],
    )
    assert _main(out, "--resume", "--workers", "2") == 0
    assert flown == [3]  # the finished task was read back, not flown again
    assert _report(out) == _report(reference)
    assert not (out / ".lock").exists()


def test_resume_refuses_a_folder_that_is_not_a_capacity_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "U"
    out.mkdir()
    (out / "headline.md").write_text("NOTES\n")
    assert _main(out, "--resume") == 2
    assert "is not a capacity run" in capsys.readouterr().err
    assert (out / "headline.md").read_text() == "NOTES\n"
    assert sorted(p.name for p in out.iterdir()) == ["headline.md"]


def test_resume_refuses_other_settings_and_reruns_a_damaged_task(
    tmp_path: Path, reference: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import shutil

    out = tmp_path / "run"
    shutil.copytree(reference, out)
    for q in ("headline.json", "headline.md", "headline.csv", "capacities.json"):
        (out / q).unlink()
    args = [a if a != "0.2" else "0.3" for a in ARGS]
    assert _exit_code([*args, "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err
    assert "run.json was run with task 0 config=" in err and "track_length_m" in err
    (out / "tasks" / "0001.json").write_text('{"task": ')  # a torn file
    doc = json.loads((out / "tasks" / "0002.json").read_text())
    doc["result"]["searches"][0]["capacity"] = float("nan")
    (out / "tasks" / "0002.json").write_text(json.dumps(doc))
    assert _main(out, "--resume") == 0
    err = capsys.readouterr().err
    assert "0001.json is damaged: unreadable" in err
    assert "0002.json is damaged: searches[0]: capacity nan is not a positive number" in err
    assert _report(out) == _report(reference)


def test_worker_count_does_not_change_the_report(tmp_path: Path, reference: Path) -> None:
    assert _main(tmp_path / "w2", "--workers", "2") == 0
    assert _report(tmp_path / "w2") == _report(reference)


def test_a_failed_run_leaves_no_folder(tmp_path: Path, capsys) -> None:  # noqa: ANN001
    import importlib.util

    out = tmp_path / "run"
    if importlib.util.find_spec("ray") is None:
        assert _main(out, "--backend", "ray") == 2
        assert "pip install" in capsys.readouterr().err and not out.exists()
    assert _main(out, "--address", "auto") == 2
    assert "--address needs --backend ray" in capsys.readouterr().err and not out.exists()


def test_one_entrant_gives_a_report_without_verdicts(tmp_path: Path) -> None:
    args = [*ARGS]
    args[args.index("pid")] = "--conditions"  # drop pid: passive alone
    args.remove("--conditions")
    out = tmp_path / "one"
    assert capacity_main([*args, "--out", str(out)]) == 0
    h = json.loads((out / "headline.json").read_text())
    assert h["settings"]["entrants"] == ["passive"] and h["headline"]["pairs"] == 0
    md = (out / "headline.md").read_text()
    assert "no pairs to compare" in md and "## Verdicts" not in md
    assert "no pairs to compare" in readme_block(h)


def test_publish_report_is_whole_or_not_at_all(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from agents.evaluation.outputs import publish_report

    (tmp_path / "a.txt").write_text("old a")
    (tmp_path / "b.json").write_text("old b")
    with pytest.raises(RuntimeError), publish_report(tmp_path, ["a.txt", "b.json"]) as st:
        (st / "a.txt").write_text("new a")
        raise RuntimeError("the figures failed")
    assert (tmp_path / "a.txt").read_text() == "old a"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.json"]
    real = os.replace

    def replace_then_ctrl_c(src: Any, dst: Any) -> None:  # Ctrl-C after each file
        real(src, dst)
        signal.raise_signal(signal.SIGINT)

    with pytest.raises(KeyboardInterrupt), publish_report(tmp_path, ["a.txt", "b.json"]) as st:
        (st / "a.txt").write_text("new a")
        (st / "b.json").write_text("new b")
        monkeypatch.setattr(os, "replace", replace_then_ctrl_c)
    monkeypatch.setattr(os, "replace", real)
    assert (tmp_path / "a.txt").read_text() == "new a"
    assert (tmp_path / "b.json").read_text() == "new b"  # the signal waited for the last file
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.json"]


def test_record_problem_names_the_field(tmp_path: Path) -> None:
    spec = {
        "key": ["pid", "c"],
        "controller": "pid",
        "families": [{"family": "roughness"}],
        "seeds": [5],
    }
    good = {
        "key": ["pid", "c"],
        "controller": "pid",
        "steps": 1,
        "run_steps": 1,
        "wall_s": 0.1,
        "sts_s": 0.0,
        "sts": {},
        "searches": [
            {
                "family": "roughness",
                "seed": 5,
                "capacity": 0.3,
                "censored": None,
                "non_monotone": False,
                "runs": [],
            }
        ],
    }
    assert store.record_problem({"task": spec, "result": good}, spec) is None
    bad = {**good, "searches": []}
    assert "one per family and seed" in store.record_problem({"task": spec, "result": bad}, spec)
    bad = {**good, "steps": -1}
    assert "'steps'" in store.record_problem({"task": spec, "result": bad}, spec)
    assert "another task" in store.record_problem({"task": {}, "result": good}, spec)
    (tmp_path / store.RUN_FILE).write_text('{"kind": "something else", "tasks": []}')
    with pytest.raises(OutputDirError, match="not the record of a capacity run"):
        store.open_run(tmp_path, [], resume=True)


def _sigint_default() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_sigint_to_the_cli_then_resume(tmp_path: Path, reference: Path) -> None:
    """A real Ctrl-C to ``python -m agents.capacity`` once a task has finished: exit 130, a
    line naming --resume and no traceback, no report; --resume gives the reference."""
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "agents.capacity", *ARGS, "--out", str(out)]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1"}
    log = tmp_path / "stderr.txt"
    proc = subprocess.Popen(
        cmd, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=log.open("w"),
        preexec_fn=_sigint_default,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 300
        while not (out / "tasks" / "0000.json").exists():
            assert proc.poll() is None, log.read_text()[-2000:]
            assert time.monotonic() < deadline
            time.sleep(0.01)
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    err = log.read_text()
    if proc.returncode == 0:  # the last task finished before the signal landed
        pytest.skip("the run finished before the signal")
    assert proc.returncode == 130 and "--resume" in err and "Traceback" not in err, err
    assert not (out / "headline.json").exists()
    done = subprocess.run(
        [*cmd, "--resume"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert _report(out) == _report(reference)


def test_the_report_says_what_sets_each_capacity(reference: Path) -> None:
    """Per condition × family × entrant, the kind of the first contact of every seed's run
    at its capacity (levitation gap, guidance gap, both; "none" if right-censored),
    counted again here from the kept runs of capacities.json."""
    from collections import Counter

    h = json.loads((reference / "headline.json").read_text())
    caps = json.loads((reference / "capacities.json").read_text())["capacities"]
    for cond, fams in h["analysis"].items():
        for fam, cell in fams.items():
            for lab, e in cell["entrants"].items():
                want: Counter[str] = Counter()
                for search in caps[cond][fam][lab]:
                    at = [
                        r["kind"]
                        for r in search["runs"]
                        if r["contact"] and r["severity"] == search["capacity"]
                    ]
                    want["none" if search["censored"] == "right" else at[0]] += 1
                assert e["contact_at_capacity"] == dict(want), (cond, fam, lab)
                assert sum(want.values()) == 3
    assert "## What sets the capacity" in (reference / "headline.md").read_text()
