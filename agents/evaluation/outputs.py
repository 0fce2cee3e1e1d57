"""Output directories and files that never lose or mix a user's work.

* :func:`prepare_output_dir` — checked *before* any computation: the path must be a
  writable directory (created if missing); a non-empty directory is refused unless
  ``overwrite`` is given, in which case the files a previous report wrote there (the
  ``owned`` names: report, JSON, CSV, figures) are removed first so no stale figure
  survives beside the new report.
* :func:`atomic_write_text` / :func:`atomic_write_bytes` / :func:`atomic_path` — write to
  a temporary file in the same directory and rename it over the target (``os.replace``):
  an interrupted write leaves the old file or none, never a truncated one.
"""

from __future__ import annotations

import contextlib
import math
import os
import shutil
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any


class OutputDirError(ValueError):
    """The output directory cannot be used (not writable, a file, or not empty)."""


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
    if existed and any(p.iterdir()):
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
        if created and p.is_dir() and not any(p.iterdir()):
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
        yield tmp_path
        os.replace(tmp_path, t)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        raise


def atomic_write_bytes(target: str | Path, data: bytes) -> None:
    with atomic_path(target) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())


def atomic_write_text(target: str | Path, text: str) -> None:
    atomic_write_bytes(target, text.encode("utf-8"))


def json_safe(x: Any) -> Any:
    """``x`` with every value JSON can hold: non-finite floats become None (JSON has no
    NaN/inf), numpy scalars and arrays plain Python numbers and lists, objects with a
    ``to_dict()`` (fit results) their dict; nested dicts, lists and tuples recursively."""
    import numpy as np

    if hasattr(x, "to_dict") and not isinstance(x, dict):
        return json_safe(x.to_dict())
    if isinstance(x, float | np.floating):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [json_safe(v) for v in x]
    if isinstance(x, np.ndarray):
        return json_safe(x.tolist())
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x
