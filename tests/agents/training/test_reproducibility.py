"""A training run reproduces on another machine of the same kind (agents/training/numerics.py).

Another CPU is emulated by restricting Intel MKL to AVX2 (``MKL_ENABLE_INSTRUCTIONS=AVX2``):
on an AVX-512 host that changes MKL's kernels exactly as moving to an AVX2-only host does.
With the pinned numerics (``python train.py``'s default) the weights are identical; without
them (the negative control, only meaningful on an AVX-512 host) they differ.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

pytest.importorskip("stable_baselines3")

ROOT = Path(__file__).resolve().parents[3]


def _cpu_flags() -> str:
    try:
        return Path("/proc/cpuinfo").read_text()
    except OSError:
        return ""


def _train(out: Path, **env: str) -> str:
    e = {k: v for k, v in os.environ.items() if k not in ("MKL_CBWR", "ATEN_CPU_CAPABILITY")}
    e.update(env)
    proc = subprocess.run(
        [
            sys.executable,
            str(ROOT / "train.py"),
            "--preset",
            "tiny",
            "--timesteps",
            "2048",
            "--n-envs",
            "2",
            "--no-eval",
            "--no-progress",
            "--out",
            str(out),
        ],
        cwd=ROOT,
        env=e,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return hashlib.sha256(zipfile.ZipFile(out / "model.zip").read("policy.pth")).hexdigest()


@pytest.mark.skipif(" avx2 " not in _cpu_flags().replace("\n", " "), reason="needs an x86 CPU")
def test_weights_do_not_depend_on_the_cpu_instruction_set(tmp_path: Path) -> None:
    host = _train(tmp_path / "host")
    avx2 = _train(tmp_path / "avx2", MKL_ENABLE_INSTRUCTIONS="AVX2")
    assert host == avx2


@pytest.mark.slow
@pytest.mark.skipif(" avx512f " not in _cpu_flags().replace("\n", " "), reason="needs AVX-512")
def test_negative_control_unpinned_weights_depend_on_the_instruction_set(tmp_path: Path) -> None:
    """Why the pinning exists: unpinned, an AVX-512 host and an AVX2 host train differently
    (so the test above has teeth on an AVX-512 host)."""
    raw_host = _train(tmp_path / "raw_host", MKL_CBWR="", ATEN_CPU_CAPABILITY="")
    raw_avx2 = _train(
        tmp_path / "raw_avx2", MKL_CBWR="", ATEN_CPU_CAPABILITY="", MKL_ENABLE_INSTRUCTIONS="AVX2"
    )
    assert raw_host != raw_avx2
