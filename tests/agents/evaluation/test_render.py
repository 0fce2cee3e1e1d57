"""The one renderer of the evaluation's tables (issue 19 point 6)."""

from __future__ import annotations

import math

import pytest

from agents.evaluation import render


def test_table_header_alignment_and_rows() -> None:
    text = render.table(("a", "b"), [(1, "x"), ("", 2.5)], "lr")
    assert text == "| a | b |\n|---|---:|\n| 1 | x |\n|  | 2.5 |\n"
    corner = render.table(("", "p", "q"), [("p", "—", ">")])
    assert corner.splitlines()[0] == "| | p | q |"  # a matrix's empty corner
    with pytest.raises(ValueError, match="align"):
        render.table(("a", "b"), [], "l")


def test_formatters() -> None:
    assert render.probability(5.1e-7) == "5.1e-07" and render.probability(None) == "n/a"
    assert render.probability(1) == "1" and render.probability(math.nan) == "n/a"
    assert render.fixed(0.51234) == "0.512" and render.fixed(2.0, 1) == "2.0"
    assert render.fixed(math.inf) == "n/a" and render.fixed("gap") == "gap"
    assert render.significant(0.0038) == "0.0038" and render.significant(None) == "n/a"
    assert render.interval(0.1, 0.25) == "[0.1, 0.25]"
    assert render.with_interval(0.123, [0.1, 0.2], 2) == "0.12 [0.1, 0.2]"
    assert render.with_interval(0.123, [None, 0.2], 2) == "0.12"
    assert render.with_interval(math.nan, [0.1, 0.2]) == "n/a"
