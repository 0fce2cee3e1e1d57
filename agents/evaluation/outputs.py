"""Output directories and files that never lose or mix a user's work.

* :func:`prepare_output_dir` — checked *before* any computation: the path must be a
  writable directory (created if missing); a non-empty directory is refused unless
  ``overwrite`` is given, in which case the files a previous report wrote there (the
  ``owned`` names: report, JSON, CSV, figures) are removed first so no stale figure
  survives beside the new report.
* :func:`atomic_write_text` / :func:`atomic_write_bytes` / :func:`atomic_path` — write to
  a temporary file in the same directory and rename it over the target (``os.replace``):
  an interrupted write leaves the old file or none, never a truncated one. The file gets
  the permissions any new file gets (``0o666`` less the umask), not ``mkstemp``'s 0600.
* :func:`atomic_dir` — the same for a whole directory (a benchmark block: report, JSON,
  CSV and figures appear together or not at all).
* :func:`output_lock` — one run per output directory: an exclusive ``flock`` on
  ``<dir>/.lock`` (holding the holder's pid) for the whole run; a second run on the same
  directory is refused naming the directory and the pid (:class:`OutputLockError`).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

LOCK_NAME = ".lock"
"""The lock file of an output directory (:func:`output_lock`); never counts as content."""


class OutputDirError(ValueError):
    """The output directory cannot be used (not writable, a file, or not empty)."""


class OutputLockError(OutputDirError):
    """The output directory is in use by another run (the message names it and its pid)."""


def current_umask() -> int:
    """The process's umask (read without changing it where /proc tells it)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def honour_umask(path: str | Path, directory: bool = False) -> None:
    """Give ``path`` (made by ``mkstemp`` / ``mkdtemp``: 0600 / 0700) the mode a plain
    ``open`` / ``mkdir`` would have given it: ``0o666`` (``0o777`` for a directory) less
    the umask."""
    os.chmod(path, (0o777 if directory else 0o666) & ~current_umask())


def entries(path: Path) -> list[Path]:
    """The contents of the directory ``path`` without its lock file."""
    return [q for q in path.iterdir() if q.name != LOCK_NAME]


def _writable(path: Path) -> None:
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputDirError(f"cannot create output directory {path}: {exc}") from None
    if not path.is_dir():
        raise OutputDirError(f"output path {path} is not a directory")
    try:
        fd, probe = tempfile.mkstemp(prefix=".write-test-", dir=path)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise OutputDirError(f"output directory {path} is not writable: {exc}") from None


def prepare_output_dir(
    path: str | Path,
    *,
    overwrite: bool = False,
    owned: Sequence[str] = (),
    flag: str = "--overwrite",
) -> Path:
    """Check (and create) the output directory ``path`` before any work is done.

    A directory that already holds files is refused (``OutputDirError``) unless
    ``overwrite``; then the entries named in ``owned`` (files or directories a previous
    run of the same tool wrote) are removed. A path under an existing file, an unwritable
    location or ``/proc`` raise ``OutputDirError`` naming the path."""
    p = Path(path)
    for parent in [p, *p.parents]:
        if parent.exists() and not parent.is_dir():
            raise OutputDirError(f"output path {p}: {parent} exists and is not a directory")
    existed = p.is_dir()
    if existed and entries(p):
        if not overwrite:
            raise OutputDirError(
                f"output directory {p} is not empty; refusing to overwrite a previous run "
                f"(choose another path or pass {flag})"
            )
        for name in owned:
            q = p / name
            if q.is_dir() and not q.is_symlink():
                shutil.rmtree(q)
            elif q.exists() or q.is_symlink():
                q.unlink()
    created = not existed
    try:
        _writable(p)
    except OutputDirError:
        if created and p.is_dir() and not entries(p):
            p.rmdir()
        raise
    return p


def discard_if_empty(path: str | Path) -> None:
    """Remove ``path`` if it is an empty directory (after a run that wrote nothing)."""
    p = Path(path)
    with contextlib.suppress(OSError):
        if p.is_dir() and not any(p.iterdir()):
            p.rmdir()


@contextlib.contextmanager
def atomic_path(target: str | Path) -> Iterator[Path]:
    """A temporary path beside ``target``; renamed over it when the block succeeds,
    deleted when it fails."""
    t = Path(target)
    t.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{t.name}.", suffix=".tmp", dir=t.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        honour_umask(tmp_path)  # writers that reopen the path keep this mode
        yield tmp_path
        if tmp_path.exists():
            honour_umask(tmp_path)
        os.replace(tmp_path, t)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        raise


@contextlib.contextmanager
def atomic_dir(target: str | Path) -> Iterator[Path]:
    """A temporary directory beside ``target`` (hidden, ``.<name>.partial-*``): fill it in
    the block; on success it replaces ``target`` (whatever was there — an unfinished
    earlier attempt — is removed after the new one is in place), on failure or interrupt
    it is deleted and ``target`` is left as it was. Readers see a finished directory or
    none."""
    t = Path(target)
    t.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{t.name}.partial-", dir=t.parent))
    try:
        honour_umask(tmp, directory=True)
        yield tmp
        old = None
        if t.exists() or t.is_symlink():
            old = Path(tempfile.mkdtemp(prefix=f".{t.name}.old-", dir=t.parent))
            os.replace(t, old / t.name)
        os.replace(tmp, t)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def partial_dirs(parent: Path) -> list[Path]:
    """Leftovers of :func:`atomic_dir` in ``parent`` (a process killed with SIGKILL
    mid-write): safe to delete by whoever holds the output directory's lock."""
    if not parent.is_dir():
        return []
    return [
        q
        for q in parent.iterdir()
        if q.is_dir() and q.name.startswith(".") and (".partial-" in q.name or ".old-" in q.name)
    ]


