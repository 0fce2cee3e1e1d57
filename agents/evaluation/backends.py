"""Where the blocks of a fragility sweep run: this process, local worker processes, or a
Ray cluster.

Every backend runs the same :func:`agents.evaluation.batch_rollout.run_block` on the same
:class:`~agents.evaluation.batch_rollout.BlockSpec` s and yields ``(index, BlockResult)``
as blocks finish; the caller orders them by index, so the results do not depend on the
backend, the number of workers or the completion order (a block's content is fixed by the
plan — its seeds — never by the number of workers).

* ``local`` with ``workers=1``: in this process, one block after the other (fine-grained
  progress), with one BLAS thread like a worker (:mod:`hyperloop_env.threads`).
* ``local`` with ``workers=W > 1``: a ``concurrent.futures.ProcessPoolExecutor`` with W
  spawned worker processes, each limited to one compute thread (numba, BLAS) so W workers
  use W cores. Each call starts its own pool, unless it runs inside :func:`shared_pool`
  (W): then every call with W workers uses that one pool, whose workers start once (their
  imports and compiled kernels loaded once for a study of several phases).
* ``ray``: one Ray task per block (``num_cpus=1``). ``address=None`` starts a local Ray
  (and shuts it down afterwards); ``address="auto"`` or ``"ray://host:10001"`` joins a
  running cluster. Workers import this package: install it on every node (or share the
  checkout at the same path: the driver's project root is put on the workers'
  ``PYTHONPATH``).

Controllers registered in this process by entry point
(``register_controller(name, "package.module:factory")``) reach the workers of both
backends the same way: :func:`agents.controllers.registry.registrations` is sent with every
task and the worker adopts it before running the block (a factory registered as a Python
callable stays in this process: register it by entry point to use it on workers).

Stopping: an exception, Ctrl-C or SIGTERM in the driver (:func:`sigterm_exits` turns
SIGTERM into ``SystemExit(143)`` while blocks run, so the cleanup runs) cancels the
blocks not yet started and terminates the worker processes; no worker (nor
multiprocessing's resource tracker, which ends when they do) is left behind, idle.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any

from agents.controllers import registry
from agents.evaluation.batch_rollout import run_block
from hyperloop_env.threads import one_blas_thread

BACKENDS = ("local", "ray")
PROJECT_ROOT = Path(__file__).resolve().parents[2]
_THREAD_VARS = ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")

Progress = Callable[[int], None]


SIGTERM_GRACE_S = 30.0
"""After SIGTERM the process ends within this many seconds, whatever its cleanup does."""


def _on_sigterm(signum: int, frame: Any) -> None:
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # one is enough: let the cleanup run
    print(
        f"\n{Path(sys.argv[0]).name or 'python'}: SIGTERM received: stopping the workers",
        file=sys.stderr,
        flush=True,
    )
    # the cleanup (workers terminated and joined, temporary outputs removed) normally takes
    # seconds; should the interpreter's shutdown then hang (concurrent.futures joins its
    # manager thread at exit), leave anyway after SIGTERM_GRACE_S: a SIGTERM must end us
    watchdog = threading.Timer(SIGTERM_GRACE_S, os._exit, (128 + signum,))
    watchdog.daemon = True
    watchdog.start()
    raise SystemExit(128 + signum)


@contextlib.contextmanager
def sigterm_exits() -> Iterator[None]:
    """While the block runs, SIGTERM raises ``SystemExit(143)`` in the main thread (instead
    of killing the process on the spot), so ``finally`` blocks stop worker processes and
    remove temporary outputs. Leaves a handler the application installed alone; does
    nothing outside the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.getsignal(signal.SIGTERM)
    if old not in (signal.SIG_DFL, None):  # someone else's (or ours, already installed)
        yield
        return
    signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        yield
    except SystemError as exc:
        # a signal handler that raises while a compiled (numba) function runs comes out as
        # "SystemError: ... returned a result with an exception set", the handler's
        # SystemExit / KeyboardInterrupt chained under it: give the caller the real one
        interrupt = _chained_interrupt(exc)
        if interrupt is None:
            raise
        raise interrupt from None
    finally:
        signal.signal(signal.SIGTERM, old)


