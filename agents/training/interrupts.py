"""Signal handling of a training run: the first SIGINT / SIGTERM stops training cleanly at
the next environment step (a checkpoint is then saved by
:mod:`agents.training.checkpoint_callback`), a second one aborts; worker processes are
started with SIGINT ignored so that a Ctrl-C reaches only the trainer.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Iterator
from typing import Any

from agents.invocation import invoked_prog


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
    """Ignore SIGINT while worker processes are started (``--vec subproc``, the overlapped
    updates' learner), so that a Ctrl-C reaches only the trainer, which stops cleanly, and
    not its workers. Only the main thread may set it (elsewhere, e.g. in a Ray Tune
    trial's thread, nothing is changed)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)
