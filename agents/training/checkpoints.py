"""Resumable checkpoints of a training run: written atomically, verified on load, saved on
interrupt.

A checkpoint at ``N`` environment steps is four files in ``<out>/checkpoints/`` (the first
three named as SB3's ``CheckpointCallback`` names them):

* ``model_<N>_steps.zip`` — the model (policy, optimiser state, step count);
* ``model_vecnormalize_<N>_steps.pkl`` — the ``VecNormalize`` statistics;
* ``model_replay_buffer_<N>_steps.pkl`` — SAC only: the replay buffer;
* ``model_state_<N>_steps.json`` — the manifest, written last: the step count, the run's
  resolved configuration (:func:`agents.training.experiment.run_fingerprint`), the
  Python / NumPy / torch random states (:mod:`agents.training.run_state`), the best
  evaluation reward so far, the wall time so far and the SHA-256 of every file above.

Every file goes to a temporary name in the same directory and is renamed over its target
(:mod:`agents.evaluation.outputs`), so an interruption leaves either a complete file or
none; a checkpoint without its manifest does not exist. On ``--resume``
(:func:`load_latest`) the newest checkpoint's manifest is checked field by field (every
field a resume reads: :func:`manifest_problem` names the one missing or invalid), its files
against the manifest (sizes and hashes), and it is loaded; if it is damaged (truncated,
junk bytes, unreadable, a model file that holds no saved model), a warning names the
problem and the next older one is tried. The newest *intact* checkpoint must come from
the same configuration as the resumed command
(:func:`~agents.training.run_state.config_differences`; only
``--timesteps`` and bookkeeping such as ``--eval-freq`` may change), else the resume is
refused.

When checkpoints are written (the SB3 callback of
:mod:`agents.training.checkpoint_callback`): at the start of a rollout once
``checkpoint_freq`` environment steps or ``checkpoint_interval_s`` seconds of wall time
have passed since the last one (defaults 250 000 steps / 300 s: at most five minutes of
work are lost to a hard kill), at the end of training, and when the run is interrupted
(SIGINT / Ctrl-C or SIGTERM, :mod:`agents.training.interrupts`): training stops at the next
environment step and the state at the start of the current rollout — the policy as last
updated, with the step count, normalisation statistics and random states of that moment
— is saved, so the steps of the unfinished rollout (never learned from) are not counted.
A second interrupt aborts at once without saving.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import time
import warnings
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agents.evaluation.outputs import atomic_path, atomic_write_text
from agents.training.run_state import config_differences, rng_state
from agents.training.run_state import policy_digest as policy_digest
from hyperloop_env.config import canonical_keywords

CHECKPOINT_DIR = "checkpoints"
MANIFEST_FORMAT = 1
MANIFEST_RE = re.compile(r"^model_state_(\d+)_steps\.json$")
MODEL_RE = re.compile(r"^model_(\d+)_steps\.zip$")


class CheckpointError(ValueError):
    """No usable checkpoint, or one from another configuration (the message says which)."""


class CheckpointWarning(UserWarning):
    """A damaged or unusable checkpoint was skipped."""


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _fsync(path: Path) -> None:
    with open(path, "rb") as fh:
        os.fsync(fh.fileno())


# --------------------------------------------------------------------------------------
# writing
# --------------------------------------------------------------------------------------


def checkpoint_files(steps: int) -> dict[str, str]:
    return {
        "model": f"model_{steps}_steps.zip",
        "vecnormalize": f"model_vecnormalize_{steps}_steps.pkl",
        "replay_buffer": f"model_replay_buffer_{steps}_steps.pkl",
        "manifest": f"model_state_{steps}_steps.json",
    }


def save_checkpoint(
    out: Path,
    model: Any,
    vecnormalize: Any,
    *,
    steps: int,
    fingerprint: dict[str, Any],
    reason: str,
    rng: dict[str, Any] | None = None,
    best_mean_reward: float | None = None,
    wall_time_s: float = 0.0,
    command: str = "",
    curriculum: dict[str, Any] | None = None,
) -> Path:
    """Write the checkpoint of ``steps`` steps (see the module docstring); returns the
    manifest path. ``model.num_timesteps`` is saved as ``steps``; ``curriculum``: the
    severity curriculum's state (:mod:`agents.training.curriculum`), if the run has one."""
    ckpt_dir = out / CHECKPOINT_DIR
    ckpt_dir.mkdir(parents=True, exist_ok=True)
    names = checkpoint_files(steps)
    saved_steps = model.num_timesteps
    model.num_timesteps = steps
    try:
        written = {}
        # an OverlappedPPO: saved with every update of the rollouts collected so far
        settled = getattr(model, "settled", None)
        with atomic_path(ckpt_dir / names["model"]) as tmp, settled() if settled else nullcontext():
            model.save(str(tmp))
            _fsync(tmp)
        written["model"] = names["model"]
        with atomic_path(ckpt_dir / names["vecnormalize"]) as tmp:
            vecnormalize.save(str(tmp))
            _fsync(tmp)
        written["vecnormalize"] = names["vecnormalize"]
        if getattr(model, "replay_buffer", None) is not None:
            with atomic_path(ckpt_dir / names["replay_buffer"]) as tmp:
                model.save_replay_buffer(str(tmp))
                _fsync(tmp)
            written["replay_buffer"] = names["replay_buffer"]
    finally:
        model.num_timesteps = saved_steps
    files = {}
    for role, name in written.items():
        p = ckpt_dir / name
        files[role] = {"name": name, "bytes": p.stat().st_size, "sha256": _sha256(p)}
    manifest = {
        "format": MANIFEST_FORMAT,
        "num_timesteps": int(steps),
        "reason": reason,
        "saved_at": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "command": command,
        "config": fingerprint,
        "files": files,
        "rng": rng if rng is not None else rng_state(),
        "best_mean_reward": best_mean_reward
        if best_mean_reward is not None and math.isfinite(best_mean_reward)
        else None,
        "wall_time_s": float(wall_time_s),
    }
    if curriculum is not None:
        manifest["curriculum"] = curriculum
    path = ckpt_dir / names["manifest"]
    atomic_write_text(path, json.dumps(manifest) + "\n")
    return path


