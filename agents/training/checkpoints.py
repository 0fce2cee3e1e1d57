"""Resumable checkpoints of a training run: written atomically, verified on load, saved on
interrupt.

A checkpoint at ``N`` environment steps is four files in ``<out>/checkpoints/`` (the first
three named as SB3's ``CheckpointCallback`` names them):

* ``model_<N>_steps.zip`` — the model (policy, optimiser state, step count);
* ``model_vecnormalize_<N>_steps.pkl`` — the ``VecNormalize`` statistics;
* ``model_replay_buffer_<N>_steps.pkl`` — SAC only: the replay buffer;
* ``model_state_<N>_steps.json`` — the manifest, written last: the step count, the run's
  resolved configuration (:func:`agents.training.experiment.run_fingerprint`), the
  Python / NumPy / torch random states, the best evaluation reward so far, the wall time
  so far and the SHA-256 of every file above.

Every file goes to a temporary name in the same directory and is renamed over its target
(:mod:`agents.evaluation.outputs`), so an interruption leaves either a complete file or
none; a checkpoint without its manifest does not exist. On ``--resume``
(:func:`load_latest`) the newest checkpoint is checked against its manifest (sizes and
hashes) and loaded; if it is damaged (truncated, junk bytes, unreadable), a warning names
the problem and the next older one is tried. The newest *intact* checkpoint must come from
the same configuration as the resumed command (:func:`config_differences`; only
``--timesteps`` and bookkeeping such as ``--eval-freq`` may change), else the resume is
refused.

When checkpoints are written (:class:`ResumableCheckpoint`): at the start of a rollout once
``checkpoint_freq`` environment steps or ``checkpoint_interval_s`` seconds of wall time
have passed since the last one (defaults 250 000 steps / 300 s: at most five minutes of
work are lost to a hard kill), at the end of training, and when the run is interrupted
(SIGINT / Ctrl-C or SIGTERM, :class:`GracefulInterrupt`): training stops at the next
environment step and the state at the start of the current rollout — the policy as last
updated, with the step count, normalisation statistics and random states of that moment
— is saved, so the steps of the unfinished rollout (never learned from) are not counted.
A second interrupt aborts at once without saving.
"""

from __future__ import annotations

import contextlib
import copy
import hashlib
import json
import math
import os
import re
import signal
import sys
import threading
import time
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agents.evaluation.outputs import atomic_path, atomic_write_text
from agents.invocation import invoked_prog
from hyperloop_env.config import canonical_keywords
from hyperloop_env.json_values import json_value

CHECKPOINT_DIR = "checkpoints"
MANIFEST_FORMAT = 1
MANIFEST_RE = re.compile(r"^model_state_(\d+)_steps\.json$")
MODEL_RE = re.compile(r"^model_(\d+)_steps\.zip$")

COMMON_HYPERPARAMETERS: tuple[str, ...] = (
    "gamma",
    "learning_rate",
    "batch_size",
    "log_std_init",
    "net_arch",
    "activation",
    "norm_reward",
)
ALGO_HYPERPARAMETERS: dict[str, tuple[str, ...]] = {
    "ppo": ("n_steps", "n_epochs", "gae_lambda", "clip_range", "ent_coef"),
    "sac": ("sac_buffer_size", "sac_learning_starts", "sac_train_freq", "sac_gradient_steps"),
}


class CheckpointError(ValueError):
    """No usable checkpoint, or one from another configuration (the message says which)."""


class CheckpointWarning(UserWarning):
    """A damaged or unusable checkpoint was skipped."""


# --------------------------------------------------------------------------------------
# configuration
# --------------------------------------------------------------------------------------


def jsonable(x: Any) -> Any:
    """``x`` as it reads back from JSON (lists for tuples, Python numbers, inf kept)."""
    return json.loads(json.dumps(json_value(x, non_finite="keep")))


def config_differences(
    saved: dict[str, Any], current: dict[str, Any], prefix: str = ""
) -> list[str]:
    """Human-readable differences ``key: saved -> current`` between two fingerprints."""
    out = []
    for key in sorted(set(saved) | set(current)):
        name = f"{prefix}{key}"
        a, b = saved.get(key, "<missing>"), current.get(key, "<missing>")
        if isinstance(a, dict) and isinstance(b, dict):
            out += config_differences(a, b, name + ".")
        elif a != b:
            out.append(f"{name}: {a!r} in the checkpoint, {b!r} now")
    return out


# --------------------------------------------------------------------------------------
# random state, digests
# --------------------------------------------------------------------------------------


