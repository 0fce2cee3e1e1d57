"""Cache-line aligned arrays: zeros of the asked shape and dtype, C-contiguous, their data
on a 64-byte boundary whatever the allocator's placement, and bad shapes refused; the
per-step float dtype check."""

from __future__ import annotations

import numpy as np
import pytest

from hyperloop_env.physics.arrays import CACHE_LINE_BYTES, aligned_copy, aligned_zeros, is_float


@pytest.mark.parametrize(
    ("shape", "dtype"),
    [((96, 64), np.float64), ((4, 1), np.float64), (7, np.bool_), (13, np.int64), ((0, 3), float)],
)
def test_aligned_zeros_are_zeros_on_a_cache_line(shape, dtype) -> None:  # noqa: ANN001
    keep = [np.zeros(k) for k in range(1, 9)]  # move the allocator around
    for _ in range(8):
        a = aligned_zeros(shape, dtype)
        keep.append(np.zeros(3))
        assert a.ctypes.data % CACHE_LINE_BYTES == 0 or a.size == 0
        assert a.flags.c_contiguous and a.flags.writeable
        assert a.shape == ((shape,) if isinstance(shape, int) else shape)
        assert a.dtype == np.dtype(dtype) and not a.any()


def test_aligned_copy_keeps_the_values_and_the_dtype() -> None:
    src = np.arange(30.0).reshape(5, 6)[:, ::2]  # not contiguous
    b = aligned_copy(src)
    assert b.ctypes.data % CACHE_LINE_BYTES == 0 and b.flags.c_contiguous
    assert np.array_equal(b, src) and b.dtype == src.dtype
    c = aligned_copy([1, 2, 3], np.int64)
    assert c.dtype == np.int64 and c.tolist() == [1, 2, 3]


def test_a_negative_dimension_is_refused() -> None:
    with pytest.raises(ValueError, match="negative dimension"):
        aligned_zeros((3, -1))


def test_is_float_takes_float32_and_float64_only_whatever_the_dtype_object() -> None:
    """NumPy's own dtype objects pass by identity; an equal dtype that is another object (an
    unpickled array's) by equality; other dtypes and byte orders do not pass."""
    import pickle

    for dt in (np.float32, np.float64):
        a = np.zeros(3, dtype=dt)
        b = pickle.loads(pickle.dumps(a))
        assert b.dtype is not a.dtype and b.dtype == a.dtype  # another object, equal
        assert is_float(a.dtype) and is_float(b.dtype)
    for dt in (np.float16, np.int64, np.bool_, np.complex128, ">f8" if np.little_endian else "<f8"):
        assert not is_float(np.dtype(dt))
