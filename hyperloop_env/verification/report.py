"""The verification results as a text table, as the README's Markdown table, or as one JSON
object (:func:`render`: one of :data:`FORMATS`)."""

from __future__ import annotations

import json
from typing import Any

from hyperloop_env.verification.common import CaseResult
from hyperloop_env.verification.registry import KNOWN_FAILURES, outcome


def _fmt(x: float | None) -> str:
    return "-" if x is None else f"{x:.6g}"


def format_table(results: dict[str, CaseResult]) -> str:
    """One line per case (computed or value, reference or threshold, relative error,
    tolerance, outcome) and a summary line."""
    w = max(34, *(len(n) for n in results)) if results else 34
    lines = [
        f"{'case':{w}s} {'computed/value':>15s} {'reference/thr':>15s} "
        f"{'rel_error':>10s} {'tol':>8s}  result"
    ]
    for name, r in results.items():
        if r.computed is not None:
            a, b, e = _fmt(r.computed), _fmt(r.reference), f"{r.rel_error:.2e}"
        else:
            a, b, e = _fmt(r.value), _fmt(r.threshold), "-"
        lines.append(
            f"{name:{w}s} {a:>15s} {b:>15s} {e:>10s} {r.tolerance:8.1e}  {outcome(name, r)}"
        )
        if "speedup" in r.info:
            lines.append(
                f"{'':{w}s} RK4 {r.info['rk4_wall_s']:.3g} s, Radau {r.info['radau_wall_s']:.3g}"
                f" s: speed-up x{r.info['speedup']:.0f}"
            )
        if name in KNOWN_FAILURES:
            lines.append(f"{'':{w}s} known failure: {KNOWN_FAILURES[name]}")
    counts = {k: 0 for k in ("PASS", "FAIL", "XFAIL", "XPASS")}
    for name, r in results.items():
        counts[outcome(name, r)] += 1
    summary = f"{counts['PASS']}/{len(results)} passed"
    if counts["XFAIL"] or counts["XPASS"]:
        summary += f", {counts['XFAIL']} known failures (XFAIL), {counts['XPASS']} XPASS"
    lines.append(summary)
    return "\n".join(lines)


def markdown_table(results: dict[str, CaseResult]) -> str:
    """The README's table (section "Verification"): one row per case, the columns of
    :func:`format_table` (``tests/test_readme_verification.py`` checks the README's copy
    against a fresh run)."""
    lines = [
        "| case | computed / value | reference / threshold | rel. error | tolerance | result |",
        "|---|---:|---:|---:|---:|---|",
    ]
    for name, r in results.items():
        if r.computed is not None:
            a, b, e = _fmt(r.computed), _fmt(r.reference), f"{r.rel_error:.2e}"
        else:
            a, b, e = _fmt(r.value), _fmt(r.threshold), "-"
        lines.append(f"| `{name}` | {a} | {b} | {e} | {r.tolerance:.1e} | {outcome(name, r)} |")
    return "\n".join(lines)


def results_json(results: dict[str, CaseResult]) -> dict[str, dict[str, Any]]:
    """``CaseResult.to_dict`` per case name; a known failure also carries its reason
    (``known_failure``) and its ``outcome`` (XFAIL or XPASS)."""
    out = {}
    for k, r in results.items():
        d = r.to_dict()
        if k in KNOWN_FAILURES:
            d["known_failure"] = KNOWN_FAILURES[k]
            d["outcome"] = outcome(k, r)
        out[k] = d
    return out


FORMATS = ("table", "markdown", "json")


def render(results: dict[str, CaseResult], fmt: str = "table") -> str:
    """The results as ``fmt``: ``table`` (:func:`format_table`), ``markdown``
    (:func:`markdown_table`) or ``json`` (:func:`results_json`, indented)."""
    if fmt == "json":
        return json.dumps(results_json(results), indent=2)
    if fmt == "markdown":
        return markdown_table(results)
    if fmt == "table":
        return format_table(results)
    raise ValueError(f"format must be one of {FORMATS}, got {fmt!r}")
