"""Compiled kernels called without numba's per-call type dispatch.

Calling a ``numba.njit`` function (its dispatcher) infers the numba type of every argument
and looks up the specialisation compiled for those types, on every call. For the kernels
of a control step, called with many arrays, that lookup is a visible part of the step: a
call with eleven array arguments that does nothing took 0.48 µs through the dispatcher and
0.17 µs through the specialisation itself (``python speed/bench_dispatch.py``, 2026-12-06,
on the 2-core machine of the performance docs). :func:`compiled_entry` looks the
specialisation up once, for types fixed in advance, and returns it to be called directly.

The specialisation checks only that each array argument is a NumPy array of the expected
item size (numba's unboxing): an array of another number of dimensions, layout or kind
would be read wrong. So a caller binds an entry only for arguments whose types it owns (its
own buffers) and checks the one argument it does not own (an observation's or an action's
dtype and number of dimensions). It binds that argument as any layout (:func:`strided`),
which the compiled code reads through its strides, or as C-ordered where reading through
strides would cost more than the dispatch (a loop that vectorises over contiguous entries
only), and then calls the dispatcher itself for any other layout. The arithmetic is that of
the dispatcher's specialisation for the same types, so every result is the same bit for bit.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numba as nb
import numpy as np
from numba.core import types


def strided(dtype: Any, ndim: int) -> types.Array:
    """The numba type of a writable array of ``dtype`` and ``ndim`` dimensions in any layout
    (read through its strides): the type to bind an argument the caller does not own."""
    return types.Array(nb.from_dtype(np.dtype(dtype)), ndim, "A")


def compiled_entry(dispatcher: Any, *args: Any) -> Callable[..., Any]:
    """The specialisation of ``dispatcher`` (a ``numba.njit`` function) for ``args`` (each a
    value, typed as numba types it, or a numba type), compiled or loaded from numba's cache
    now: a function to call with arguments of exactly those types (module docstring)."""
    if not hasattr(dispatcher, "compile") or not hasattr(dispatcher, "py_func"):
        raise TypeError(f"compiled_entry: {dispatcher!r} is not a numba.njit function")
    sig = tuple(a if isinstance(a, types.Type) else nb.typeof(a) for a in args)
    return dispatcher.compile(sig)
