"""The batched products of the linear controllers (:func:`agents.controllers.lqr.
accumulate_rows`): each output is the sum over the inputs in order from +0, rounded as
NumPy's element-wise steps round, whatever the shape, the zero pattern of the matrix and
the alignment of the arrays, and a NaN input reaches every output it has a term in."""

from __future__ import annotations

import numpy as np
import pytest

from agents.controllers.lqr import accumulate_rows
from hyperloop_env.physics.arrays import aligned_zeros


def _in_order(A: np.ndarray, X: np.ndarray) -> np.ndarray:
    """``A @ X`` term by term: out_j = (((+0 + A_j0·X_0) + A_j1·X_1) + …), NumPy's rounding."""
    out = np.zeros((A.shape[0], X.shape[1]))
    for k in range(A.shape[1]):
        out = out + A[:, k : k + 1] * X[k]
    return out


@pytest.mark.parametrize("seed", range(6))
def test_accumulate_rows_is_the_in_order_sum_bit_for_bit(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(25):
        nj, nk, n = (int(v) for v in rng.integers(1, [100, 45, 70]))
        A = rng.standard_normal((nj, nk))
        A[rng.random((nj, nk)) < rng.uniform(0.0, 0.9)] = 0.0  # zero blocks and lone zeros
        A[:, rng.integers(0, nk)] = 0.0
        X = rng.standard_normal((nk, n)) * 10.0 ** rng.integers(-6, 4, size=(nk, 1))
        out = np.full((nj, n), 7.0) if seed % 2 else aligned_zeros((nj, n))
        accumulate_rows(A, X, out)
        assert out.tobytes() == _in_order(A, X).tobytes(), (nj, nk, n)


def test_a_nan_input_reaches_the_outputs_with_a_term_in_it() -> None:
    """Input 4 counts for output 9 only: NaN there, and every output of the blocks of
    eight, four and one rows where input 4 has no term stays finite."""
    rng = np.random.default_rng(11)
    A = rng.standard_normal((21, 9))
    A[:, 4] = 0.0
    A[9, 4] = 1.5
    X = rng.standard_normal((9, 5))
    X[4, 2] = np.nan
    out = np.zeros((21, 5))
    accumulate_rows(A, X, out)
    assert np.isnan(out[9, 2])
    clean = list(range(8)) + list(range(16, 21))  # rows 0-7, 16-19 and 20
    assert np.isfinite(out[clean]).all()
    assert np.isfinite(np.delete(out, 2, axis=1)).all()