def atomic_write_bytes(target: str | Path, data: bytes) -> None:
    with atomic_path(target) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())


def atomic_write_text(target: str | Path, text: str) -> None:
    atomic_write_bytes(target, text.encode("utf-8"))


# --------------------------------------------------------------------------------------
# one run per output directory
# --------------------------------------------------------------------------------------

_HELD: dict[str, list[Any]] = {}
"""Locks this process holds: real path -> [fd, depth, directory created by the lock]
(a nested :func:`output_lock` on the same directory in the same process is re-entrant)."""


def _holder(lock: Path) -> str:
    try:
        text = lock.read_text().strip()
    except OSError:
        text = ""
    pid = text.split()[0] if text else ""
    return f"pid {pid}" if pid.isdigit() else "pid unknown"


@contextlib.contextmanager
def output_lock(directory: str | Path, what: str = "output directory") -> Iterator[Path]:
    """Hold the output directory ``directory`` for this run (created if missing; removed
    again at the end if the lock created it and nothing was written): an exclusive,
    non-blocking ``flock`` on ``<directory>/.lock``, which holds the holder's pid. Another
    process holding it: :class:`OutputLockError` naming the directory and that pid. The
    lock dies with its process (a killed run leaves no stale lock); nested use in one
    process is re-entrant. Without ``fcntl`` (Windows) it only creates the directory."""
    p = Path(directory)
    for parent in [p, *p.parents]:
        if parent.exists() and not parent.is_dir():
            raise OutputDirError(f"{what} {p}: {parent} exists and is not a directory")
    created = not p.exists()
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputDirError(f"cannot create {what} {p}: {exc}") from None
    key = os.path.realpath(p)
    if key in _HELD:
        _HELD[key][1] += 1
        try:
            yield p
        finally:
            _HELD[key][1] -= 1
        return
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield p
        return
    lock = p / LOCK_NAME
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o666)
        except OSError as exc:
            if created:
                discard_if_empty(p)
            raise OutputDirError(f"{what} {p} is not writable: {exc}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise OutputLockError(
                f"{what} {p} is in use by another run ({_holder(lock)} holds {lock}); "
                "wait for it to finish (or stop it), or choose another directory"
            ) from None
        try:  # the file may have been removed by the holder that just released it
            same = os.stat(lock).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    os.ftruncate(fd, 0)
    os.write(fd, f"{os.getpid()} {' '.join(sys.argv)[:500]}\n".encode())
    _HELD[key] = [fd, 1, created]
    try:
        yield p
    finally:
        del _HELD[key]
        with contextlib.suppress(OSError):
            lock.unlink()
        os.close(fd)
        if created:
            discard_if_empty(p)


# --------------------------------------------------------------------------------------
# a report of several files, published whole
# --------------------------------------------------------------------------------------


@contextlib.contextmanager
def signals_deferred() -> Iterator[None]:
    """Hold SIGINT and SIGTERM back for the block (a few renames): a signal that arrives
    inside it is delivered, by the handler that was in force, when the block ends. Outside
    the main thread it does nothing (signals reach the main thread only)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    sigs = (signal.SIGINT, signal.SIGTERM)
    old = {s: signal.getsignal(s) for s in sigs}
    for s in sigs:
        if old[s] is not signal.SIG_IGN:
            signal.signal(s, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        for s in sigs:
            signal.signal(s, old[s])
        for s in caught[:1]:
            signal.raise_signal(s)


def publish_report(out: Path, names: Sequence[str]) -> contextlib.AbstractContextManager[Path]:
    """A staging directory (``<out>/.report.partial-*``) for the files ``names`` of a
    report; when the block succeeds, the previous report's ``names`` are removed and the
    staged ones moved in, with SIGINT and SIGTERM held back (:func:`signals_deferred`), in
    the order given — put the file a reader checks first (the JSON) last. A failure or an
    interrupt inside the block removes the staging directory and leaves ``out`` as it was:
    a reader never sees a report that is half the old one and half the new one."""
    return _publish(out, tuple(names))


@contextlib.contextmanager
def _publish(out: Path, names: tuple[str, ...]) -> Iterator[Path]:
    stage = Path(tempfile.mkdtemp(prefix=".report.partial-", dir=out))
    try:
        honour_umask(stage, directory=True)
        yield stage
        missing = [n for n in names if not (stage / n).exists()]
        if missing:
            raise FileNotFoundError(f"report file {missing[0]!r} was not written")
        with signals_deferred():
            for n in reversed(names):  # the one read first goes first
                _remove(out / n)
            for n in names:
                os.replace(stage / n, out / n)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def _remove(q: Path) -> None:
    if q.is_dir() and not q.is_symlink():
        shutil.rmtree(q)
    elif q.exists() or q.is_symlink():
        q.unlink()
