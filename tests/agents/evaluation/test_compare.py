"""``hyperloop compare target | comfort | cost`` and :mod:`agents.evaluation.comparisons`:
the published target, comfort and cost files are what the commands make of their inputs;
capacity runs are combined only where they are the same flights (a run that flew an
entrant on its first N seeds agrees with one that flew all of them); a file they cannot
use is one error line naming it, and exit 2."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from agents.cli import main as hyperloop
from agents.cli.compare import main
from agents.evaluation.comparisons import comfort, cost, target

ROOT = Path(__file__).resolve().parents[3]
BENCH = ROOT / "docs" / "benchmark"
RUNS = [BENCH / d / "headline.json" for d in (".", "mpc-vs-lqr", "mpc-preview-vs-lqr")]
TARGET = BENCH / "target"
COMFORT = BENCH / "comfort"


def _refused(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if "error:" in ln]
    assert len(lines) == 1, err
    return lines[0]


def test_help(capsys: pytest.CaptureFixture[str]) -> None:
    assert hyperloop(["--help"]) == 0
    assert "\n  compare " in capsys.readouterr().out
    for mode in ([], ["target"], ["comfort"], ["cost"]):
        with pytest.raises(SystemExit) as e:
            main([*mode, "--help"])
        assert e.value.code == 0
        out = capsys.readouterr().out
        assert out.startswith(f"usage: {' '.join(['hyperloop compare', *mode])} ")
    assert "Is a learned agent resolved above" in _help(["target"], capsys)
    assert "--seed0" in _help(["comfort"], capsys)


def _help(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    with pytest.raises(SystemExit):
        main([*argv, "--help"])
    return capsys.readouterr().out


def _target_args(out: Path) -> list[str]:
    doc = json.loads((TARGET / "target.json").read_text())
    args = ["target", "--learned", *doc["learned"], "--classical", *doc["classical"]]
    args += ["--runs", *map(str, RUNS), "--comfort", str(COMFORT / "comfort.json")]
    return [*args, "--out", str(out)]


def test_target_reproduces_the_published_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "target"
    assert main(_target_args(out)) == 0
    md = (TARGET / "target.md").read_text()
    assert (out / "target.md").read_text() == md
    assert capsys.readouterr().out == md
    new, old = (json.loads((d / "target.json").read_text()) for d in (out, TARGET))
    assert new.pop("command").startswith("hyperloop compare target --learned ")
    old.pop("command")
    assert new == old
    assert "pass --overwrite" in _refused(_target_args(out), capsys)  # it holds a check now
    assert main([*_target_args(out), "--overwrite"]) == 0


def test_runs_on_fewer_seeds_merge_where_they_agree() -> None:
    full = {"seeds": [1, 2, 3], "capacity": [0.5, 0.6, 0.7], "censored": [False] * 3}
    part = {"seeds": [1, 2], "capacity": [0.5, 0.6], "censored": [False] * 2}
    assert target.merge_rows(part, full, "x") is full and target.merge_rows(full, part, "x") is full
    other = {"seeds": [1, 2], "capacity": [0.5, 0.61], "censored": [False] * 2}
    with pytest.raises(target.TargetInputError, match="not the same flights"):
        target.merge_rows(other, full, "x")
    elsewhere = {"seeds": [1, 4], "capacity": [0.5, 0.6], "censored": [False] * 2}
    with pytest.raises(target.TargetInputError, match="not the same flights"):
        target.merge_rows(full, elsewhere, "x")


def test_target_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = ["--out", str(tmp_path / "o")]
    base = ["target", "--learned", "ppo", "--classical", "lqr", *out, "--runs"]
    assert "none.json: no such file" in _refused([*base, str(tmp_path / "none.json")], capsys)
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    assert "bad.json: not readable" in _refused([*base, str(bad)], capsys)
    bad.write_text(json.dumps({"settings": {}}))
    assert "bad.json: no field analysis" in _refused([*base, str(bad)], capsys)
    doc = json.loads(RUNS[0].read_text())
    doc["settings"]["seeds"] = 3
    bad.write_text(json.dumps(doc))
    line = _refused([*base, str(RUNS[0]), str(bad)], capsys)
    assert "bad.json: other seeds or search settings than" in line
    line = _refused([*base, str(RUNS[0]), "--learned", "nobody"], capsys)
    assert "nobody has no roughness capacities on paper-1000-straight" in line
    line = _refused(
        ["target", "--learned", "lqr", "--classical", "lqr", *out, "--runs", "x"], capsys
    )
    assert "--learned and --classical both name ['lqr']" in line
    assert not (tmp_path / "o").exists()


def test_comfort_rows_and_table_are_recomputed_from_the_published_per_seed_values() -> None:
    doc = json.loads((COMFORT / "comfort.json").read_text())
    assert comfort.comfort_table(doc["a_wz_per_seed"], doc["reference"]) == doc["rows"]
    assert comfort.comfort_markdown(doc) == (COMFORT / "comfort.md").read_text()


def test_a_tiny_comfort_comparison_flies_the_published_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Two seeds of one condition: the same a_wz as the published comparison's first two
    seeds, the files written, the table printed; a second run is refused."""
    out = tmp_path / "c"
    pub = json.loads((COMFORT / "comfort.json").read_text())
    cond = "paper-1000-straight"
    args = ["comfort", "--controllers", "lqr-preview", "--conditions", cond, "--seeds", "2"]
    args += ["--distance-km", f"{pub['distance_km']:g}", "--out", str(out)]
    assert main(args) == 0
    printed = capsys.readouterr().out
    doc = json.loads((out / "comfort.json").read_text())
    assert doc["seeds"] == [pub["seeds"][0], pub["seeds"][0] + 1] and doc["reference"] == "lqr"
    for c in ("lqr", "lqr-preview"):
        assert doc["a_wz_per_seed"][cond][c] == pytest.approx(
            pub["a_wz_per_seed"][cond][c][:2], rel=1e-6
        )
    md = (out / "comfort.md").read_text()
    assert printed == f"{cond}: done ({doc['wall_s']:.0f} s)\n" + md
    assert md == comfort.comfort_markdown(doc)
    assert doc["command"] == "hyperloop compare " + " ".join(args)
    assert "pass --overwrite" in _refused(args, capsys)


