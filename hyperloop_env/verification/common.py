"""Result type and small helpers shared by the verification case modules.

:class:`CaseResult` is the outcome of one verification case (see
:mod:`hyperloop_env.verification.registry` for the registry and
:mod:`hyperloop_env.verification.cli` for the command line's flags);
:class:`ConstantCurrentRhs` calls the compiled right-hand side with constant currents.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hyperloop_env.json_values import json_value
from hyperloop_env.physics.layout import P_NMODES
from hyperloop_env.physics.model import neutral_commands
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES
from hyperloop_env.physics.vehicle import NU, rhs


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
            out["info"] = json_value(self.info, non_finite="keep")
        return out


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


class ConstantCurrentRhs:
    """Python wrapper of the compiled right-hand side
    :func:`~hyperloop_env.physics.vehicle.rhs` with constant currents: the levitation
    magnets at ``current`` [A], the guidance pairs at their bias. ``nfev`` counts the calls;
    ``uo`` holds the unit outputs of the last call."""

    def __init__(self, P: np.ndarray, irr: np.ndarray, spans: np.ndarray, current: float):
        self.P = P
        self.irr = irr
        self.spans = spans
        nm = int(P[P_NMODES])
        self.cur = neutral_commands(P)  # full command vector: guidance pairs at bias
        self.cur[: len(UNIT_NAMES)] = current
        self.wts = np.zeros((N_UNITS, 2, nm))
        self.uo = np.zeros((NU, N_UNITS))
        self.nfev = 0

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
        d = np.empty_like(y)
        rhs(t, y, self.P, self.irr, 0.0, self.cur, self.cur, self.spans, d, self.wts, self.uo)
        self.nfev += 1
        return d