def rng_state() -> dict[str, Any]:
    """The global Python, NumPy and torch (CPU) random states, JSON-friendly."""
    import random

    import numpy as np
    import torch

    py = random.getstate()
    # SB3 draws minibatch permutations from NumPy's global (legacy) generator
    name, keys, pos, has_gauss, cached = np.random.get_state()  # noqa: NPY002
    return {
        "python": [py[0], list(py[1]), py[2]],
        "numpy": [name, keys.tolist(), int(pos), int(has_gauss), float(cached)],
        "torch": torch.get_rng_state().tolist(),
    }


def set_rng_state(state: dict[str, Any]) -> None:
    """Restore what :func:`rng_state` returned."""
    import random

    import numpy as np
    import torch

    v, keys, gauss = state["python"]
    random.setstate((v, tuple(keys), gauss))
    name, nkeys, pos, has_gauss, cached = state["numpy"]
    np.random.set_state(  # noqa: NPY002
        (name, np.array(nkeys, dtype=np.uint32), pos, has_gauss, cached)
    )
    torch.set_rng_state(torch.tensor(state["torch"], dtype=torch.uint8))


def policy_digest(model: Any) -> str:
    """SHA-256 of the policy's parameters (all tensors of ``model.policy.state_dict()``)."""
    h = hashlib.sha256()
    for name, tensor in sorted(model.policy.state_dict().items()):
        h.update(name.encode())
        h.update(tensor.detach().cpu().contiguous().numpy().tobytes())
    return h.hexdigest()


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
) -> Path:
    """Write the checkpoint of ``steps`` steps (see the module docstring); returns the
    manifest path. ``model.num_timesteps`` is saved as ``steps``."""
    ckpt_dir = out / CHECKPOINT_DIR
    ckpt_dir.mkdir(parents=True, exist_ok=True)
    names = checkpoint_files(steps)
    saved_steps = model.num_timesteps
    model.num_timesteps = steps
    try:
        written = {}
        with atomic_path(ckpt_dir / names["model"]) as tmp:
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
    try:
        ok = (
            int(data["num_timesteps"]) == steps
            and isinstance(data["config"], dict)
            and isinstance(data["rng"], dict)
            and all({"name", "bytes", "sha256"} <= set(v) for v in data["files"].values())
            and {"model", "vecnormalize"} <= set(data["files"])
        )
    except (KeyError, TypeError, ValueError, AttributeError):
        ok = False
    if not ok:
        return None, f"manifest {path.name} is incomplete"
    return data, None


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

    cls = {"ppo": PPO, "sac": SAC}[algo]
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


# --------------------------------------------------------------------------------------
# interrupts and the checkpoint callback
# --------------------------------------------------------------------------------------


class GracefulInterrupt:
    """Context manager: the first SIGINT / SIGTERM only sets :attr:`signum` (training stops
    at the next step and saves a checkpoint); a second one raises ``KeyboardInterrupt``.
    Outside the main thread (where handlers cannot be installed) it does nothing."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.signum: int | None = None
        self._old: dict[int, Any] = {}

    def __enter__(self) -> GracefulInterrupt:
        if threading.current_thread() is threading.main_thread():
            for s in self.SIGNALS:
                self._old[s] = signal.signal(s, self._handle)
        return self

    def _handle(self, signum: int, frame: Any) -> None:
        if self.signum is not None:
            raise KeyboardInterrupt
        self.signum = signum
        print(
            f"\n{invoked_prog('hyperloop-train')}: {signal.Signals(signum).name} received: "
            "stopping at the next step and saving a checkpoint (interrupt again to abort "
            "without saving)",
            file=sys.stderr,
            flush=True,
        )

    def __exit__(self, *exc: object) -> None:
        for s, h in self._old.items():
            signal.signal(s, h)
        self._old.clear()


@contextlib.contextmanager
def sigint_ignored() -> Iterator[None]:
    """Ignore SIGINT while worker processes are started (``--vec subproc``), so that a
    Ctrl-C reaches only the trainer, which stops cleanly, and not its workers."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def _base_callback() -> type:
    from stable_baselines3.common.callbacks import BaseCallback

    return BaseCallback


class _Snapshot:
    """The state at the start of a rollout: step count, random states, VecNormalize
    statistics (the policy does not change while a rollout is collected)."""

    def __init__(self, steps: int, vecnormalize: Any) -> None:
        self.steps = steps
        self.rng = rng_state()
        self.obs_rms = copy.deepcopy(getattr(vecnormalize, "obs_rms", None))
        self.ret_rms = copy.deepcopy(getattr(vecnormalize, "ret_rms", None))


