"""Results never depend on the number of workers or of BLAS threads
(:mod:`hyperloop_env.threads`): the same fragility sweep of classical designs whose set-up
runs LAPACK (lqr, mpc) and of a learned agent (ppo), in this process with two BLAS threads
and in two worker processes with one, gives the same JSON."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[3]
ARGS = [
    "-m",
    "agents.fragility",
    "--controllers",
    "lqr",
    "mpc",
    "ppo",
    "--conditions",
    "paper-2000-straight",
    "--family",
    "roughness",
    "--levels",
    "0.3",
    "0.6",
    "--seeds",
    "3",
    "--distance-km",
    "0.7",
    "--settle-s",
    "0.2",
    "--n-boot",
    "20",
    "--n-boot-fragility",
    "20",
    "--no-figures",
    "--no-progress",
]


def _numbers(x: Any, path: str = "") -> dict[str, Any]:
    """Every leaf of a JSON document by its path, without timings and run settings."""
    out: dict[str, Any] = {}
    if isinstance(x, dict):
        for k, v in x.items():
            if k not in ("wall_s", "command", "workers", "backend", "paths"):
                out.update(_numbers(v, f"{path}/{k}"))
    elif isinstance(x, list):
        for i, v in enumerate(x):
            out.update(_numbers(v, f"{path}[{i}]"))
    else:
        out[path] = x
    return out


def _run(out: Path, workers: int, blas_threads: int) -> dict[str, Any]:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": str(blas_threads)}
    done = subprocess.run(
        [sys.executable, *ARGS, "--workers", str(workers), "--out", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return _numbers(json.loads((out / "results.json").read_text()))


def test_one_worker_with_two_blas_threads_equals_two_workers(tmp_path: Path) -> None:
    one = _run(tmp_path / "one", 1, 2)
    two = _run(tmp_path / "two", 2, 2)
    assert one.keys() == two.keys()
    differ = [k for k in one if one[k] != two[k]]
    assert not differ, f"{len(differ)} of {len(one)} values differ, e.g. {differ[:5]}"
    assert any("mpc" in str(v) for v in one.values())  # every controller flew


def _design_digest(name: str, actuators: str, threads: int) -> str:
    """A digest of every array a controller holds after its design, built in this process
    with ``threads`` BLAS threads."""
    import hashlib

    import numpy as np
    from threadpoolctl import threadpool_limits

    from agents.controllers.registry import make_controller
    from hyperloop_env.env import HyperloopSuspensionEnv

    h = hashlib.sha256()

    def walk(o: Any, depth: int = 0) -> None:
        if isinstance(o, np.ndarray):
            h.update(o.tobytes())
        elif isinstance(o, list | tuple):
            for x in o:
                walk(x, depth)
        elif depth < 4 and hasattr(o, "__dict__") and not isinstance(o, type):
            for _, v in sorted(vars(o).items()):
                walk(v, depth + 1)

    with threadpool_limits(limits=threads, user_api="blas"):
        walk(make_controller(name, HyperloopSuspensionEnv(actuators=actuators)))
    return h.hexdigest()


def test_a_design_does_not_depend_on_the_blas_threads() -> None:
    """The Riccati, Schur and QP set-ups (lqr, lqr-preview, mpc) give the same bits with one
    BLAS thread and with two (mpc's differed before make_controller took one thread)."""
    for act in ("levitation", "levitation+guidance"):
        for name in ("lqr", "lqr-preview", "mpc"):
            assert _design_digest(name, act, 1) == _design_digest(name, act, 2), (name, act)
