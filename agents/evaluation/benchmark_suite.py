"""The benchmark suite (``agents/evaluation/benchmark_suite.json``, written by ``hyperloop
calibrate`` from the passive and PID baselines): its families' levels, fitting grids and
fixed disturbances, read and checked (:func:`load_suite`) and shown (:func:`suite_markdown`)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from agents.evaluation.render import (
    table,
)

SUITE_FILE = Path(__file__).with_name("benchmark_suite.json")


def load_suite(path: str | Path | None = None) -> dict[str, Any]:
    """The benchmark suite (module docstring); ValueError naming the problem if the file
    is missing a field or a family is unknown."""
    from hyperloop_env.disturbances import DISTURBANCES

    p = Path(path) if path is not None else SUITE_FILE
    try:
        suite = json.loads(p.read_text(), parse_constant=_no_constant)
    except FileNotFoundError:
        raise ValueError(f"no benchmark suite at {p} (write it with hyperloop calibrate)") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ValueError(f"{p}: not a readable JSON suite ({exc})") from None
    if not isinstance(suite, dict):
        raise ValueError(f"{p}: a suite is a JSON object with 'families', got a {_kind(suite)}")
    fams = suite.get("families")
    if not isinstance(fams, dict) or not fams:
        raise ValueError(f"{p}: 'families' must be a non-empty mapping")
    for name, spec in fams.items():
        if name not in DISTURBANCES:
            raise ValueError(f"{p}: unknown family {name!r}; known: {sorted(DISTURBANCES)}")
        if not isinstance(spec, dict):
            raise ValueError(f"{p}: families.{name} must be an object, got a {_kind(spec)}")
        fixed = spec.get("fixed", {})
        if not isinstance(fixed, dict) or not all(
            k in DISTURBANCES and _positive(v) for k, v in fixed.items()
        ):
            raise ValueError(
                f"{p}: families.{name}.fixed must map disturbance names to positive "
                f"severities, got {fixed!r}"
            )
        for key in ("levels", "grid"):
            v = spec.get(key)
            if not isinstance(v, list) or not v or not all(_positive(x) for x in v):
                raise ValueError(
                    f"{p}: families.{name}.{key} must be a non-empty list of "
                    f"positive numbers, got {v!r}"
                )
        spec.setdefault("fixed", {})
    return suite


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number JSON allows")


def _kind(x: Any) -> str:
    return {list: "list", str: "string", dict: "object"}.get(type(x), type(x).__name__)


def _positive(x: Any) -> bool:
    return not isinstance(x, bool) and isinstance(x, int | float) and math.isfinite(x) and x > 0


def suite_markdown(suite: dict[str, Any]) -> str:
    """The suite as a Markdown table (family, unit, levels, grid, fixed)."""
    from hyperloop_env.disturbances import DISTURBANCES

    rows = [
        (
            name,
            DISTURBANCES[name].severity_unit,
            ", ".join(f"{v:g}" for v in spec["levels"]),
            ", ".join(f"{v:g}" for v in spec["grid"]),
            ", ".join(f"{k} = {v:g}" for k, v in spec["fixed"].items()) or "—",
        )
        for name, spec in suite["families"].items()
    ]
    header = (
        "family",
        "severity unit",
        "suite levels (low, mid, high)",
        "fragility grid",
        "held fixed",
    )
    return table(header, rows)


REFERENCE_FAMILY = "roughness"


HEADLINE_FAMILIES = ("roughness", "pier_settlement", "thermal_camber")
"""The families of the README headline (roughness and two more; the others of the suite
run with ``--families``)."""
