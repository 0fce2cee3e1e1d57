"""Resumes, damaged blocks and refusals of the benchmark and fragility surfaces (issue 17,
part 2, points 8 and 9; point 3's real-signal test is in test_signals.py)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from agents.cli import fragility as fragility_cli
from agents.evaluation import benchmark as bm
from agents.evaluation import fragility as fr

SUITE = {
    "families": {
        "roughness": {"levels": [0.3], "grid": [0.15, 0.6], "fixed": {}},
        "payload": {"levels": [0.2], "grid": [0.2], "fixed": {}},
    }
}
KW = dict(
    conditions=["paper-2000-straight"],
    seeds=2,
    distance_km=0.6,
    suite=SUITE,
    figures=False,
    progress=False,
    n_boot=10,
    n_boot_fragility=20,
)


@pytest.fixture(scope="module")
def fresh(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    out = tmp_path_factory.mktemp("bench") / "fresh"
    return out, bm.run_benchmark(["passive", "pid+g"], out_dir=out, **KW)


def _edit(path: Path, change) -> None:  # noqa: ANN001
    doc = json.loads(path.read_text())
    change(doc)
    path.write_text(json.dumps(doc))


def _counting(monkeypatch: pytest.MonkeyPatch) -> list[list[str]]:
    calls: list[list[str]] = []
    real = fr.fragility
    monkeypatch.setattr(fr, "fragility", lambda c, *a, **k: calls.append(c) or real(c, *a, **k))
    return calls


def test_resume_reruns_damaged_or_incomplete_blocks_naming_file_and_field(
    fresh: tuple[Path, dict],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A truncated results.json, one without 'fits', one missing a level row: each block is
    unfinished (a stderr line names the file and what is wrong) and runs again; the
    headline equals the fresh run's (no n/a), its wall time includes the blocks read."""
    src, res = fresh
    r = tmp_path / "r"
    shutil.copytree(src, r)
    (r / "headline.json").unlink()
    truncated = r / "roughness" / "levitation" / "results.json"
    truncated.write_text(truncated.read_text()[:100])
    no_fits = r / "roughness" / "levitation-guidance" / "results.json"
    _edit(no_fits, lambda d: d.pop("fits"))
    no_row = r / "payload" / "levitation" / "results.json"
    _edit(no_row, lambda d: d.update(levels=d["levels"][1:]))
    kept = r / "payload" / "levitation-guidance" / "results.json"
    _edit(kept, lambda d: d["settings"].update(wall_s=1000.0))
    calls = _counting(monkeypatch)
    capsys.readouterr()
    resumed = bm.run_benchmark(["passive", "pid+g"], out_dir=r, resume=True, **KW)
    err = capsys.readouterr().err
    assert calls == [["passive"], ["pid"], ["passive"]]
    assert f"{truncated} is damaged or incomplete: unreadable (JSONDecodeError" in err
    assert f"{no_fits} is damaged or incomplete: no 'fits' list" in err
    assert (
        f"{no_row} is damaged or incomplete: no level row for controller 'passive', "
        "condition 'paper-2000-straight', level 0.2"
    ) in err
    assert json.dumps(resumed["headline"], sort_keys=True) == json.dumps(
        res["headline"], sort_keys=True
    )
    assert "n/a" not in (r / "headline.md").read_text().split("## P(unsteady)")[0]
    assert resumed["settings"]["wall_s"] >= 1000.0  # point 9: the earlier part counts
    assert json.loads((r / "headline.json").read_text())["settings"]["wall_s"] >= 1000.0
    for f in (truncated, no_fits, no_row):
        doc = json.loads(f.read_text())
        st = doc["settings"]
        assert bm.block_problem(doc, st["controllers"], st["conditions"], st["levels"]) is None


