"""Result type and small helpers shared by the verification modules.

:class:`CaseResult` is the outcome of one verification case (see
:mod:`hyperloop_env.verification` for the registry and the command-line interface).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class CaseResult:
    """Outcome of one verification case.

    Comparison cases fill ``computed``, ``reference`` and ``rel_error`` (checked against
    ``tolerance``); threshold cases fill ``value`` and ``threshold`` (``tolerance`` repeats
    the threshold). ``info`` holds extra, non-graded numbers."""

    name: str
    description: str
    passed: bool
    tolerance: float
    computed: float | None = None
    reference: float | None = None
    rel_error: float | None = None
    value: float | None = None
    threshold: float | None = None
    info: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"description": self.description}
        if self.computed is not None:
            out["computed"] = self.computed
            out["reference"] = self.reference
            out["rel_error"] = self.rel_error
        if self.value is not None:
            out["value"] = self.value
            out["threshold"] = self.threshold
        out["tolerance"] = self.tolerance
        out["passed"] = self.passed
        if self.info:
            out["info"] = jsonable(self.info)
        return out


def jsonable(obj: Any) -> Any:
    """``obj`` with numpy scalars/arrays and tuples turned into JSON-serialisable types."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple | np.ndarray):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.bool_ | bool):
        return bool(obj)
    if isinstance(obj, np.integer | int):
        return int(obj)
    if isinstance(obj, np.floating | float):
        return float(obj)
    return obj


def compare(
    name: str,
    description: str,
    computed: float,
    reference: float,
    tolerance: float,
    info: dict[str, Any] | None = None,
    extra_ok: bool = True,
) -> CaseResult:
    """Comparison case: passes if |computed − reference|/|reference| <= tolerance (and
    ``extra_ok``, a further condition documented in the case's description)."""
    rel = abs(computed - reference) / abs(reference)
    return CaseResult(
        name=name,
        description=description,
        passed=bool(rel <= tolerance and extra_ok),
        tolerance=tolerance,
        computed=float(computed),
        reference=float(reference),
        rel_error=float(rel),
        info=info or {},
    )


def threshold(
    name: str,
    description: str,
    value: float,
    limit: float,
    passed: bool,
    info: dict[str, Any] | None = None,
) -> CaseResult:
    """Threshold case: ``passed`` is decided by the caller (value against ``limit``)."""
    return CaseResult(
        name=name,
        description=description,
        passed=bool(passed),
        tolerance=float(limit),
        value=float(value),
        threshold=float(limit),
        info=info or {},
    )
