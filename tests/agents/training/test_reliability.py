"""No lost or mixed training work: interrupt and resume, damaged checkpoints, re-runs into
the same --out, resume with another configuration, and option checking (all with the
``tiny`` preset; the SIGINT test runs train.py in a subprocess: ~10 s)."""

from __future__ import annotations

import json
import os
import queue
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")
import torch  # noqa: E402
from stable_baselines3 import PPO  # noqa: E402

from agents.cli import train as cli  # noqa: E402
from agents.training import checkpoints as ck  # noqa: E402
from agents.training import experiment  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
TINY = ["--preset", "tiny", "--no-eval", "--no-progress"]
ROLLOUT_2_ENVS = 2 * 256  # tiny preset: n_steps 256

torch.set_num_threads(1)


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    env["PYTHONUNBUFFERED"] = "1"
    return env


def _train(*args: str) -> dict:
    return experiment.train(cli.resolve_config([*TINY, *args]))


def _manifest_steps(out: Path) -> list[int]:
    return sorted(c.steps for c in ck.list_checkpoints(out) if c.manifest is not None)


def _fingerprint(*args: str) -> dict:
    return experiment.run_fingerprint(cli.resolve_config([*TINY, *args]))


# ---- SIGINT: a checkpoint is saved, --resume continues from exactly its weights -------------


@pytest.mark.parametrize("overlap", [False, True], ids=["plain", "overlapped-updates"])
def test_sigint_saves_checkpoint_and_resume_continues(tmp_path: Path, overlap: bool) -> None:
    out = tmp_path / "run"
    # no periodic checkpoint can happen: whatever is saved, the interrupt saved it
    args = [
        *TINY,
        "--overlap-updates" if overlap else "--no-overlap-updates",
        "--timesteps",
        "1000000",
        "--n-envs",
        "2",
        "--out",
        str(out),
        "--checkpoint-freq",
        "1000000000",
        "--checkpoint-interval-s",
        "1e9",
        "--eval-freq",
        "1000000000",
        "--verbose",
        "1",
    ]
    proc = subprocess.Popen(
        [sys.executable, str(ROOT / "train.py"), *args],
        cwd=ROOT,
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    lines: queue.Queue[str] = queue.Queue()
    threading.Thread(target=lambda: [lines.put(ln) for ln in proc.stdout], daemon=True).start()
    started = updated = False
    deadline = time.monotonic() + 120
    try:
        while not updated:  # "training started", then SB3's log table after an update
            line = lines.get(timeout=max(0.1, deadline - time.monotonic()))
            started = started or line.startswith("training started")
            updated = started and "n_updates" in line
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err[-2000:]
    m = re.search(r"interrupted at (\d+) timesteps", err)
    assert m, err[-2000:]
    steps = int(m.group(1))
    # the state at the start of the interrupted rollout: a whole number of rollouts, >= 1 update
    assert steps >= ROLLOUT_2_ENVS and steps % ROLLOUT_2_ENVS == 0
    assert _manifest_steps(out) == [steps]
    ckpt_model = out / "checkpoints" / f"model_{steps}_steps.zip"
    assert PPO.load(str(ckpt_model), device="cpu").num_timesteps == steps

    # the same command with --resume (in-process, to keep the test short)
    log = experiment.train(
        cli.resolve_config([*args, "--verbose", "0", "--timesteps", str(steps + 1024), "--resume"])
    )
    assert log == json.loads((out / "training_log.json").read_text())
    assert log["num_timesteps"] == steps + 1024  # the requested total, nothing counted twice
    assert log["resumed_from"]["num_timesteps"] == steps
    # right after loading, the resumed model held the checkpoint's weights, not fresh ones
    saved = ck.policy_digest(PPO.load(str(ckpt_model), device="cpu"))
    assert log["resumed_from"]["policy_sha256"] == saved
    cfg = cli.resolve_config(args)
    venv = experiment.make_vec_env(experiment.env_config(cfg), 2, 0, "native")
    fresh = experiment.build_model(cfg, venv, None)
    assert ck.policy_digest(fresh) != saved
    venv.close()


# ---- damaged checkpoints --------------------------------------------------------------------


@pytest.fixture(scope="module")
def two_checkpoints(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("ckpt") / "run"
    _train("--out", str(out), "--timesteps", "2048", "--checkpoint-freq", "1024")
    assert _manifest_steps(out) == [1024, 2048]
    return out


def _copy(src: Path, tmp_path: Path) -> Path:
    dst = tmp_path / "run"
    shutil.copytree(src, dst)
    return dst


def _truncate(p: Path) -> None:
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])


def _junk(p: Path) -> None:  # same length: only the hash can tell
    p.write_bytes(np.random.default_rng(0).bytes(p.stat().st_size))


def _junk_with_matching_manifest(p: Path) -> None:
    """Junk whose size and hash the manifest agrees with: only loading can tell."""
    _junk(p)
    steps = int(re.search(r"_(\d+)_steps", p.name).group(1))
    mpath = p.parent / f"model_state_{steps}_steps.json"
    man = json.loads(mpath.read_text())
    for info in man["files"].values():
        if info["name"] == p.name:
            info["bytes"] = p.stat().st_size
            info["sha256"] = ck._sha256(p)
    mpath.write_text(json.dumps(man))


