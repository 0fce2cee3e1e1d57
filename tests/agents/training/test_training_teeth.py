"""Training with teeth: resume continues from the saved weights, a seed reproduces a run,
and ``python train.py`` runs end to end (tiny preset, short evaluation).

Written against the public behaviour only — the ``train.py`` command line
(``agents.cli.train.main``), the files a run leaves in ``--out`` (``*.zip`` models with
their VecNormalize ``*.pkl``, ``model.zip``, ``vecnormalize.pkl``, ``training_log.json``) and
Stable-Baselines3's own API — so that they hold while checkpointing is reworked. The one
hook is a spy on ``PPO.learn`` (SB3's public method the training loop must call): it
records the policy parameters and the observation-normalisation statistics at the moment
training continues, i.e. right after loading.
"""

from __future__ import annotations

import json
import pickle
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")
import torch  # noqa: E402
from stable_baselines3 import PPO  # noqa: E402

from agents.cli import train as cli  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
SEED = 5
BASE_ARGS = [
    "--preset",
    "tiny",
    "--no-eval",
    "--no-progress",
    "--seed",
    str(SEED),
    "--timesteps",
    "2048",
    "--checkpoint-freq",
    "1024",
    "--eval-freq",
    "1024",
]
"""4 envs × 256 steps per rollout: two PPO updates, a checkpoint after each rollout."""

torch.set_num_threads(1)


def _train(out: Path, *extra: str) -> None:
    assert cli.main([*BASE_ARGS, "--out", str(out), *extra]) == 0


def _params(model: Any) -> dict[str, torch.Tensor]:
    return {k: v.detach().clone() for k, v in model.policy.state_dict().items()}


def _load(path: Path) -> tuple[int, dict[str, torch.Tensor]]:
    m = PPO.load(str(path), device="cpu")
    return int(m.num_timesteps), _params(m)


def _same(a: dict[str, torch.Tensor], b: dict[str, torch.Tensor]) -> bool:
    return a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)


def _obs_rms(pkl: Path) -> tuple[np.ndarray, np.ndarray]:
    with pkl.open("rb") as fh:
        vn = pickle.load(fh)
    return vn.obs_rms.mean.copy(), vn.obs_rms.var.copy()


def _saved_models(out: Path) -> list[tuple[int, Path]]:
    """(num_timesteps, path) of every saved model of a run but the EvalCallback's best."""
    return sorted(
        (_load(p)[0], p) for p in out.rglob("*.zip") if "best" not in p.relative_to(out).parts
    )


def _vecnormalize_beside(model: Path) -> Path:
    """The VecNormalize statistics saved with a model (same step count / directory)."""
    if model.name == "model.zip":
        return model.with_name("vecnormalize.pkl")
    steps = "".join(c for c in model.stem if c.isdigit())
    (pkl,) = [
        p
        for p in model.parent.glob("*.pkl")
        if "vecnormalize" in p.name and "".join(c for c in p.stem if c.isdigit()) == steps
    ]
    return pkl


@pytest.fixture
def learn_spy(monkeypatch: pytest.MonkeyPatch) -> list[dict[str, Any]]:
    """Record, at every PPO.learn call, the policy parameters, num_timesteps and the training
    env's VecNormalize statistics (what training continues from)."""
    calls: list[dict[str, Any]] = []
    original = PPO.learn

    def spy(self, *args, **kwargs):
        vn = self.get_vec_normalize_env()
        calls.append(
            {
                "params": _params(self),
                "num_timesteps": int(self.num_timesteps),
                "obs_rms": None if vn is None else (vn.obs_rms.mean.copy(), vn.obs_rms.var.copy()),
            }
        )
        return original(self, *args, **kwargs)

    monkeypatch.setattr(PPO, "learn", spy)
    return calls


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("teeth") / "run"
    _train(out)
    return out


def test_same_seed_gives_identical_weights(finished_run: Path, tmp_path: Path) -> None:
    again = tmp_path / "again"
    _train(again)
    steps_a, a = _load(finished_run / "model.zip")
    steps_b, b = _load(again / "model.zip")
    assert steps_a == steps_b >= 2048
    assert _same(a, b), "two runs with the same seed gave different weights"
    rms_a = _obs_rms(finished_run / "vecnormalize.pkl")
    for x, y in zip(rms_a, _obs_rms(again / "vecnormalize.pkl"), strict=True):
        np.testing.assert_array_equal(x, y)
    # and a different seed really gives different weights (the comparison has teeth)
    other = tmp_path / "other"
    _train(other, "--seed", str(SEED + 1), "--timesteps", "1024")
    assert not _same(a, _load(other / "model.zip")[1])


