"""A checkpoint manifest is checked field by field before a resume reads it: a damaged
field (the random states, the file list, the step count, the bookkeeping) makes the
checkpoint unusable with a message naming the manifest file and the field — the resume
falls back to an older checkpoint, or ``train.py --resume`` stops with that message (exit 2)
instead of a KeyError or a raw traceback (tiny preset, a few seconds)."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("stable_baselines3")
import torch  # noqa: E402

from agents.cli import train as cli  # noqa: E402
from agents.training import checkpoints as ck  # noqa: E402
from agents.training import experiment  # noqa: E402

TINY = ["--preset", "tiny", "--no-eval", "--no-progress", "--n-envs", "2"]
TINY += ["--checkpoint-freq", "512", "--eval-freq", "1000000"]

torch.set_num_threads(1)


@pytest.fixture(scope="module")
def two_checkpoints(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("manifest") / "run"
    experiment.train(cli.resolve_config([*TINY, "--out", str(out), "--timesteps", "1024"]))
    assert sorted(c.steps for c in ck.list_checkpoints(out)) == [512, 1024]
    return out


def _copy(src: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(src, tmp_path / "run"))


def _del(*path: str) -> Callable[[dict[str, Any]], None]:
    def damage(m: dict[str, Any]) -> None:
        for key in path[:-1]:
            m = m[key]
        del m[path[-1]]

    return damage


def _set(value: Any, *path: str | int) -> Callable[[dict[str, Any]], None]:
    def damage(m: dict[str, Any]) -> None:
        for key in path[:-1]:
            m = m[key]
        m[path[-1]] = value

    return damage


DAMAGES: dict[str, tuple[Callable[[dict[str, Any]], None], str]] = {
    "rng without python": (_del("rng", "python"), "'rng.python' is missing"),
    "rng without numpy": (_del("rng", "numpy"), "'rng.numpy' is missing"),
    "rng without torch": (_del("rng", "torch"), "'rng.torch' is missing"),
    "python state cut": (_set([3, [1, 2, 3], None], "rng", "python"), "'rng.python[1]'"),
    "numpy state cut": (_set([1, 2], "rng", "numpy", 1), "'rng.numpy[1]'"),
    "numpy state junk": (_set("abc", "rng", "numpy"), "'rng.numpy'"),
    "torch state out of range": (_set([300] * 5056, "rng", "torch"), "'rng.torch'"),
    "rng not an object": (_set([], "rng"), "'rng' must be an object"),
    "no steps": (_del("num_timesteps"), "'num_timesteps' is missing"),
    "steps a string": (_set("1024", "num_timesteps"), "'num_timesteps'"),
    "no config": (_del("config"), "'config' is missing"),
    "no model file": (_del("files", "model"), "'files.model' is missing"),
    "file outside": (_set("../../x.zip", "files", "model", "name"), "'files.model.name'"),
    "size a string": (_set("12", "files", "vecnormalize", "bytes"), "'files.vecnormalize.bytes'"),
    "best reward junk": (_set("abc", "best_mean_reward"), "'best_mean_reward'"),
    "wall time junk": (_set("abc", "wall_time_s"), "'wall_time_s'"),
}


def _damage(out: Path, steps: int, damage: Callable[[dict[str, Any]], None]) -> Path:
    path = out / "checkpoints" / f"model_state_{steps}_steps.json"
    manifest = json.loads(path.read_text())
    damage(manifest)
    path.write_text(json.dumps(manifest))
    return path


@pytest.mark.parametrize("kind", list(DAMAGES))
def test_a_damaged_manifest_stops_the_resume_naming_the_file_and_the_field(
    kind: str, two_checkpoints: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = _copy(two_checkpoints, tmp_path)
    damage, field = DAMAGES[kind]
    for steps in (512, 1024):
        _damage(out, steps, damage)
    before = {f: f.read_bytes() for f in out.rglob("*") if f.is_file()}
    args = [*TINY, "--out", str(out), "--timesteps", "1536", "--resume"]
    with pytest.warns(ck.CheckpointWarning, match="model_state_1024_steps.json"):
        assert cli.main(args) == 2
    err = capsys.readouterr().err
    assert "no usable checkpoint" in err and "model_state_1024_steps.json" in err, err
    assert field in err, err
    assert {f: f.read_bytes() for f in out.rglob("*") if f.is_file()} == before


def test_a_damaged_newest_manifest_falls_back_to_the_older_checkpoint(
    two_checkpoints: Path, tmp_path: Path
) -> None:
    out = _copy(two_checkpoints, tmp_path)
    _damage(out, 1024, _del("rng", "python"))
    cfg = cli.resolve_config([*TINY, "--out", str(out), "--timesteps", "1024", "--resume"])
    with pytest.warns(ck.CheckpointWarning, match=r"model_state_1024_steps.json: field 'rng\.py"):
        log = experiment.train(cfg)
    assert log["resumed_from"]["num_timesteps"] == 512 and log["num_timesteps"] == 1024


def test_an_intact_manifest_passes() -> None:
    from agents.training.run_state import rng_state

    files = {
        role: {"name": f"{role}.bin", "bytes": 1, "sha256": "0" * 64}
        for role in ("model", "vecnormalize")
    }
    manifest = {"num_timesteps": 5, "config": {}, "files": files, "rng": rng_state()}
    assert ck.manifest_problem(json.loads(json.dumps(manifest)), 5) is None
    assert "must be 6" in ck.manifest_problem(manifest, 6)
