"""The compiled kernels' entries (:mod:`hyperloop_env.physics.entry`): the dispatcher's
results, strided arguments read through their strides, a clear error for a plain function."""

from __future__ import annotations

import numba as nb
import numpy as np
import pytest

from hyperloop_env.physics.entry import compiled_entry, strided


@nb.njit(_nrt=False)
def _weighted_sum(x, w, k):  # type: ignore[no-untyped-def]  # pragma: no cover - compiled
    s = 0.0
    for i in range(x.shape[0]):
        for j in range(x.shape[1]):
            s += x[i, j] * w[j] * k
    return s


def test_entry_gives_the_dispatchers_result_for_the_types_it_was_bound_to() -> None:
    rng = np.random.default_rng(0)
    x, w = rng.normal(size=(7, 5)), rng.normal(size=5)
    entry = compiled_entry(_weighted_sum, x, w, 3)
    assert entry(x, w, 3) == _weighted_sum(x, w, 3)
    assert entry(x, w, 3) == pytest.approx(3.0 * float((x @ w).sum()), rel=1e-12)


def test_strided_entry_reads_any_layout_and_dtype_as_bound() -> None:
    rng = np.random.default_rng(1)
    x = rng.normal(size=(6, 4)).astype(np.float32)
    w = rng.normal(size=4)
    entry = compiled_entry(_weighted_sum, strided(np.float32, 2), w, nb.int64)
    want = _weighted_sum(np.ascontiguousarray(x), w, 2)
    wide = np.zeros((12, 8), dtype=np.float32)
    wide[::2, ::2] = x
    for view in (x, wide[::2, ::2], np.asfortranarray(x), np.flipud(np.flipud(x).copy())):
        assert entry(view, w, 2) == want
    assert strided("float64", 1) == nb.types.Array(nb.float64, 1, "A")


def test_a_plain_function_is_a_type_error_naming_it() -> None:
    with pytest.raises(TypeError, match="is not a numba.njit function"):
        compiled_entry(_weighted_sum.py_func, np.zeros((1, 1)), np.zeros(1), 1)
