"""No lost work on the output surfaces (issue 17, part 2): files honour the umask, one run
per output directory (a lock naming the holder's pid), directories that appear whole."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from agents.evaluation import outputs
from agents.evaluation.outputs import OutputLockError

ROOT = Path(__file__).resolve().parents[3]


def _mode(p: Path) -> int:
    return stat.S_IMODE(p.stat().st_mode)


@pytest.mark.parametrize("mask", [0o022, 0o002, 0o077])
def test_atomic_files_and_dirs_honour_the_umask(tmp_path: Path, mask: int) -> None:
    """Reports, models and checkpoints (all written through atomic_path) get 0o666 less
    the umask, as a plain open() gives, not mkstemp's 0600; atomic_dir 0o777 less it."""
    old = os.umask(mask)
    try:
        outputs.atomic_write_text(tmp_path / "report.md", "x")
        with outputs.atomic_path(tmp_path / "model.zip") as tmp:
            with open(tmp, "wb") as fh:  # how SB3 / pickle / savefig write the temp name
                fh.write(b"zip")
        with outputs.atomic_dir(tmp_path / "block") as d:
            (d / "results.json").write_text("{}")
        plain = tmp_path / "plain"
        plain.write_text("x")
    finally:
        os.umask(old)
    assert _mode(tmp_path / "report.md") == 0o666 & ~mask == _mode(plain)
    assert _mode(tmp_path / "model.zip") == 0o666 & ~mask
    assert _mode(tmp_path / "block") == 0o777 & ~mask


def test_atomic_dir_appears_whole_or_not_at_all(tmp_path: Path) -> None:
    target = tmp_path / "levitation"
    with pytest.raises(KeyboardInterrupt), outputs.atomic_dir(target) as d:
        (d / "figures").mkdir()
        raise KeyboardInterrupt
    assert not target.exists() and not list(tmp_path.iterdir())
    target.mkdir()
    (target / "figures").mkdir()  # an unfinished earlier attempt is replaced
    with outputs.atomic_dir(target) as d:
        (d / "results.json").write_text("{}")
    assert sorted(q.name for q in target.iterdir()) == ["results.json"]
    assert [q.name for q in tmp_path.iterdir()] == ["levitation"]


def test_output_lock_refuses_a_second_holder_naming_dir_and_pid(
    tmp_path: Path, folder_holder
) -> None:  # noqa: ANN001
    d = tmp_path / "run"
    proc = folder_holder(d)
    with pytest.raises(OutputLockError, match=rf"{d}.*in use.*pid {proc.pid}"):
        with outputs.output_lock(d):
            pass
    # the directory's lock file is not content: a new run may still use it
    assert outputs.prepare_output_dir(d) == d
    proc.kill()
    proc.wait()
    # a killed holder leaves no stale lock
    with outputs.output_lock(d), outputs.output_lock(d):  # re-entrant in one process
        assert (d / outputs.LOCK_NAME).read_text().split()[0] == str(os.getpid())
    assert not (d / outputs.LOCK_NAME).exists()


def test_output_lock_removes_the_directory_it_created_if_nothing_was_written(
    tmp_path: Path,
) -> None:
    with outputs.output_lock(tmp_path / "new"):
        assert (tmp_path / "new").is_dir()
    assert not (tmp_path / "new").exists()
    with outputs.output_lock(tmp_path / "kept"):
        (tmp_path / "kept" / "a").write_text("x")
    assert [q.name for q in (tmp_path / "kept").iterdir()] == ["a"]