CORRUPTIONS = {
    "truncated model": ("model_2048_steps.zip", _truncate),
    "junk model": ("model_2048_steps.zip", _junk),
    "junk vecnormalize": ("model_vecnormalize_2048_steps.pkl", _junk),
    "truncated manifest": ("model_state_2048_steps.json", _truncate),
    "junk the manifest vouches for": ("model_2048_steps.zip", _junk_with_matching_manifest),
    "missing vecnormalize": ("model_vecnormalize_2048_steps.pkl", lambda p: p.unlink()),
}


@pytest.mark.parametrize("kind", list(CORRUPTIONS))
def test_damaged_newest_checkpoint_falls_back_to_older(
    two_checkpoints: Path, tmp_path: Path, kind: str
) -> None:
    out = _copy(two_checkpoints, tmp_path)
    name, corrupt = CORRUPTIONS[kind]
    corrupt(out / "checkpoints" / name)
    fp = _fingerprint("--out", str(out))
    venv = experiment.make_vec_env(experiment.env_config(cli.resolve_config(TINY)), 4, 0, "native")
    with pytest.warns(ck.CheckpointWarning, match="2048 steps"):
        res = ck.load_latest(out, fp, "ppo", venv, "cpu")
    assert res.steps == 1024 and res.model.num_timesteps == 1024
    older = PPO.load(str(out / "checkpoints" / "model_1024_steps.zip"), device="cpu")
    assert ck.policy_digest(res.model) == ck.policy_digest(older)
    venv.close()


def test_resume_after_truncated_checkpoint_end_to_end(
    two_checkpoints: Path, tmp_path: Path
) -> None:
    out = _copy(two_checkpoints, tmp_path)
    _truncate(out / "checkpoints" / "model_2048_steps.zip")
    with pytest.warns(ck.CheckpointWarning):
        log = _train("--out", str(out), "--resume", "--timesteps", "3072")
    assert log["resumed_from"]["num_timesteps"] == 1024
    assert log["num_timesteps"] == 3072
    assert "model_2048_steps.zip" in log["resumed_from"]["skipped"][0]


def test_all_checkpoints_damaged_is_a_clear_error(two_checkpoints: Path, tmp_path: Path) -> None:
    out = _copy(two_checkpoints, tmp_path)
    for f in (out / "checkpoints").glob("model_*_steps.zip"):
        _truncate(f)
    with pytest.warns(ck.CheckpointWarning), pytest.raises(ck.CheckpointError, match="no usable"):
        _train("--out", str(out), "--resume", "--timesteps", "3072")


def test_checkpoint_files_are_written_atomically(two_checkpoints: Path) -> None:
    """No temporary file is left and every file matches its manifest."""
    names = [f.name for f in (two_checkpoints / "checkpoints").iterdir()]
    assert not [n for n in names if n.startswith(".") or n.endswith(".tmp")], names
    for c in ck.list_checkpoints(two_checkpoints):
        assert ck.verify_files(c) is None


# ---- one run per directory; resume only the same configuration ----------------------------


def test_rerun_into_same_out_is_refused_and_overwrite_replaces(tmp_path: Path) -> None:
    out = tmp_path / "run"
    _train("--out", str(out), "--timesteps", "3072", "--checkpoint-freq", "1024")
    assert _manifest_steps(out) == [1024, 2048, 3072]
    before = {f: f.read_bytes() for f in out.rglob("*") if f.is_file()}
    assert cli.main([*TINY, "--out", str(out), "--timesteps", "1024"]) == 2
    assert {f: f.read_bytes() for f in out.rglob("*") if f.is_file()} == before  # untouched
    (out / "notes.txt").write_text("mine")
    log = _train("--out", str(out), "--timesteps", "1024", "--seed", "5", "--overwrite")
    assert log["num_timesteps"] == 1024
    # the first run's later checkpoints are gone: a --resume cannot continue the old run
    assert _manifest_steps(out) == [1024]
    assert json.loads((out / "run_config.json").read_text())["config"]["seed"] == 5
    assert (out / "notes.txt").read_text() == "mine"  # not a file of the run: kept


def test_resume_with_another_configuration_is_refused(
    two_checkpoints: Path, tmp_path: Path
) -> None:
    out = _copy(two_checkpoints, tmp_path)
    before = sorted(f.name for f in (out / "checkpoints").iterdir())
    for extra, what in (
        (["--env-kwarg", "gap_weight=3"], "env.gap_weight"),
        (["--n-envs", "2"], "n_envs"),
        (["--algo", "sac"], "algo"),
        (["--scenario", "paper-1000-straight"], "scenario"),
        (["--track-length-m", "300"], "env.track_length_m"),
        (["--seed", "1"], "seed"),
    ):
        with pytest.raises(ck.CheckpointError, match=re.escape(what)):
            _train("--out", str(out), "--resume", "--timesteps", "3072", *extra)
    assert sorted(f.name for f in (out / "checkpoints").iterdir()) == before
    assert cli.main([*TINY, "--out", str(out), "--resume", "--n-envs", "2"]) == 2


