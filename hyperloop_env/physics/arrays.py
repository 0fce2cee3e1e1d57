"""Arrays for the compiled kernels whose data start on a cache-line boundary.

NumPy's allocator aligns an array's data to 16 bytes. The compiled kernels' vectorised
loops load and store 32 bytes at a time (AVX2), so on a 16-byte boundary every other access
straddles two 64-byte cache lines. For a kernel that streams through its buffers (a
controller's batched products, rows of the batch innermost) that costs up to half of its
time, decided by where the allocator happened to place the buffer: the MPC's condensed
prediction (96 × 30 per row, 64 rows, :func:`agents.controllers.lqr.accumulate_rows`) takes
13–14 µs with its output on a 32-byte boundary and 15–16 µs on a 16-byte one (15 against
22 µs with one term per pass, as the product was first written), and ``np.zeros`` gives
either, allocation by allocation (``python speed/bench_alignment.py``).
:func:`aligned_zeros` places the data on a 64-byte boundary, so every row whose length is a
multiple of eight float64 starts a cache line. Only the placement changes, never an
operation or its order, so every result is the same bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np

FLOAT32, FLOAT64 = np.dtype(np.float32), np.dtype(np.float64)
"""NumPy's dtype objects of float32 and float64. Arrays made with either dtype hold these very
objects, so a check made at every control step tests identity first (``dt is FLOAT32``)
and equality only if that fails (``dt == np.float32`` converts the type on every call,
several times slower). An equal dtype that is another object, such as an unpickled
array's, still passes through the equality test."""


def is_float(dt: np.dtype) -> bool:
    """True if the dtype ``dt`` is float32 or float64: identity with :data:`FLOAT32` /
    :data:`FLOAT64` first, equality after (the per-step dtype check of the controllers and
    the environment)."""
    return dt is FLOAT32 or dt is FLOAT64 or dt == FLOAT32 or dt == FLOAT64


CACHE_LINE_BYTES = 64
"""The alignment of :func:`aligned_zeros` [bytes]: one cache line of x86-64 and ARMv8."""


def aligned_zeros(shape: int | tuple[int, ...], dtype: Any = np.float64) -> np.ndarray:
    """``np.zeros(shape, dtype)``, C-contiguous, its data on a :data:`CACHE_LINE_BYTES`
    boundary (a view into a slightly larger buffer it keeps alive; an empty array has no
    data to place)."""
    dt = np.dtype(dtype)
    dims = (shape,) if isinstance(shape, int | np.integer) else tuple(shape)
    if any(int(d) < 0 for d in dims):
        raise ValueError(f"aligned_zeros: negative dimension in shape {shape!r}")
    nbytes = int(np.prod(dims, dtype=np.int64)) * dt.itemsize
    if nbytes == 0:  # no data to place
        return np.zeros(dims, dt)
    buf = np.zeros(nbytes + CACHE_LINE_BYTES, dtype=np.uint8)
    start = -buf.ctypes.data % CACHE_LINE_BYTES
    return buf[start : start + nbytes].view(dt).reshape(dims)


def aligned_copy(a: Any, dtype: Any = None) -> np.ndarray:
    """A C-contiguous copy of ``a`` (as ``dtype``, by default its own) on a cache-line
    boundary: :func:`aligned_zeros` filled with ``a``."""
    src = np.asarray(a, dtype=dtype)
    out = aligned_zeros(src.shape, src.dtype)
    out[...] = src
    return out