def test_resume_of_a_finished_run_continues_from_its_final_weights(
    finished_run: Path, tmp_path: Path, learn_spy: list[dict[str, Any]]
) -> None:
    run = tmp_path / "run"
    shutil.copytree(finished_run, run)
    steps, final = _load(run / "model.zip")
    final_rms = _obs_rms(run / "vecnormalize.pkl")
    _train(run, "--resume", "--timesteps", str(steps + 1024))
    assert len(learn_spy) == 1
    entry = learn_spy[0]
    assert entry["num_timesteps"] == steps
    assert _same(entry["params"], final), "resume did not start from the saved model.zip"
    for x, y in zip(entry["obs_rms"], final_rms, strict=True):
        np.testing.assert_array_equal(x, y)
    after_steps, after = _load(run / "model.zip")
    assert after_steps >= steps + 1024
    assert not _same(after, final)  # and it trained further


def test_resume_of_an_interrupted_run_continues_from_the_newest_checkpoint(
    finished_run: Path, tmp_path: Path, learn_spy: list[dict[str, Any]]
) -> None:
    """An interrupted run has checkpoints but no final model: resume loads the newest
    checkpoint's weights and its VecNormalize statistics."""
    run = tmp_path / "run"
    shutil.copytree(finished_run, run)
    for name in ("model.zip", "vecnormalize.pkl", "training_log.json"):
        (run / name).unlink()
    saved = _saved_models(run)
    assert len(saved) >= 2, "the run saved fewer than two checkpoints"
    newest_steps, newest = saved[-1]
    assert saved[0][0] < newest_steps
    _, newest_params = _load(newest)
    newest_rms = _obs_rms(_vecnormalize_beside(newest))
    _train(run, "--resume", "--timesteps", str(newest_steps + 1024))
    assert len(learn_spy) == 1
    entry = learn_spy[0]
    assert entry["num_timesteps"] == newest_steps
    assert _same(entry["params"], newest_params), "resume did not load the newest checkpoint"
    for x, y in zip(entry["obs_rms"], newest_rms, strict=True):
        np.testing.assert_array_equal(x, y)
    # a fresh model (what a broken resume would build) has other weights
    _, fresh = _load(saved[0][1])
    assert not _same(fresh, newest_params)


_NO_PNG = """
import runpy, sys
from pathlib import Path
import matplotlib
matplotlib.use("Agg")
import matplotlib.figure
# figures are tested in tests/agents/evaluation; here the 48 PNGs would cost a minute
matplotlib.figure.Figure.tight_layout = lambda self, *a, **k: None
matplotlib.figure.Figure.savefig = lambda self, path, *a, **k: Path(path).write_bytes(b"")
sys.argv = sys.argv[1:]
runpy.run_path(sys.argv[0], run_name="__main__")
"""


def test_train_py_end_to_end_tiny(tmp_path: Path) -> None:
    """``python train.py`` as a user runs it (the script itself, as ``__main__``, in a new
    process): train with the tiny preset, then the STS evaluation of the agent and the three
    baselines on the four paper conditions over the preset's 0.7 km, the report written.
    Only the PNG rendering is stubbed out (matplotlib's savefig), to keep this in the
    default suite."""
    out = tmp_path / "e2e"
    t0 = time.perf_counter()
    r = subprocess.run(
        [
            sys.executable,
            "-c",
            _NO_PNG,
            str(ROOT / "train.py"),
            "--preset",
            "tiny",
            "--out",
            str(out),
            "--no-progress",
            "--seed",
            "1",
        ],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=ROOT,
    )
    wall = time.perf_counter() - t0
    assert r.returncode == 0, r.stderr[-3000:]
    assert "STS report" in r.stdout
    assert (out / "model.zip").exists() and (out / "report" / "report.md").exists()
    res = json.loads((out / "report" / "results.json").read_text())
    cases = {(x["metrics"]["controller"], x["metrics"]["condition"]) for x in res["results"]}
    # the trained agent is named by its run directory, never the shipped agent's "ppo"
    assert {c for c, _ in cases} == {"passive", "pid", "lqr", str(out)}
    assert len(cases) == 16
    assert "Verdict:" in r.stdout and "What this can resolve" in r.stdout
    assert res["settings"]["distance_km"] <= 1.0  # the preset's short evaluation (0.7 km)
    assert len(list((out / "report" / "figures").glob("*.png"))) == 48 + 1  # + comparison
    log = json.loads((out / "training_log.json").read_text())
    assert log["num_timesteps"] >= 4096 and log["seed"] == 1
    print(f"train.py --preset tiny end to end: {wall:.0f} s")  # ~20 s on an idle 2-core machine
