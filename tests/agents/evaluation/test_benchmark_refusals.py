"""The benchmark refuses what it cannot use, naming the file and the field, before it
touches anything: a folder that is not a run given to --resume, damaged values in a
finished block, runs to --merge whose content does not agree with their blocks, suites
that are not suites; Ctrl-C ends it with one line naming --resume."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest

from agents.cli import benchmark as benchmark_cli
from agents.evaluation import benchmark as bm

SUITE = {"families": {"roughness": {"levels": [0.3], "grid": [0.15, 0.6], "fixed": {}}}}
KW: dict[str, Any] = dict(
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
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("bench") / "run"
    bm.run_benchmark(["passive", "pid+g"], out_dir=out, **KW)
    return out


def _edit(path: Path, change) -> None:  # noqa: ANN001
    doc = json.loads(path.read_text())
    change(doc)
    path.write_text(json.dumps(doc))


def test_resume_into_a_folder_that_is_not_a_run_touches_nothing(tmp_path: Path) -> None:
    u = tmp_path / "U"
    u.mkdir()
    (u / "headline.md").write_text("NOTES\n")
    with pytest.raises(ValueError, match="is not a benchmark run"):
        bm.run_benchmark(["passive"], out_dir=u, resume=True, **KW)
    (u / "roughness").mkdir()
    (u / "roughness" / "notes.txt").write_text("mine\n")
    with pytest.raises(ValueError, match=r"holds .*notes\.txt, which such a run does not"):
        bm.run_benchmark(["passive"], out_dir=u, resume=True, **KW)
    assert (u / "headline.md").read_text() == "NOTES\n"
    assert sorted(str(q.relative_to(u)) for q in u.rglob("*")) == [
        "headline.md",
        "roughness",
        "roughness/notes.txt",
    ]


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("p_contact", "abc", "levels[0].p_contact = 'abc' is not a probability"),
        ("level", "0.15", "levels[0].level = '0.15' is not a positive number"),
        ("rms_gap_mm", -1.0, "levels[0].rms_gap_mm = -1.0 is not a number >= 0 or null"),
        ("n_contacts", 5, "more contacts (5) than runs"),
        ("p_contact", float("nan"), "NaN is not a number JSON allows"),
    ],
)
def test_a_damaged_value_in_a_finished_block_is_named_and_the_block_rerun(
    run: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    field: str,
    value: Any,
    message: str,
) -> None:
    out = tmp_path / "run"
    shutil.copytree(run, out)
    block = out / "roughness" / "levitation" / "results.json"
    _edit(block, lambda d: d["levels"][0].update({field: value}))
    res = bm.run_benchmark(["passive", "pid+g"], out_dir=out, resume=True, **KW)
    err = capsys.readouterr().err
    assert str(block) in err and message in err and "the block runs again" in err
    assert json.loads(block.read_text())["levels"][0][field] != value  # flown again
    ref = json.loads((run / "headline.json").read_text())["headline"]
    assert json.loads(json.dumps(res["headline"])) == ref


def _twin(src: Path, dest: Path) -> Path:
    """A run of the entrants x (passive's results) and y+g (pid+g's), consistent."""
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


def _break(kind: str, b: Path) -> str:
    """Damage the run ``b`` as ``kind``; the message the merge must give."""
    head = b / "headline.json"
    if kind == "no entrants":
        _edit(head, lambda d: d["settings"].pop("entrants"))
        return "settings.entrants must be a list of names"
    if kind == "settings not an object":
        _edit(head, lambda d: d.update(settings=[1, 2]))
        return "'settings' must be an object"
    if kind == "entrants a string":
        _edit(head, lambda d: d["settings"].update(entrants="x y+g"))
        return "settings.entrants must be a list of names"
    block = b / "roughness" / "levitation" / "results.json"
    if kind == "controllers not a list":
        _edit(block, lambda d: d["settings"].update(controllers="x"))
        return "settings.controllers must be a list of names"
    if kind == "missing block":
        shutil.rmtree(block.parent)
        return "holds blocks for the entrants ['y+g'], but its run lists ['x', 'y+g']"
    if kind == "relabelled block":
        _edit(head, lambda d: d["settings"].update(entrants=["lqr", "y+g"]))
        return "holds blocks for the entrants ['x', 'y+g'], but its run lists ['lqr', 'y+g']"
    raise AssertionError(kind)


@pytest.mark.parametrize(
    "kind",
    [
        "no entrants",
        "settings not an object",
        "entrants a string",
        "controllers not a list",
        "missing block",
        "relabelled block",
    ],
)
def test_merge_refuses_a_source_whose_content_does_not_hold(
    run: Path, tmp_path: Path, kind: str
) -> None:
    b = _twin(run, tmp_path / "b")
    message = _break(kind, b)
    dest = tmp_path / "merged"
    with pytest.raises(ValueError, match="--merge: ") as e:
        bm.merge_runs([run, b], dest, figures=False, n_boot_fragility=20)
    assert message in str(e.value) and str(b) in str(e.value)
    assert not dest.exists()


def test_a_consistent_twin_merges(run: Path, tmp_path: Path) -> None:
    b = _twin(run, tmp_path / "b")
    res = bm.merge_runs([run, b], tmp_path / "m", figures=False, n_boot_fragility=20)
    assert res["settings"]["entrants"] == ["passive", "pid+g", "x", "y+g"]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[1, 2]", "a suite is a JSON object with 'families', got a list"),
        ('{"families": {"roughness": [1]}}', "families.roughness must be an object"),
        ("{not json", "not a readable JSON suite"),
        (
            '{"families": {"roughness": {"levels": [0.3], "grid": [0.3], "fixed": {"x": 1}}}}',
            "families.roughness.fixed must map disturbance names",
        ),
    ],
)
def test_a_suite_that_is_not_a_suite_is_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, message: str
) -> None:
    f = tmp_path / "suite.json"
    f.write_text(text)
    with pytest.raises(ValueError, match="suite.json") as e:
        bm.load_suite(f)
    assert message in str(e.value)
    with pytest.raises(SystemExit) as e:
        benchmark_cli.main(["--print-suite", "--suite", str(f)])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_address_without_ray_is_refused(tmp_path: Path, capsys) -> None:  # noqa: ANN001
    with pytest.raises(SystemExit) as e:
        benchmark_cli.main(["--address", "auto", "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "--address needs --backend ray" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_ctrl_c_prints_one_line_naming_resume(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def ctrl_c(*a: Any, **k: Any) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(bm, "run_benchmark", ctrl_c)
    out = str(tmp_path / "o")
    assert benchmark_cli.main(["--entrants", "passive", "--out", out, "--overwrite"]) == 130
    err = capsys.readouterr().err
    assert "interrupted" in err and f"--entrants passive --out {out} --resume" in err
    assert "--overwrite" not in err and "Traceback" not in err