# --------------------------------------------------------------------------------------
# reading
# --------------------------------------------------------------------------------------


@dataclass
class Checkpoint:
    """One checkpoint found in a run directory (``manifest`` None: no readable manifest)."""

    steps: int
    directory: Path
    manifest: dict[str, Any] | None
    problem: str | None = None

    def path(self, role: str) -> Path:
        if self.manifest is not None and role in self.manifest["files"]:
            return self.directory / self.manifest["files"][role]["name"]
        return self.directory / checkpoint_files(self.steps)[role]


def list_checkpoints(out: Path) -> list[Checkpoint]:
    """Every checkpoint in ``<out>/checkpoints`` (newest first), each with its manifest
    or the reason it cannot be used (``problem``)."""
    ckpt_dir = out / CHECKPOINT_DIR
    if not ckpt_dir.is_dir():
        return []
    steps_seen: dict[int, Checkpoint] = {}
    for f in ckpt_dir.iterdir():
        m = MANIFEST_RE.match(f.name)
        if m:
            steps = int(m.group(1))
            manifest, problem = _read_manifest(f, steps)
            steps_seen[steps] = Checkpoint(steps, ckpt_dir, manifest, problem)
    for f in ckpt_dir.iterdir():
        m = MODEL_RE.match(f.name)
        if m and int(m.group(1)) not in steps_seen:
            steps = int(m.group(1))
            steps_seen[steps] = Checkpoint(
                steps,
                ckpt_dir,
                None,
                "no manifest (model_state_<N>_steps.json): incomplete, or written by an older "
                "train.py without its configuration",
            )
    return [steps_seen[s] for s in sorted(steps_seen, reverse=True)]


def _read_manifest(path: Path, steps: int) -> tuple[dict[str, Any] | None, str | None]:
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        return None, f"unreadable manifest {path.name}: {type(exc).__name__}: {exc}"
    if not isinstance(data, dict) or data.get("format") != MANIFEST_FORMAT:
        return None, f"manifest {path.name} is not a format-{MANIFEST_FORMAT} checkpoint manifest"
    problem = manifest_problem(data, steps)
    if problem is not None:
        return None, f"manifest {path.name}: {problem}"
    return data, None


# --------------------------------------------------------------------------------------
# what a manifest must hold: every field a resume reads
# --------------------------------------------------------------------------------------


class _Invalid(ValueError):
    """A manifest field is missing or invalid (the message names it)."""


def _field(data: dict[str, Any], name: str, prefix: str = "") -> Any:
    if not isinstance(data, dict) or name not in data:
        raise _Invalid(f"field {prefix + name!r} is missing")
    return data[name]


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def _int_list(v: Any, name: str, length: int, lo: int, hi: int) -> None:
    if not isinstance(v, list) or len(v) != length:
        raise _Invalid(f"field {name!r} must be a list of {length} integers")
    if not all(_is_int(x) and lo <= x <= hi for x in v):
        raise _Invalid(f"field {name!r} must hold integers in [{lo}, {hi}]")