def _chained_interrupt(exc: BaseException) -> BaseException | None:
    """The first ``SystemExit`` or ``KeyboardInterrupt`` in ``exc``'s cause/context chain."""
    seen: set[int] = set()
    cur: BaseException | None = exc
    while cur is not None and id(cur) not in seen:
        seen.add(id(cur))
        if isinstance(cur, SystemExit | KeyboardInterrupt):
            return cur
        cur = cur.__cause__ or cur.__context__
    return None


def _stop_pool(pool: ProcessPoolExecutor) -> None:
    """Cancel what has not started and terminate the workers (a running block cannot be
    cancelled otherwise); wait for them to be gone."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        with contextlib.suppress(Exception):
            p.terminate()
    for p in procs:
        with contextlib.suppress(Exception):
            p.join(timeout=5)
            if p.is_alive():
                p.kill()
                p.join(timeout=5)


def _single_thread_env() -> dict[str, str]:
    return {v: "1" for v in _THREAD_VARS}


def _init_worker() -> None:  # pragma: no cover - runs in the worker processes
    try:
        import numba

        numba.set_num_threads(1)
    except (ImportError, ValueError):
        pass


def _run_remote(
    spec: Any,
    fn: Callable[..., Any] = run_block,
    registrations: tuple[registry.ControllerSpec, ...] = (),
) -> Any:  # pragma: no cover - runs in the worker processes
    """``fn(spec)`` in a worker, after adopting the driver's controller ``registrations``."""
    registry.adopt(registrations)
    return fn(spec)


def run_blocks(
    specs: Sequence[Any],
    backend: str = "local",
    workers: int = 1,
    address: str | None = None,
    progress: Progress | None = None,
    planned_steps: Sequence[int] | None = None,
    fn: Callable[..., Any] = run_block,
) -> Iterator[tuple[int, Any]]:
    """Run ``fn(spec)`` for every spec (default :func:`run_block`; any module-level
    function taking ``(spec, progress=None)`` and returning a result with a ``steps``
    attribute, e.g. :func:`agents.evaluation.capacity.run_task`); yield ``(index, result)``
    as they complete. ``progress(n)`` counts control steps: live in-process, per finished
    block on workers (``planned_steps[i]``: the block's planned steps, so runs that ended
    early in contact still fill the bar)."""
    check_backend(backend, workers, address)
    planned = list(planned_steps) if planned_steps is not None else [0] * len(specs)
    if backend == "ray":
        yield from _run_ray(specs, address, progress, planned, fn)
    elif workers == 1:
        for i, spec in enumerate(specs):
            with one_blas_thread():  # as in a worker process: same bits (hyperloop_env.threads)
                res = fn(spec, progress)
            if progress is not None and planned[i] > res.steps:
                progress(planned[i] - res.steps)
            yield i, res
    else:
        yield from _run_pool(specs, workers, progress, planned, fn)


def check_backend(backend: str, workers: int, address: str | None = None) -> None:
    """Refuse, before anything is created, a backend that is not one of :data:`BACKENDS`, a
    worker count that is not an int >= 1, an ``address`` without the ``ray`` backend and
    the ``ray`` backend without Ray installed (:class:`~agents.installation.MissingExtraError`,
    naming the extra to install). More workers than this machine has CPUs is allowed (a
    cluster's nodes) but said once on stderr; the pool never starts more processes than
    there are blocks."""
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be an int >= 1, got {workers!r}")
    if address is not None and backend != "ray":
        raise ValueError(f"address {address!r} needs the ray backend (--backend ray)")
    if backend == "ray":
        from agents.installation import MissingExtraError, missing_extra_message

        try:
            import ray  # noqa: F401
        except ImportError:
            raise MissingExtraError(
                missing_extra_message("ray", "--backend ray", ["ray"]), name="ray"
            ) from None


def _warn_workers(workers: int) -> None:
    cpus = os.cpu_count() or 1
    if workers > cpus:
        print(
            f"warning: {workers} workers on a machine with {cpus} CPUs: each worker is a "
            "process with one compute thread, so the extra ones only wait (same results)",
            file=sys.stderr,
        )


_SHARED: dict[str, Any] = {}
"""The pool of the open :func:`shared_pool`: ``workers`` and ``pool`` (None until a call
starts it, or after a call stopped it)."""


