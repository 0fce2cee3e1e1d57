"""PPO whose update runs on a second process while the next rollout is collected
(:class:`OverlappedPPO`, option ``overlap_updates``).

Stable-Baselines3's PPO alternates: collect a rollout with the policy θ_k, then update it on
that rollout (n_epochs passes of mini-batch gradient steps) to θ_{k+1}, then collect the next.
With small networks both halves are latency-bound serial work on one core. Here the update of
rollout k runs on a learner process while the trainer process collects rollout k+1 with the
policy it has, θ_{k-1}; the trainer then takes θ_k from the learner and hands it rollout k+1::

    trainer:  collect R1 (θ0) | collect R2 (θ0) | collect R3 (θ1) | collect R4 (θ2) | …
    learner:                  | θ1 ← update(θ0; R1) | θ2 ← update(θ1; R2) | …

So every rollout after the first two is collected by the policy one update older than the one
it updates: PPO with a policy lag of one update (as in asynchronous PPO, e.g. Sample Factory's
APPO). PPO's ratio π_θ/π_behaviour uses the log-probabilities recorded when the rollout was
collected, so the clipped objective still bounds the step from the policy that acted; the
advantages bootstrap from that policy's critic. The learning curve is not Stable-Baselines3's
PPO's: ``docs/training.md`` compares the two on seeds outside the shipped runs'.

Everything else is Stable-Baselines3's: the learner runs ``PPO.train`` on a copy of the model
(policy and Adam state), and the mini-batch permutations are drawn from the trainer's NumPy
generator exactly as ``PPO.train`` draws them (the learner gets the generator's state), so
the random streams — and so the checkpoints' random states — are those of the plain PPO. The
run is deterministic for a given seed: the trainer and the learner exchange rollouts and
parameters in a fixed order, each on one torch thread.

Checkpoints hold every update of the data collected before them (:meth:`settled`: the model
is saved with the learner's newest parameters, waiting for the update in flight, while the
rollout under way keeps the policy that started it); the end of :meth:`learn` — also an
interrupted one — waits for the last update and loads it. The learner ignores SIGINT (the
trainer handles Ctrl-C) and stops with :meth:`learn`; an error in it is raised in the trainer
as :class:`LearnerError` with the learner's traceback.
"""

from __future__ import annotations

import contextlib
import io
import multiprocessing as mp
import signal
import traceback
import weakref
from collections.abc import Iterator
from typing import Any

import numpy as np
from stable_baselines3 import PPO

from agents.training.interrupts import sigint_ignored

ROLLOUT_FIELDS = (
    "observations",
    "actions",
    "rewards",
    "returns",
    "episode_starts",
    "values",
    "log_probs",
    "advantages",
)


OPTIMIZER_KWARGS = {"eps": 1e-5, "fused": True}
"""Adam's options for an :class:`OverlappedPPO`: Stable-Baselines3's ``eps``, and torch's
fused CPU kernel (the same update rule in one pass over the parameters instead of a loop
over them; the rounding may differ). The update is the slower half of the overlapped pair,
so its time is the training's."""


class LearnerError(RuntimeError):
    """The learner process failed (its traceback is in the message) or went away."""


