"""Serial or threaded physics for a batch, chosen by measuring both as the batch steps.

The native vector env can step its batch on one thread or on numba's threads; the two give
bit-identical trajectories, so the choice is about time only, and the faster one depends
on the machine's load at the moment. On an idle 2-core machine the threaded kernel is
about ×2 faster at 256 environments (``speed/bench_threads.py``); when the other core is
busy, each threaded step waits for a descheduled worker thread and takes ten times as long
as the serial one. :class:`KernelChoice` keeps an estimate of the kernel's time in each
mode (a faster step replaces it at once, a slower one moves it by ``SMOOTHING`` of the
difference), uses the faster mode, and re-measures the other one every ``probe_every``
steps, so that a batch follows the load as it changes.
"""

from __future__ import annotations

PROBE_EVERY = 128
"""Steps between two measurements of the mode not in use."""

WARMUP = 8
"""First steps, alternating between the two modes."""

SMOOTHING = 0.25
"""Weight of a new measurement in a mode's moving average."""


class KernelChoice:
    """Which kernel the next step uses (:meth:`parallel`) and what it cost (:meth:`record`)."""

    def __init__(self, probe_every: int = PROBE_EVERY) -> None:
        if isinstance(probe_every, bool) or not isinstance(probe_every, int) or probe_every < 2:
            raise ValueError(f"probe_every must be an int >= 2, got {probe_every!r}")
        self.probe_every = probe_every
        self.mean_s: dict[bool, float | None] = {False: None, True: None}
        self.steps = 0

    def parallel(self) -> bool:
        """True: the threaded kernel for the next step; False: the serial one."""
        if self.steps < WARMUP:  # each mode measured a few times first
            return self.steps % 2 == 1
        serial, threaded = self.mean_s[False], self.mean_s[True]
        assert serial is not None and threaded is not None
        best = threaded < serial
        return (not best) if self.steps % self.probe_every == 0 else best

    def record(self, parallel: bool, seconds: float) -> None:
        """The step just taken used ``parallel`` and its kernel took ``seconds``."""
        old = self.mean_s[parallel]
        if old is None or seconds < old:  # a faster step counts at once (the first threaded
            self.mean_s[parallel] = seconds  # step also starts the threads: an outlier)
        else:  # a slower one (the load rising) moves the estimate gradually
            self.mean_s[parallel] = old + SMOOTHING * (seconds - old)
        self.steps += 1
