"""A process that compiles the package's numba kernels says so once on stderr; one that
finds them in numba's disk cache says nothing."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numba as nb
import numpy as np
from numba.core import event as numba_event

import hyperloop_env

ROOT = Path(__file__).resolve().parents[2]
NOTICE = "hyperloop_env: compiling the physics kernels (first run only"

# two of the package's kernels (each its own compilation), small enough to compile in ~1 s
_COMPILE_TWO = """
import numpy as np
from hyperloop_env.physics.layout import NM, NP
from hyperloop_env.reward import gap_term, guidance_term

gap_term(np.zeros(NM), np.ones(NP), 1.0)
guidance_term(np.zeros(NM), np.ones(NP), 1.0)
print("done")
"""


def _run(cache_dir: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache_dir)}
    return subprocess.run(
        [sys.executable, "-c", _COMPILE_TWO],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


def test_a_compiling_process_says_so_once_and_a_cached_one_not_at_all(tmp_path: Path) -> None:
    cold = _run(tmp_path)
    assert cold.returncode == 0 and cold.stdout.strip() == "done", cold.stderr
    assert cold.stderr.count(NOTICE) == 1, cold.stderr
    assert cold.stderr.strip() == hyperloop_env.COMPILE_MESSAGE  # one line, nothing else
    warm = _run(tmp_path)  # the same cache: numba loads both kernels, compiles nothing
    assert warm.returncode == 0 and warm.stdout.strip() == "done", warm.stderr
    assert NOTICE not in warm.stderr, warm.stderr


def _fresh_function(module: str):
    def f(x):
        return x + 1.0

    f.__module__ = module
    return nb.njit(f)


def test_the_notice_speaks_for_the_package_only_and_once(capsys, monkeypatch) -> None:
    monkeypatch.setattr(hyperloop_env.COMPILE_NOTICE, "shown", True)  # the process's own
    notice = hyperloop_env.CompileNotice()
    numba_event.register("numba:compile", notice)
    try:
        _fresh_function("somebody_else")(np.float64(1.0))
        assert capsys.readouterr().err == "" and not notice.shown
        for _ in range(2):
            _fresh_function(hyperloop_env.__name__ + ".probe")(np.float64(1.0))
    finally:
        numba_event.unregister("numba:compile", notice)
    err = capsys.readouterr().err
    assert notice.shown and err.count(NOTICE) == 1, err