def _serve(conn: Any) -> None:  # pragma: no cover - learner process
    """The learner's loop: the model (saved, as bytes), then ``PPO.train`` on each rollout
    it is sent (:mod:`module docstring <agents.training.overlap>`), replying with the
    policy's and Adam's state and the logged values."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        import torch
        from stable_baselines3.common.logger import Logger

        torch.set_num_threads(1)
        model_bytes = conn.recv()
        if model_bytes is None:
            return
        model = PPO.load(io.BytesIO(model_bytes), device="cpu")
        model.set_logger(Logger(None, []))
        buf = model.rollout_buffer
        while True:
            msg = conn.recv()
            if msg is None:
                return
            arrays, progress, rng, steps = msg
            for name in ROLLOUT_FIELDS:
                setattr(buf, name, arrays[name])
            buf.full, buf.pos, buf.generator_ready = True, buf.buffer_size, False
            model._current_progress_remaining = progress
            model.num_timesteps = steps
            np.random.set_state(rng)  # noqa: NPY002 - SB3 permutes with the global generator
            model.train()
            log = model.logger
            logged = {k: (v, log.name_to_excluded.get(k)) for k, v in log.name_to_value.items()}
            log.name_to_value.clear()
            log.name_to_count.clear()
            log.name_to_excluded.clear()
            policy = model.policy
            state = _to_numpy((policy.state_dict(), policy.optimizer.state_dict()))
            conn.send(("ok", *state, logged, model._n_updates))
    except BaseException:
        with contextlib.suppress(Exception):
            conn.send(("error", traceback.format_exc()))


class Learner:
    """A learner process and its pipe (:func:`start_learner`)."""

    def __init__(self) -> None:
        ctx = mp.get_context("spawn")
        self.conn, child = ctx.Pipe()
        with sigint_ignored():  # Ctrl-C reaches the trainer, which stops cleanly
            self.proc = ctx.Process(target=_serve, args=(child,), name="ppo-learner", daemon=True)
            self.proc.start()
        child.close()
        self.closed = False

    def load(self, model: PPO) -> None:
        """Hand the learner its copy of ``model`` (policy and Adam state)."""
        buf = io.BytesIO()
        model.save(buf)
        self.send(buf.getvalue())

    def send(self, msg: Any) -> None:
        try:
            self.conn.send(msg)
        except (BrokenPipeError, EOFError, OSError) as e:
            raise LearnerError(f"the PPO learner process went away ({e})") from None

    def recv(self) -> tuple[Any, ...]:
        try:
            reply = self.conn.recv()
        except (EOFError, OSError) as e:
            code = self.proc.exitcode
            raise LearnerError(
                f"the PPO learner process went away (exit code {code}; {e!r})"
            ) from None
        if reply[0] == "error":
            raise LearnerError(f"the PPO learner process failed:\n{reply[1]}")
        return reply

    def close(self) -> None:
        """Stop the process (it finishes what it was sent); closing twice is a no-op."""
        if self.closed:
            return
        self.closed = True
        with contextlib.suppress(Exception):
            self.conn.send(None)
        self.proc.join(timeout=10)
        if self.proc.is_alive():
            self.proc.terminate()
            self.proc.join(timeout=5)
        self.conn.close()


def start_learner() -> Learner:
    """A learner process started ahead of its model: it imports torch and Stable-Baselines3
    (about two seconds) while the trainer builds its environments and model; hand it to the
    model with :meth:`OverlappedPPO.adopt_learner`, or :meth:`Learner.close` it."""
    return Learner()


class OverlappedPPO(PPO):
    """Stable-Baselines3's PPO with each update on a learner process, overlapping the next
    rollout (module docstring). Saved and loaded as a plain :class:`PPO` (the learner is not
    part of the model)."""

    def _setup_model(self) -> None:
        super()._setup_model()
        self._learner: Learner | None = None
        self._spare: Learner | None = None
        self._pending = False
        self._reply: tuple[Any, ...] | None = None

    def _excluded_save_params(self) -> list[str]:
        return [*super()._excluded_save_params(), "_learner", "_spare", "_pending", "_reply"]

    def adopt_learner(self, learner: Learner) -> None:
        """Use ``learner`` (:func:`start_learner`) for the next :meth:`learn`; it is closed
        with the model if that never comes."""
        if self._spare is not None:
            self._spare.close()
        self._spare = learner
        weakref.finalize(self, learner.close)

    def learn(self, *args: Any, **kwargs: Any) -> OverlappedPPO:
        """:meth:`PPO.learn`; returns once the last update is loaded (module docstring)."""
        self._learner, self._spare = self._spare or Learner(), None
        try:
            self._learner.load(self)  # it loads while the first rollout is collected
            super().learn(*args, **kwargs)
            self._apply()
        finally:
            learner, self._learner = self._learner, None
            self._pending, self._reply = False, None
            learner.close()
        return self

    def train(self) -> None:
        """Load the previous update, then hand the rollout just collected to the learner."""
        assert self._learner is not None, "OverlappedPPO.train runs inside learn()"
        self._apply()
        buf = self.rollout_buffer
        rng = np.random.get_state()  # noqa: NPY002
        for _ in range(self.n_epochs):  # the trainer's generator advances as PPO.train's does
            np.random.permutation(buf.buffer_size * buf.n_envs)  # noqa: NPY002
        arrays = {name: getattr(buf, name) for name in ROLLOUT_FIELDS}
        self._learner.send((arrays, self._current_progress_remaining, rng, self.num_timesteps))
        self._pending = True

    def _wait(self) -> None:
        if self._pending:
            assert self._learner is not None
            self._reply = self._learner.recv()
            self._pending = False

    def _apply(self) -> None:
        """Load the update in flight (waiting for it) and record its logged values."""
        self._wait()
        if self._reply is None:
            return
        _, params, optim, logged, n_updates = self._reply
        self._reply = None
        self.policy.load_state_dict(_to_torch(params))
        self.policy.optimizer.load_state_dict(_to_torch(optim))
        self._n_updates = n_updates
        for key, (value, exclude) in logged.items():
            self.logger.record(key, value, exclude=exclude)

    @contextlib.contextmanager
    def settled(self) -> Iterator[None]:
        """Inside: the model with every update of the rollouts collected so far (the one in
        flight waited for); after: the policy the rollout under way started with, bit for
        bit. What a checkpoint saves."""
        self._wait()
        if self._reply is None:
            yield
            return
        _, params, optim, _, n_updates = self._reply
        keep = (
            {k: v.clone() for k, v in self.policy.state_dict().items()},
            _clone_state(self.policy.optimizer.state_dict()),
            self._n_updates,
        )
        self.policy.load_state_dict(_to_torch(params))
        self.policy.optimizer.load_state_dict(_to_torch(optim))
        self._n_updates = n_updates
        try:
            yield
        finally:
            self.policy.load_state_dict(keep[0])
            self.policy.optimizer.load_state_dict(keep[1])
            self._n_updates = keep[2]


def _clone_state(state: Any) -> Any:
    """A deep copy of an optimizer's state dict (its tensors cloned)."""
    import copy

    return copy.deepcopy(state)


def _to_numpy(x: Any) -> Any:
    """``x`` with every tensor replaced by a NumPy copy: sent through the pipe as plain bytes
    (torch's own pickling of tensors sends shared-memory handles the receiver must map)."""
    import torch

    if isinstance(x, torch.Tensor):
        return x.detach().numpy().copy()
    if isinstance(x, dict):
        return type(x)((k, _to_numpy(v)) for k, v in x.items())
    if isinstance(x, (list, tuple)):
        return type(x)(_to_numpy(v) for v in x)
    return x


def _to_torch(x: Any) -> Any:
    """The inverse of :func:`_to_numpy` (the same values, bit for bit)."""
    import torch

    if isinstance(x, np.ndarray):
        return torch.from_numpy(x)
    if isinstance(x, dict):
        return type(x)((k, _to_torch(v)) for k, v in x.items())
    if isinstance(x, (list, tuple)):
        return type(x)(_to_torch(v) for v in x)
    return x