def test_resume_refuses_other_settings_before_running_anything(
    fresh: tuple[Path, dict], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    src, _ = fresh
    r = tmp_path / "r"
    shutil.copytree(src, r)
    damaged = r / "roughness" / "levitation" / "results.json"
    damaged.write_text("{")
    other = r / "payload" / "levitation-guidance" / "results.json"
    _edit(other, lambda d: d["settings"].update(n_boot_fragility=999))
    calls = _counting(monkeypatch)
    with pytest.raises(ValueError, match=rf"{other} was run with n_boot_fragility=999"):
        bm.run_benchmark(["passive", "pid+g"], out_dir=r, resume=True, **KW)
    assert calls == [] and damaged.read_text() == "{"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"n_boot_fragility": -5}, "--n-boot-fragility"),
        ({"n_boot_fragility": 0}, "--n-boot-fragility"),
        ({"n_boot": -1}, "--n-boot"),
        ({"distance_km": 0.05}, "--settle-s"),
    ],
)
def test_bad_values_are_refused_before_anything_is_created(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, change: dict, message: str
) -> None:
    calls = _counting(monkeypatch)
    out = tmp_path / "out"
    with pytest.raises(ValueError, match=message):
        bm.run_benchmark(["passive", "pid+g"], out_dir=out, **{**KW, **change})
    assert not out.exists() and calls == []
    with pytest.raises(ValueError, match="entrants repeat"):
        bm.run_benchmark(["pid", "pid"], out_dir=out, **KW)
    assert not out.exists()


def test_fragility_refuses_repeated_controllers_bad_bootstrap_and_settle(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    kw = dict(
        seeds=2,
        distance_km=0.6,
        progress=False,
        n_boot=10,
        n_boot_fragility=20,
        out_dir=tmp_path / "f",
    )
    with pytest.raises(ValueError, match="controllers repeat: pid"):
        fr.fragility(["pid", "passive", "pid"], ["paper-2000-straight"], "roughness", [0.3], **kw)
    with pytest.raises(ValueError, match=r"--n-boot-fragility \(n_boot_fragility\) must be"):
        fr.fragility(
            ["pid"], ["paper-2000-straight"], "roughness", [0.3], **{**kw, "n_boot_fragility": -5}
        )
    assert not (tmp_path / "f").exists()
    with pytest.raises(SystemExit) as exc:
        fragility_cli.main(
            [
                "--controllers",
                "passive",
                "--levels",
                "0.3",
                "--seeds",
                "2",
                "--distance-km",
                "0.6",
                "--settle-s",
                "1e9",
                "--no-progress",
                "--out",
                str(tmp_path / "f"),
            ]
        )
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--settle-s (settle_s) = 1e+09 s is not shorter than a run" in err, err
    assert not (tmp_path / "f").exists()


def test_fragility_benchmark_and_merge_hold_their_output_directory(
    fresh: tuple[Path, dict], tmp_path: Path, folder_holder
) -> None:  # noqa: ANN001
    """Point 4 on the evaluation surfaces: a directory held by another process (its pid
    named) is refused by every writer, before anything runs."""
    from agents.evaluation.outputs import OutputLockError

    held = tmp_path / "held"
    proc = folder_holder(held)
    match = rf"{held} is in use by another run \(pid {proc.pid}"
    with pytest.raises(OutputLockError, match=match):
        bm.run_benchmark(["passive"], out_dir=held, **KW)
    with pytest.raises(OutputLockError, match=match):
        bm.run_benchmark(["passive"], out_dir=held, resume=True, **KW)
    with pytest.raises(OutputLockError, match=match):
        fr.fragility(
            ["passive"],
            ["paper-2000-straight"],
            "roughness",
            [0.3],
            seeds=2,
            distance_km=0.6,
            progress=False,
            out_dir=held,
        )
    a, _ = fresh
    with pytest.raises(OutputLockError, match=match):
        bm.merge_runs([a, _copy_run(a, tmp_path / "b")], held, overwrite=True)
    assert sorted(q.name for q in held.iterdir()) == [".lock"]


def _copy_run(src: Path, dest: Path) -> Path:
    """A copy of a run with its entrants renamed (passive -> x, pid -> y) in its headline
    and in its blocks alike, so that a merge with ``src`` is valid."""
    names = {"passive": "x", "pid": "y"}
    shutil.copytree(src, dest)
    _edit(dest / "headline.json", lambda d: d["settings"].update(entrants=["x", "y+g"]))

    def rename(d: dict) -> None:
        d["settings"]["controllers"] = [names[c] for c in d["settings"]["controllers"]]
        for r in (*d["levels"], *d["fits"]):
            r["controller"] = names[r["controller"]]

    for block in dest.glob("*/*/results.json"):
        _edit(block, rename)
    return dest
