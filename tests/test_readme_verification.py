"""The README's verification table is what ``python -m hyperloop_env.verification
--markdown`` prints: the same cases in the same order with the same outcomes, values and
references to the printed precision (rounding-level quantities — relative errors below
1e-6, residuals far below their threshold — differ between CPUs and are only checked
against their tolerance)."""

from __future__ import annotations

import math
from pathlib import Path

from hyperloop_env.verification.registry import outcome, run_all
from hyperloop_env.verification.report import markdown_table

ROOT = Path(__file__).resolve().parents[1]


def _rows(table: str) -> list[list[str]]:
    return [
        [c.strip() for c in line.strip("|").split("|")]
        for line in table.splitlines()
        if line.startswith("| `")
    ]


def _readme_table() -> str:
    text = (ROOT / "README.md").read_text()
    sec = text.split("## Verification", 1)[1]
    start = sec.index("| case | computed / value |")
    return sec[start : sec.index("\n\n", start)]


def test_readme_verification_table_matches_a_fresh_run() -> None:
    results = run_all()
    fresh, readme = _rows(markdown_table(results)), _rows(_readme_table())
    assert [r[0] for r in readme] == [r[0] for r in fresh]
    for old, new in zip(readme, fresh, strict=True):
        name = old[0].strip("`")
        r = results[name]
        assert old[5] == new[5] == outcome(name, r), name
        assert old[4] == new[4], name  # tolerance
        tol = float(old[4])
        if old[3] != "-":  # computed vs reference
            assert math.isclose(float(old[1]), r.computed, rel_tol=1e-4), name
            assert math.isclose(float(old[2]), r.reference, rel_tol=1e-5), name
            assert float(old[3]) <= tol, name
            if r.rel_error >= 1e-6:
                assert math.isclose(float(old[3]), r.rel_error, rel_tol=0.02), name
        else:  # a value against a threshold
            assert old[2] == new[2], name
            v, thr = float(old[1]), float(old[2])
            if abs(r.value) > 1e-3 * max(abs(thr), 1e-300) and abs(r.value) > 1e-6:
                assert math.isclose(v, r.value, rel_tol=0.01), name
