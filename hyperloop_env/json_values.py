"""Plain Python and JSON values from results and configurations: the one conversion rule.

:func:`json_value` makes a value that ``json.dumps`` can write (every report, manifest,
verification result and STS record goes through it):

* objects with a ``to_dict()`` method (fit results, verification cases) -> their dict;
* dicts -> dicts with string keys (``str(key)`` for non-string keys);
* lists, tuples and NumPy arrays -> lists (a 0-d array -> its scalar);
* NumPy scalars -> Python ``bool`` / ``int`` / ``float`` (:func:`python_number`);
* non-finite floats (NaN, +-inf): ``non_finite="null"`` (the default, for files read by
  other tools: strict JSON has no NaN) -> ``None``; ``non_finite="keep"`` -> kept (written
  as ``NaN`` / ``Infinity``; for checkpoint manifests and verification records, which
  round-trip through Python's own ``json``);
* paths (``os.PathLike``) -> ``str``;
* anything else (``str``, ``None``, ...) unchanged.

:func:`python_numbers` applies only the number rule: NumPy scalars become Python ``bool`` /
``int`` / ``float`` inside nested dicts, lists and tuples, whose types and keys are kept,
and everything else is left as it is (for configurations given programmatically).
"""

from __future__ import annotations

import math
import os
from typing import Any, Literal

import numpy as np

NonFinite = Literal["null", "keep"]


def json_value(x: Any, *, non_finite: NonFinite = "null") -> Any:
    """``x`` as a value ``json.dumps`` can write (the rule is in the module docstring)."""
    if non_finite not in ("null", "keep"):
        raise ValueError(f"non_finite must be 'null' or 'keep', got {non_finite!r}")
    return _json(x, non_finite == "null")


def _json(x: Any, null: bool) -> Any:
    if isinstance(x, dict):
        return {k if isinstance(k, str) else str(k): _json(v, null) for k, v in x.items()}
    if hasattr(x, "to_dict"):
        return _json(x.to_dict(), null)
    if isinstance(x, bool | int | float | np.bool_ | np.integer | np.floating):
        v = python_number(x)
        return None if null and isinstance(v, float) and not math.isfinite(v) else v
    if isinstance(x, list | tuple):
        return [_json(v, null) for v in x]
    if isinstance(x, np.ndarray):
        return _json(x.tolist(), null)
    if isinstance(x, os.PathLike):
        return os.fspath(x)
    return x


def python_numbers(x: Any) -> Any:
    """``x`` with NumPy scalars replaced by Python ``bool`` / ``int`` / ``float`` (also in
    nested dicts, lists and tuples, which keep their type and keys)."""
    if isinstance(x, dict):
        return {k: python_numbers(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return type(x)(python_numbers(v) for v in x)
    return python_number(x)


def python_number(x: Any) -> Any:
    """A NumPy scalar as a Python ``bool`` / ``int`` / ``float``; anything else unchanged."""
    if isinstance(x, np.bool_):
        return bool(x)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.floating):
        return float(x)
    return x
