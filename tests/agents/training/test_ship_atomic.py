"""``train.py --ship`` writes every file of agents/shipped/<name>/ atomically: a copy cut
short (Ctrl-C, SIGTERM, a full disk) leaves the agent shipped before, never a truncated
model. The destination is redirected to a temporary folder."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from agents.training import shipping


@pytest.fixture
def run_and_dest(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[Path, Path]:
    run = tmp_path / "run"
    (run / "report").mkdir(parents=True)
    (run / "model.zip").write_bytes(b"new model " * 1000)
    (run / "vecnormalize.pkl").write_bytes(b"new stats")
    (run / "training_log.json").write_text(json.dumps({"algo": "ppo"}))
    (run / "report" / "report.md").write_text("# report\n![fig](figures/a.png)\ntext\n")
    dest = tmp_path / "shipped" / "ppo"
    dest.mkdir(parents=True)
    for name in shipping.SHIP_FILES:
        (dest / name).write_bytes(b"the agent shipped before")
    monkeypatch.setattr(shipping, "check_ship_destination", lambda name: dest)
    return run, dest


def test_ship_copies_the_run(run_and_dest: tuple[Path, Path]) -> None:
    run, dest = run_and_dest
    assert shipping.ship(run, "ppo") == dest
    for name in shipping.SHIP_FILES:
        assert (dest / name).read_bytes() == (run / name).read_bytes()
    assert (dest / "eval_report.md").read_text() == "# report\ntext\n"
    assert sorted(p.name for p in dest.iterdir()) == sorted(
        [*shipping.SHIP_FILES, "eval_report.md"]
    )


def test_an_interrupted_ship_leaves_the_agent_shipped_before(
    run_and_dest: tuple[Path, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    run, dest = run_and_dest

    def cut_short(src: Path, dst: Path) -> None:  # half the bytes, then the signal
        Path(dst).write_bytes(Path(src).read_bytes()[:100])
        raise KeyboardInterrupt

    monkeypatch.setattr(shutil, "copy2", cut_short)
    with pytest.raises(KeyboardInterrupt):
        shipping.ship(run, "ppo")
    for name in shipping.SHIP_FILES:
        assert (dest / name).read_bytes() == b"the agent shipped before", name
    assert sorted(p.name for p in dest.iterdir()) == sorted(shipping.SHIP_FILES)  # no temp