def make_checkpoint_callback(**kwargs: Any) -> Any:
    """A :class:`ResumableCheckpoint` (built lazily: SB3 is an optional dependency)."""
    BaseCallback = _base_callback()

    class ResumableCheckpoint(BaseCallback):  # type: ignore[misc,valid-type]
        """Periodic, final and interrupt checkpoints (module docstring). Stops training
        (``_on_step`` returns False) once ``interrupt.signum`` is set."""

        def __init__(
            self,
            out: Path,
            fingerprint: dict[str, Any],
            checkpoint_freq: int,
            checkpoint_interval_s: float,
            interrupt: GracefulInterrupt,
            eval_callback: Any = None,
            wall_time_before_s: float = 0.0,
            command: str = "",
            announce: str = "",
        ) -> None:
            super().__init__(verbose=0)
            self.out = out
            self.fingerprint = fingerprint
            self.checkpoint_freq = int(checkpoint_freq)
            self.checkpoint_interval_s = float(checkpoint_interval_s)
            self.interrupt = interrupt
            self.eval_callback = eval_callback
            self.wall_time_before_s = wall_time_before_s
            self.command = command
            self.announce = announce
            self.snapshot: _Snapshot | None = None
            self.last_saved_steps = -1
            self.last_saved: Path | None = None
            self._t_start = time.monotonic()
            self._t_last = self._t_start

        # -- helpers -------------------------------------------------------------------
        @property
        def on_policy(self) -> bool:
            from stable_baselines3.common.on_policy_algorithm import OnPolicyAlgorithm

            return isinstance(self.model, OnPolicyAlgorithm)

        def wall_time_s(self) -> float:
            return self.wall_time_before_s + time.monotonic() - self._t_start

        def _best(self) -> float | None:
            cb = self.eval_callback
            return None if cb is None else float(cb.best_mean_reward)

        def save(
            self,
            reason: str,
            steps: int | None = None,
            rng: Any = None,
            obs_rms: Any = None,
            ret_rms: Any = None,
        ) -> Path:
            vn = self.model.get_vec_normalize_env()
            steps = int(self.model.num_timesteps if steps is None else steps)
            saved = (vn.obs_rms, vn.ret_rms)
            if obs_rms is not None:
                vn.obs_rms, vn.ret_rms = obs_rms, ret_rms
            try:
                path = save_checkpoint(
                    self.out,
                    self.model,
                    vn,
                    steps=steps,
                    fingerprint=self.fingerprint,
                    reason=reason,
                    rng=rng,
                    best_mean_reward=self._best(),
                    wall_time_s=self.wall_time_s(),
                    command=self.command,
                )
            finally:
                vn.obs_rms, vn.ret_rms = saved
            self.last_saved_steps = steps
            self.last_saved = path
            self._t_last = time.monotonic()
            return path

        def save_interrupted(self) -> tuple[Path, int]:
            """The checkpoint of an interrupted run: the state at the start of the current
            rollout for on-policy algorithms (PPO), the current state otherwise."""
            snap = self.snapshot
            if self.on_policy and snap is not None:
                if snap.steps == self.last_saved_steps and self.last_saved is not None:
                    return self.last_saved, snap.steps
                return self.save(
                    "interrupt", snap.steps, snap.rng, snap.obs_rms, snap.ret_rms
                ), snap.steps
            steps = int(self.model.num_timesteps)
            if steps == self.last_saved_steps and self.last_saved is not None:
                return self.last_saved, steps
            return self.save("interrupt"), steps

        def save_final(self) -> Path:
            steps = int(self.model.num_timesteps)
            if steps == self.last_saved_steps and self.last_saved is not None:
                return self.last_saved
            return self.save("final")

        # -- SB3 hooks -----------------------------------------------------------------
        def _on_training_start(self) -> None:
            self.last_saved_steps = int(self.model.num_timesteps)
            self._t_last = time.monotonic()
            if self.announce:
                print(self.announce, flush=True)

        def _on_rollout_start(self) -> None:
            steps = int(self.model.num_timesteps)
            vn = self.model.get_vec_normalize_env()
            if self.on_policy:
                self.snapshot = _Snapshot(steps, vn)
            due_steps = steps // self.checkpoint_freq > max(self.last_saved_steps, 0) // (
                self.checkpoint_freq
            )
            due_time = time.monotonic() - self._t_last >= self.checkpoint_interval_s
            if steps > self.last_saved_steps and (due_steps or due_time):
                path = self.save("interval" if due_time and not due_steps else "steps")
                if self.verbose or self.model.verbose:
                    print(f"checkpoint at {steps} steps: {path}", flush=True)

        def _on_step(self) -> bool:
            return self.interrupt.signum is None

    return ResumableCheckpoint(**kwargs)


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