def test_comfort_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    base = ["comfort", "--out", str(tmp_path / "o"), "--controllers"]
    assert "--seeds" in _refused([*base, "pid", "--seeds", "1"], capsys)
    assert "unknown scenario 'nope'" in _refused([*base, "pid", "--scenarios", "nope"], capsys)
    assert "--distance-km" in _refused([*base, "pid", "--distance-km", "0.1"], capsys)
    assert "no-such-controller" in _refused([*base, "no-such-controller"], capsys)
    line = _refused([*base, "ppo", "--seed0", "0"], capsys)
    assert "--allow-training-seeds" in line
    assert not (tmp_path / "o").exists()


def test_cost_is_the_published_table(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["cost", str(BENCH / "headline.json")]) == 0
    assert capsys.readouterr().out == (BENCH / "cost.md").read_text()
    assert cost.headline_cost(BENCH / "headline.json") == (BENCH / "cost.md").read_text()
    bad = tmp_path / "headline.json"
    bad.write_text(json.dumps({"settings": {"entrants": ["lqr"]}}))
    assert "headline.json: no field settings.tasks" in _refused(["cost", str(bad)], capsys)
    bad.write_text(json.dumps({"settings": {"entrants": ["lqr"], "tasks": [{"seeds": 2}]}}))
    assert "settings.tasks[0] has no 'entrant'" in _refused(["cost", str(bad)], capsys)
    assert "no such file" in _refused(["cost", str(tmp_path / "none.json")], capsys)


def test_the_classical_set_is_every_classical_entrant_pid_included() -> None:
    """Without --classical, a learned agent meets every classical headline entrant of its
    actuator set: pid included (pid+g with the guidance pairs); passive is no contender."""
    assert target.classical_entrants(("ppo", "ppo-memory", "sac")) == (
        "pid",
        "lqr",
        "lqr-preview",
        "mpc",
    )
    assert target.classical_entrants(("ppo-guidance",)) == ("pid+g", "lqr+g", "lqr-preview+g")
    spec = target.TargetSpec(("ppo-memory",), (), (RUNS[0],))
    assert spec.classical == ("pid", "lqr", "lqr-preview", "mpc")
    with pytest.raises(ValueError, match="different actuator sets"):
        target.classical_entrants(("ppo", "ppo-guidance"))


def test_comfort_takes_guided_entrants() -> None:
    """``name+g`` (the controller with the guidance pairs too), as the headline labels its
    guided entrants; an unknown one is refused naming it."""
    seeds = (1_000_000, 1_000_001)
    spec = comfort.ComfortSpec(("pid+g", "ppo-guidance"), seeds, reference="lqr+g")
    assert spec.names == ["lqr+g", "pid+g", "ppo-guidance"]
    with pytest.raises(ValueError, match="'nope\\+g'"):
        comfort.ComfortSpec(("nope+g",), seeds)


def test_the_guided_target_reproduces_its_published_files(tmp_path: Path) -> None:
    """docs/benchmark/target-guided: ppo-guidance and ppo-residual-guidance against the
    default (guided) classical set, from the headline and the guided entrants' comfort."""
    out = tmp_path / "tg"
    argv = ["target", "--learned", "ppo-guidance", "ppo-residual-guidance", "--runs", str(RUNS[0])]
    argv += ["--comfort", str(BENCH / "comfort-guided" / "comfort.json"), "--out", str(out)]
    assert main(argv) == 0
    published = BENCH / "target-guided"
    assert (out / "target.md").read_text() == (published / "target.md").read_text()
    doc = json.loads((published / "target.json").read_text())
    assert doc["classical"] == ["pid+g", "lqr+g", "lqr-preview+g"]
