"""Pinned CPU numerics, so that a training run reproduces on another machine.

Training is a long chain of floating-point operations that amplifies any rounding
difference. PyTorch's CPU kernels are chosen *per machine*: Intel MKL (the BLAS behind
every ``Linear`` layer) dispatches to the widest instruction set the CPU has (AVX-512 on
one host, AVX2 on another) and rounds its dot products differently on each, so the same
seed gave different weights on two machines of the same kind
(``agents/shipped/README.md``, ``scripts/repro_check.py``). Measured here (32 768 steps,
same seed): the default run and the same run with MKL restricted to AVX2 end with
different weights; with MKL's conditional numerical reproducibility pinned to the AVX2
code path (``MKL_CBWR=AVX2``) and ATen's vectorised kernels pinned to AVX2
(``ATEN_CPU_CAPABILITY=avx2``) the weights are identical whatever MKL may use. The
simulator itself (numba, no fast-math) is identical with numba's generic CPU target.

:func:`pin_cpu_numerics` sets both variables (unless the user set them) and must run
before torch is imported; ``agents.training`` calls it on import, so ``python train.py``
is pinned. Scope of the reproducibility claim: x86-64 CPUs with AVX2 (every current cloud
x86 machine), the same versions of Python, NumPy, torch, SB3 and Gymnasium (recorded in
``training_log.json``), and one torch thread (``train()`` sets it).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

PINNED = {"MKL_CBWR": "AVX2", "ATEN_CPU_CAPABILITY": "avx2"}


def cpu_has_avx2() -> bool:
    """True if /proc/cpuinfo lists avx2 (Linux x86-64); False where it cannot tell."""
    try:
        return " avx2 " in f" {Path('/proc/cpuinfo').read_text().replace(chr(10), ' ')} "
    except OSError:
        return False


def pin_cpu_numerics() -> dict[str, str]:
    """Pin MKL's and ATen's code paths (see the module docstring); returns what is in
    effect. A variable the user set is left alone; on a CPU without AVX2 nothing is set."""
    if cpu_has_avx2():
        for k, v in PINNED.items():
            os.environ.setdefault(k, v)
    return numerics_state()


def numerics_state() -> dict[str, str]:
    """The settings in effect, for the training log (``torch_imported_before`` tells if a
    caller imported torch before the pinning could apply)."""
    state = {k: os.environ.get(k, "") for k in PINNED}
    state["torch_imported_before_pinning"] = str("torch" in sys.modules and _IMPORTED_EARLY)
    return state


_IMPORTED_EARLY = "torch" in sys.modules