def test_resume_without_checkpoint_and_before_training(tmp_path: Path) -> None:
    with pytest.raises(experiment.RunDirError, match="no checkpoint"):
        _train("--out", str(tmp_path / "missing"), "--resume")
    assert not (tmp_path / "missing").exists()
    (tmp_path / "empty").mkdir()
    with pytest.raises(ck.CheckpointError, match="no usable checkpoint"):
        _train("--out", str(tmp_path / "empty"), "--resume")


# ---- options are checked before anything is created -----------------------------------------


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--timesteps", "1.9"], "expected an integer, got '1.9'"),
        (["--timesteps", "inf"], "expected an integer"),
        (["--n-envs", "2.5"], "expected an integer"),
        (["--seed", "-1"], "a run trains on seeds of the training range [0, 99999]"),
        (["--seed", str(2**32)], "a run trains on seeds of the training range [0, 99999]"),
        (["--checkpoint-interval-s", "0"], "--checkpoint-interval-s must be a positive"),
        (["--track-length-m", "1e9"], "MAX_PROFILE_BYTES"),
        (["--env-kwarg", "speed_kmh=1e9"], "speed_kmh=1000000000.0 is too fast"),
        (["--resume", "--overwrite"], "exclude each other"),
    ],
)
def test_bad_options_fail_before_anything_is_created(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as exc:
        cli.main(["--preset", "tiny", "--no-progress", "--out", str(out), *args])
    assert exc.value.code == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_eval_distance_shorter_than_settling_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit):
        cli.main(["--preset", "tiny", "--out", str(tmp_path / "r"), "--eval-distance-km", "0.2"])
    err = capsys.readouterr().err
    assert "--eval-distance-km=0.2" in err and "raise --eval-distance-km to >=" in err
    assert not (tmp_path / "r").exists()
    assert cli.resolve_config(["--preset", "tiny", "--no-eval", "--eval-distance-km", "0.2"])


def test_numpy_scalars_are_accepted_as_train_options() -> None:
    cfg = cli.resolve_config(TINY)
    cfg.update(
        timesteps=np.int64(1024),
        n_envs=np.int64(2),
        seed=np.int64(7),
        eval_seeds=np.int32(1),
        track_length_m=np.float32(150.0),
        checkpoint_freq=np.float64(512.0),
        env_kwargs={"gap_weight": np.float32(3.0), "sensor_delay": np.int64(1)},
    )
    cli._validate(cfg, cli.build_parser())
    assert cfg["timesteps"] == 1024 and type(cfg["timesteps"]) is int
    assert type(cfg["seed"]) is int and type(cfg["track_length_m"]) is float
    assert type(cfg["env_kwargs"]["gap_weight"]) is float
    fp = experiment.run_fingerprint(cfg)
    assert fp["env"]["track_length_m"] == 150.0 and fp["seed"] == 7
    json.dumps(fp, allow_nan=False)


# ---- checkpoint schedule, SAC, --eval-only ----------------------------------------------------


def test_wall_time_interval_writes_checkpoints(tmp_path: Path) -> None:
    out = tmp_path / "run"
    _train(
        "--out",
        str(out),
        "--timesteps",
        "2048",
        "--checkpoint-freq",
        "1000000000",
        "--checkpoint-interval-s",
        "0.001",
        "--eval-freq",
        "1000000000",
    )
    # at a rollout start once the interval has passed (rollouts of 4 x 256), and at the end
    reasons = {c.steps: c.manifest["reason"] for c in ck.list_checkpoints(out)}
    assert reasons == {1024: "interval", 2048: "final"}


def test_sac_checkpoint_keeps_replay_buffer_and_resumes(tmp_path: Path) -> None:
    out = tmp_path / "sac"
    common = ["--algo", "sac", "--out", str(out), "--checkpoint-freq", "256"]
    _train(*common, "--timesteps", "512")
    newest = ck.list_checkpoints(out)[0]
    assert newest.steps == 512 and "replay_buffer" in newest.manifest["files"]
    venv = experiment.make_vec_env(experiment.env_config(cli.resolve_config(TINY)), 4, 0, "native")
    res = ck.load_latest(out, _fingerprint(*common), "sac", venv, "cpu")
    assert res.model.replay_buffer.size() * 4 == 512  # 4 envs: 128 rows of 4 transitions
    venv.close()
    log = _train(*common, "--timesteps", "768", "--resume")
    assert log["num_timesteps"] == 768 and log["resumed_from"]["num_timesteps"] == 512


def test_eval_only_does_not_replace_a_report_silently(
    two_checkpoints: Path, tmp_path: Path
) -> None:
    out = _copy(two_checkpoints, tmp_path)
    (out / "report").mkdir()
    (out / "report" / "report.md").write_text("the first report")
    t0 = time.perf_counter()
    assert cli.main(["--preset", "tiny", "--no-progress", "--out", str(out), "--eval-only"]) == 2
    assert time.perf_counter() - t0 < 5
    assert (out / "report" / "report.md").read_text() == "the first report"
