"""The one renderer of the evaluation's tables: a Markdown table (header + rows → text)
and the number formatters, named by what they format. Every report of evaluate,
reproduce_paper, fragility, benchmark and capacity builds its tables here; the figures
are in :mod:`agents.evaluation.figures`.

Missing values (None, NaN, ±inf where a number is expected) print as ``n/a`` unless a
formatter says otherwise. The formatters keep the published numbers as they are: where
two tables print the same kind of number differently (a probability in the STS form of
the paper's tables or with two significant digits in the benchmark headline), both
forms are formatters here rather than one table changing its numbers."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from hyperloop_env.sts import format_probability

NA = "n/a"
"""What a missing value prints as."""


def missing(x: Any) -> bool:
    """True for None and for a float that is NaN or infinite."""
    return x is None or (isinstance(x, float) and not math.isfinite(x))


def probability(p: Any) -> str:
    """A probability in the form of the paper's STS tables (never rounds a small value to
    zero: ``5.1e-07``; 0 and 1 exact; else four significant digits),
    :func:`hyperloop_env.sts.format_probability`."""
    return NA if missing(p) else format_probability(float(p))


def fixed(x: Any, decimals: int = 3) -> str:
    """A number with ``decimals`` digits after the point (``0.512``); a value that is not
    a number (a label) as it is."""
    if missing(x):
        return NA
    if isinstance(x, float):
        return f"{x:.{decimals}f}"
    return str(x)


def significant(x: Any, digits: int = 3) -> str:
    """A number with ``digits`` significant digits (``0.0038``, ``1.2e+03``); None prints
    ``n/a``, a non-finite float as Python prints it (``nan``, ``inf``: a value that should
    not be missing shows that it is)."""
    return NA if x is None else f"{x:.{digits}g}"


def interval(lo: Any, hi: Any, fmt: Callable[[Any], str] = significant) -> str:
    """An interval ``[lo, hi]``, each end by ``fmt``."""
    return f"[{fmt(lo)}, {fmt(hi)}]"


def with_interval(x: Any, ci: Any, digits: int = 3) -> str:
    """``x [lo, hi]`` with ``digits`` significant digits; ``x`` alone when the interval
    is missing or has a missing end; ``n/a`` when ``x`` is missing."""
    if missing(x):
        return NA
    s = significant(x, digits)
    if ci and all(not missing(v) for v in ci):
        s += " " + interval(ci[0], ci[1], lambda v: significant(v, digits))
    return s


def row(cells: Iterable[Any]) -> str:
    """One Markdown table row: ``| a | b |``."""
    return "| " + " | ".join(str(c) for c in cells) + " |"


def table_lines(
    header: Sequence[str], rows: Iterable[Iterable[Any]], align: str | None = None
) -> list[str]:
    """The lines of a Markdown table: the header, the alignment row and the rows.

    ``align``: one letter per column, ``l`` left (``---``) or ``r`` right (``---:``);
    default all left. An empty header cell (a matrix's corner) prints as ``| |``."""
    align = align or "l" * len(header)
    if len(align) != len(header):
        raise ValueError(f"align {align!r} has {len(align)} columns, the header {len(header)}")
    head = "|" + "|".join(f" {h} " if h else " " for h in header) + "|"
    rule = "|" + "".join("---:|" if a == "r" else "---|" for a in align)
    return [head, rule, *(row(r) for r in rows)]


def table(header: Sequence[str], rows: Iterable[Iterable[Any]], align: str | None = None) -> str:
    """A Markdown table as text, ending in a newline (:func:`table_lines`)."""
    return "\n".join(table_lines(header, rows, align)) + "\n"
