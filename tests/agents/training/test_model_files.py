"""A model file that holds no saved model (empty, not a zip, a zip without SB3's ``data``)
is an error naming the file: ``train.py --eval-only`` stops with exit 2 before evaluating,
and ``--resume`` skips such a checkpoint naming its model file (tiny preset, seconds)."""

from __future__ import annotations

import json
import shutil
import zipfile
from collections.abc import Callable
from pathlib import Path

import pytest

pytest.importorskip("stable_baselines3")
import torch  # noqa: E402

from agents.cli import train as cli  # noqa: E402
from agents.training import checkpoints as ck  # noqa: E402
from agents.training import experiment  # noqa: E402

TINY = ["--preset", "tiny", "--no-progress", "--n-envs", "2"]
TINY += ["--checkpoint-freq", "512", "--eval-freq", "1000000"]

torch.set_num_threads(1)


def _empty(p: Path) -> None:
    p.write_bytes(b"")


def _not_a_zip(p: Path) -> None:
    p.write_text("not a model\n")


def _zip_without_data(p: Path) -> None:
    with zipfile.ZipFile(p, "w") as z:
        z.writestr("policy.pth", b"weights")


BROKEN: dict[str, tuple[Callable[[Path], None], str]] = {
    "empty": (_empty, "is not a zip file"),
    "text": (_not_a_zip, "is not a zip file"),
    "zip without data": (_zip_without_data, "holds no saved model"),
}


@pytest.fixture(scope="module")
def two_checkpoints(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("models") / "run"
    cfg = cli.resolve_config([*TINY, "--no-eval", "--out", str(out), "--timesteps", "1024"])
    experiment.train(cfg)
    assert sorted(c.steps for c in ck.list_checkpoints(out)) == [512, 1024]
    return out


def _files(out: Path) -> dict[Path, bytes]:
    return {f: f.read_bytes() for f in out.rglob("*") if f.is_file()}


@pytest.mark.parametrize("kind", list(BROKEN))
def test_eval_only_on_a_broken_model_file_names_it(
    kind: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    out.mkdir()
    break_it, what = BROKEN[kind]
    break_it(out / "model.zip")
    (out / "training_log.json").write_text(json.dumps({"algo": "ppo"}))
    before = _files(out)
    assert cli.main([*TINY, "--out", str(out), "--eval-only"]) == 2
    err = capsys.readouterr().err
    assert f"the model file {out / 'model.zip'} {what}" in err, err
    assert "Traceback" not in err
    assert _files(out) == before  # no report, nothing else written


def test_eval_only_without_a_model_file_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    assert cli.main([*TINY, "--out", str(out), "--eval-only"]) == 2
    assert f"no model.zip in {out}" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize("kind", list(BROKEN))
def test_resume_names_a_checkpoint_model_that_holds_no_model(
    kind: str, two_checkpoints: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Broken models whose manifests vouch for them (size and hash): only the model file
    itself can tell."""
    out = Path(shutil.copytree(two_checkpoints, tmp_path / "run"))
    break_it, what = BROKEN[kind]
    for steps in (512, 1024):
        model = out / "checkpoints" / f"model_{steps}_steps.zip"
        break_it(model)
        mpath = out / "checkpoints" / f"model_state_{steps}_steps.json"
        manifest = json.loads(mpath.read_text())
        manifest["files"]["model"].update(bytes=model.stat().st_size, sha256=ck._sha256(model))
        mpath.write_text(json.dumps(manifest))
    args = [*TINY, "--no-eval", "--out", str(out), "--timesteps", "1536", "--resume"]
    with pytest.warns(ck.CheckpointWarning) as warned:
        assert cli.main(args) == 2
    for steps in (1024, 512):
        assert any(f"model_{steps}_steps.zip {what}" in str(w.message) for w in warned)
    err = capsys.readouterr().err
    assert f"its model file model_512_steps.zip {what}" in err, err
