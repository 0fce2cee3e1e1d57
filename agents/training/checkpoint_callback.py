"""The SB3 callback that writes a training run's checkpoints
(:func:`make_checkpoint_callback`): periodic (every ``checkpoint_freq`` environment steps or
``checkpoint_interval_s`` seconds, at the start of a rollout), final, and on interrupt
(:class:`~agents.training.interrupts.GracefulInterrupt`), each with
:func:`agents.training.checkpoints.save_checkpoint`. An interrupted on-policy run saves the
state at the start of the current rollout (:class:`_Snapshot`); see
:mod:`agents.training.checkpoints` for when and what.
"""

from __future__ import annotations

import copy
import time
from pathlib import Path
from typing import Any

from agents.training.checkpoints import save_checkpoint
from agents.training.interrupts import GracefulInterrupt
from agents.training.run_state import rng_state


def _base_callback() -> type:
    from stable_baselines3.common.callbacks import BaseCallback

    return BaseCallback


class _Snapshot:
    """The state at the start of a rollout: step count, random states, VecNormalize
    statistics (the policy does not change while a rollout is collected)."""

    def __init__(self, steps: int, vecnormalize: Any, curriculum: Any = None) -> None:
        self.steps = steps
        self.rng = rng_state()
        self.curriculum = None if curriculum is None else curriculum.state()
        self.obs_rms = copy.deepcopy(getattr(vecnormalize, "obs_rms", None))
        self.ret_rms = copy.deepcopy(getattr(vecnormalize, "ret_rms", None))


class _ResumableCheckpointMixin:
    """The behaviour of :class:`ResumableCheckpoint` (see :func:`make_checkpoint_callback`),
    kept apart from SB3's ``BaseCallback`` so that the class can be built lazily: mixed in
    before ``BaseCallback``, whose ``model`` and ``verbose`` it uses and whose hooks it
    overrides."""

    model: Any
    verbose: int

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
        curriculum: dict[str, Any] | None = None,
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
                curriculum=curriculum if curriculum is not None else self._curriculum_state(),
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
                "interrupt", snap.steps, snap.rng, snap.obs_rms, snap.ret_rms, snap.curriculum
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

    def _curriculum(self) -> Any:
        from agents.training.curriculum import find_curriculum

        return find_curriculum(self.model.get_env())

    def _curriculum_state(self) -> dict[str, Any] | None:
        cur = self._curriculum()
        return None if cur is None else cur.state()

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
            self.snapshot = _Snapshot(steps, vn, self._curriculum())
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


def make_checkpoint_callback(**kwargs: Any) -> Any:
    """A :class:`ResumableCheckpoint` (built lazily: SB3 is an optional dependency)."""
    BaseCallback = _base_callback()

    class ResumableCheckpoint(_ResumableCheckpointMixin, BaseCallback):  # type: ignore[misc,valid-type]
        """Periodic, final and interrupt checkpoints (module docstring). Stops training
        (``_on_step`` returns False) once ``interrupt.signum`` is set."""

    return ResumableCheckpoint(**kwargs)
