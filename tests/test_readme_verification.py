"""The site's verification table (docs/verification.md) is what ``hyperloop verify
--markdown`` prints: the page holds the generated block, and the generator
(docs/_ext/hyperloop_docs.py, run when the site is built) gives every registered case in
order, with its outcome, value, reference and tolerance from a fresh run."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

from hyperloop_env.verification.registry import outcome, run_all

ROOT = Path(__file__).resolve().parents[1]


def _generators():  # noqa: ANN202
    spec = importlib.util.spec_from_file_location(
        "hyperloop_docs", ROOT / "docs" / "_ext" / "hyperloop_docs.py"
    )
    mod = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(mod)  # type: ignore[union-attr]
    return mod


def _rows(table: str) -> list[list[str]]:
    return [
        [c.strip() for c in line.strip("|").split("|")]
        for line in table.splitlines()
        if line.startswith("| `")
    ]


def test_the_page_shows_the_generated_table() -> None:
    page = (ROOT / "docs" / "verification.md").read_text()
    assert page.count("<!-- generated: verification -->") == 1
    assert "| case | computed" not in page  # no hand-copied table beside it


def test_the_generated_table_is_a_fresh_run() -> None:
    results = run_all()
    table = _generators().generated("verification")
    rows = _rows(table)
    assert [r[0].strip("`") for r in rows] == list(results)
    for row in rows:
        name = row[0].strip("`")
        r = results[name]
        assert row[5] == outcome(name, r) == "PASS", name
        tol = float(row[4])
        if row[3] != "-":  # computed vs reference
            assert math.isclose(float(row[1]), r.computed, rel_tol=1e-4), name
            assert math.isclose(float(row[2]), r.reference, rel_tol=1e-5), name
            assert float(row[3]) <= tol, name
        else:  # a value against a threshold
            v = float(row[1])
            if abs(r.value) > 1e-6:
                assert math.isclose(v, r.value, rel_tol=0.01), name
    assert f"({len(results)}/{len(results)} pass.)" in table