def _check_files(files: Any) -> None:
    if not isinstance(files, dict):
        raise _Invalid("field 'files' must be an object")
    for role in ("model", "vecnormalize"):
        _field(files, role, "files.")
    for role, info in files.items():
        where = f"files.{role}."
        if role not in ("model", "vecnormalize", "replay_buffer"):
            raise _Invalid(f"field 'files.{role}' is not a checkpoint file")
        name = _field(info, "name", where)
        if not isinstance(name, str) or not name or Path(name).name != name or name == "..":
            raise _Invalid(f"field {where + 'name'!r} must be a file name in the checkpoint folder")
        if not _is_int(_field(info, "bytes", where)) or info["bytes"] < 0:
            raise _Invalid(f"field {where + 'bytes'!r} must be an integer >= 0")
        digest = _field(info, "sha256", where)
        if not isinstance(digest, str) or not re.fullmatch(r"[0-9a-f]{64}", digest):
            raise _Invalid(f"field {where + 'sha256'!r} must be 64 hexadecimal digits")


def _torch_state_bytes() -> int:
    import torch

    return int(torch.get_rng_state().numel())


def _check_rng(rng: Any) -> None:
    """The random states :func:`~agents.training.run_state.set_rng_state` restores."""
    if not isinstance(rng, dict):
        raise _Invalid("field 'rng' must be an object")
    py = _field(rng, "python", "rng.")
    if not isinstance(py, list) or len(py) != 3 or not _is_int(py[0]):
        raise _Invalid("field 'rng.python' must be [version, [625 integers], gauss]")
    _int_list(py[1], "rng.python[1]", 625, 0, 2**32 - 1)
    if py[2] is not None and not _is_number(py[2]):
        raise _Invalid("field 'rng.python[2]' must be null or a number")
    npy = _field(rng, "numpy", "rng.")
    if not isinstance(npy, list) or len(npy) != 5 or npy[0] != "MT19937":
        raise _Invalid("field 'rng.numpy' must be ['MT19937', [624 integers], pos, has_gauss, x]")
    _int_list(npy[1], "rng.numpy[1]", 624, 0, 2**32 - 1)
    if not (_is_int(npy[2]) and 0 <= npy[2] <= 624 and npy[3] in (0, 1) and _is_number(npy[4])):
        raise _Invalid("field 'rng.numpy' must end with pos in [0, 624], has_gauss 0/1, a number")
    _int_list(_field(rng, "torch", "rng."), "rng.torch", _torch_state_bytes(), 0, 255)


def manifest_problem(data: dict[str, Any], steps: int) -> str | None:
    """None if the manifest ``data`` of the checkpoint at ``steps`` holds every field a
    resume reads, valid; else which field is missing or invalid."""
    try:
        n = _field(data, "num_timesteps")
        if not _is_int(n) or n != steps:
            raise _Invalid(f"field 'num_timesteps' must be {steps} (the file's name), got {n!r}")
        if not isinstance(_field(data, "config"), dict):
            raise _Invalid("field 'config' must be an object")
        _check_files(_field(data, "files"))
        _check_rng(_field(data, "rng"))
        best = data.get("best_mean_reward")
        if best is not None and not _is_number(best):
            raise _Invalid(f"field 'best_mean_reward' must be null or a number, got {best!r}")
        wall = data.get("wall_time_s")
        if wall is not None and not (_is_number(wall) and wall >= 0):
            raise _Invalid(f"field 'wall_time_s' must be a number >= 0, got {wall!r}")
        if not isinstance(data.get("command", ""), str | None):
            raise _Invalid("field 'command' must be a string")
    except _Invalid as exc:
        return str(exc)
    return None


def verify_files(ckpt: Checkpoint) -> str | None:
    """None if every file of the checkpoint has the size and hash of its manifest, else
    what is wrong."""
    if ckpt.manifest is None:
        return ckpt.problem or "no manifest"
    for role, info in ckpt.manifest["files"].items():
        p = ckpt.directory / info["name"]
        if not p.is_file():
            return f"{role} file {p.name} is missing"
        size = p.stat().st_size
        if size != info["bytes"]:
            return f"{role} file {p.name} has {size} bytes, the manifest says {info['bytes']}"
        if _sha256(p) != info["sha256"]:
            return f"{role} file {p.name} does not match its SHA-256 in the manifest"
    return None


@dataclass
class Resumed:
    """What :func:`load_latest` loaded."""

    model: Any
    env: Any  # the training VecNormalize around the given venv
    checkpoint: Checkpoint
    skipped: list[str]

    @property
    def steps(self) -> int:
        return self.checkpoint.steps

    @property
    def manifest(self) -> dict[str, Any]:
        assert self.checkpoint.manifest is not None
        return self.checkpoint.manifest


