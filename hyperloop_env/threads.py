"""One BLAS thread where the bits of a result must not depend on the thread count.

OpenBLAS splits a matrix product or a factorisation (``scipy.linalg.solve_discrete_are``,
``schur``, the Riccati and QP set-ups of the controllers) between its threads, and the
split changes the order of the floating-point sums: the same design computed with one
thread and with two differs in its last bits, and a closed loop flown for thousands of
steps turns that into different results. Every computation that feeds a published number
therefore runs with one BLAS thread, whatever the machine or ``OPENBLAS_NUM_THREADS``
says: in the main process and in worker processes alike, so that the number of workers
never changes a result. (The physics kernels are compiled and parallel over independent
vehicles only, so numba's thread count does not change their bits.)

The limit is taken with ``threadpoolctl`` (it reaches every BLAS library loaded in the
process: NumPy's and SciPy's own OpenBLAS builds) and restored on exit.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the block with every loaded BLAS library limited to one thread (restored
    afterwards; nesting is harmless)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        yield