@contextlib.contextmanager
def shared_pool(workers: int) -> Iterator[None]:
    """Within this context, every :func:`run_blocks` call on the local backend with
    ``workers`` workers runs on one pool of ``workers`` spawned processes, started by the
    first call and shut down at the end of the context, instead of a pool per call. The
    results are those of separate pools (each block is fixed by its spec). Nested or with
    ``workers <= 1``: does nothing. A call that fails or is interrupted stops the pool; the
    next call in the context starts a new one."""
    check_backend("local", workers)
    if workers <= 1 or _SHARED:
        yield
        return
    saved = {v: os.environ.get(v) for v in _THREAD_VARS}
    os.environ.update(_single_thread_env())  # inherited by every worker the pool spawns
    _SHARED.update(workers=workers, pool=None)
    try:
        yield
    finally:
        pool = _SHARED.get("pool")
        _SHARED.clear()
        if pool is not None:
            pool.shutdown(wait=True)
        _restore_env(saved)


def _restore_env(saved: dict[str, str | None]) -> None:
    for v, old in saved.items():
        if old is None:
            os.environ.pop(v, None)
        else:
            os.environ[v] = old


def _new_pool(workers: int) -> ProcessPoolExecutor:
    import multiprocessing as mp

    ctx = mp.get_context("spawn")
    return ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_init_worker)


def _run_pool(
    specs: Sequence[Any],
    workers: int,
    progress: Progress | None,
    planned: list[int],
    fn: Callable[..., Any],
) -> Iterator[tuple[int, Any]]:
    shared = _SHARED.get("workers") == workers
    if not shared:
        workers = min(workers, max(1, len(specs)))
    _warn_workers(workers)
    saved = {v: os.environ.get(v) for v in _THREAD_VARS}
    os.environ.update(_single_thread_env())  # inherited by the spawned workers
    try:
        with sigterm_exits():
            pool = _SHARED.get("pool") if shared else None
            if pool is None:
                pool = _new_pool(workers)
                if shared:
                    _SHARED["pool"] = pool
            try:
                regs = registry.registrations()
                futs = {pool.submit(_run_remote, s, fn, regs): i for i, s in enumerate(specs)}
                pending = set(futs)
                while pending:
                    done, pending = wait(pending, return_when=FIRST_COMPLETED)
                    for f in sorted(done, key=lambda f: futs[f]):
                        i = futs[f]
                        res = f.result()
                        if progress is not None:
                            progress(max(planned[i], res.steps))
                        yield i, res
            except BaseException:  # error, Ctrl-C, SIGTERM, or the consumer stopped early
                _stop_pool(pool)
                if shared:
                    _SHARED["pool"] = None
                raise
            if not shared:
                pool.shutdown(wait=True)
    finally:
        _restore_env(saved)


def results_in_order(
    specs: Sequence[Any],
    fn: Callable[..., Any],
    workers: int = 1,
    backend: str = "local",
    address: str | None = None,
) -> list[Any]:
    """``[fn(spec) for spec in specs]``, run by :func:`run_blocks` on ``workers``: the
    results in the order of ``specs``, whatever the order they finish in."""
    out: list[Any] = [None] * len(specs)
    for i, res in run_blocks(specs, backend, workers, address, fn=fn):
        out[i] = res
    return out


def _run_ray(
    specs: Sequence[Any],
    address: str | None,
    progress: Progress | None,
    planned: list[int],
    fn: Callable[..., Any],
) -> Iterator[tuple[int, Any]]:
    import ray

    started = False
    if not ray.is_initialized():
        env_vars = _single_thread_env()
        pp = os.pathsep.join(p for p in (str(PROJECT_ROOT), os.environ.get("PYTHONPATH")) if p)
        env_vars["PYTHONPATH"] = pp
        kw: dict[str, Any] = {"runtime_env": {"env_vars": env_vars}, "log_to_driver": False}
        if address is None:
            kw["include_dashboard"] = False
        ray.init(address=address, **kw)
        started = True
    try:
        remote = ray.remote(num_cpus=1)(_run_remote)
        regs = registry.registrations()
        refs = {remote.remote(s, fn, regs): i for i, s in enumerate(specs)}
        pending = list(refs)
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                i = refs[ref]
                res = ray.get(ref)
                if progress is not None:
                    progress(max(planned[i], res.steps))
                yield i, res
    finally:
        if started:
            ray.shutdown()