def load_latest(
    out: Path,
    fingerprint: dict[str, Any],
    algo: str,
    venv: Any,
    device: str,
    *,
    warn: bool = True,
) -> Resumed:
    """Load the newest intact checkpoint of ``out`` (model and ``VecNormalize`` around
    ``venv``; SAC's replay buffer too), falling back past damaged ones with a
    :class:`CheckpointWarning`. Raises :class:`CheckpointError` if there is none, or if the
    newest intact one belongs to another configuration than ``fingerprint``."""
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.vec_env import VecNormalize

    from agents.controllers.learned import model_file_problem

    cls = {"ppo": PPO, "sac": SAC}[algo]
    if algo == "ppo" and fingerprint.get("overlap_updates"):  # the run's own algorithm
        from agents.training.overlap import OverlappedPPO

        cls = OverlappedPPO
    skipped: list[str] = []

    def skip(ckpt: Checkpoint, why: str) -> None:
        msg = f"checkpoint at {ckpt.steps} steps in {ckpt.directory} is unusable ({why})"
        skipped.append(msg)
        if warn:
            warnings.warn(msg + "; trying an older one", CheckpointWarning, stacklevel=3)

    for ckpt in list_checkpoints(out):
        problem = verify_files(ckpt)
        if problem is not None:
            skip(ckpt, problem)
            continue
        saved = ckpt.manifest["config"]  # type: ignore[index]
        if isinstance(saved.get("env"), dict):  # keywords saved under a former name
            saved = {**saved, "env": canonical_keywords(saved["env"])}
        diff = config_differences(saved, fingerprint)
        if diff:
            cmd = ckpt.manifest.get("command") or "unknown"  # type: ignore[union-attr]
            raise CheckpointError(
                f"--resume: the newest checkpoint in {out} ({ckpt.steps} steps) belongs to a "
                f"run with a different configuration: "
                + "; ".join(diff)
                + f". Resume with the options of that run (its last command: {cmd}; only "
                "--timesteps and the evaluation/checkpoint settings may change), or train "
                "into another --out (or pass --overwrite instead of --resume to discard it)."
            )
        unsaved = model_file_problem(ckpt.path("model"))
        if unsaved is not None:
            skip(ckpt, f"its model file {ckpt.path('model').name} {unsaved}")
            continue
        try:
            env = VecNormalize.load(str(ckpt.path("vecnormalize")), venv)
            model = cls.load(str(ckpt.path("model")), env=env, device=device)
            if algo == "sac" and "replay_buffer" in ckpt.manifest["files"]:  # type: ignore[index]
                model.load_replay_buffer(str(ckpt.path("replay_buffer")))
        except Exception as exc:  # noqa: BLE001 - any failure to load: try an older one
            skip(ckpt, f"cannot be loaded: {type(exc).__name__}: {exc}")
            continue
        if int(model.num_timesteps) != ckpt.steps:
            skip(ckpt, f"its model says {model.num_timesteps} steps")
            continue
        env.training = True
        return Resumed(model, env, ckpt, skipped)
    found = ("; ".join(skipped) + ". ") if skipped else ""
    raise CheckpointError(
        f"--resume: no usable checkpoint in {out}. {found}Looked for "
        f"{out}/{CHECKPOINT_DIR}/model_state_<N>_steps.json with its model and VecNormalize "
        "files; train without --resume first (with --overwrite to replace what is there)"
    )


def restore_eval_history(eval_callback: Any, log_dir: Path, steps: int, best: float | None) -> None:
    """Give a resumed run's ``EvalCallback`` the evaluations up to ``steps`` (from
    ``evaluations.npz``) and the best mean reward of the checkpoint."""
    import numpy as np

    if best is not None:
        eval_callback.best_mean_reward = float(best)
    f = log_dir / "evaluations.npz"
    if not f.exists():
        return
    try:
        d = np.load(f)
        keep = [i for i, t in enumerate(d["timesteps"]) if int(t) <= steps]
        eval_callback.evaluations_timesteps = [int(d["timesteps"][i]) for i in keep]
        eval_callback.evaluations_results = [list(d["results"][i]) for i in keep]
        eval_callback.evaluations_length = [list(d["ep_lengths"][i]) for i in keep]
    except Exception as exc:  # noqa: BLE001 - a damaged history is only a warning
        warnings.warn(
            f"could not read {f} ({exc}); the evaluation history restarts",
            CheckpointWarning,
            stacklevel=2,
        )
