"""Comparisons of controllers from published results (``hyperloop compare``).

* :mod:`~agents.evaluation.comparisons.target` — is a learned agent resolved above every
  classical controller, with a ride no rougher? (from capacity runs and a comfort file)
* :mod:`~agents.evaluation.comparisons.comfort` — ride comfort (ISO 2631-1 W_k) of
  controllers on common seeds, each paired with a reference.
* :mod:`~agents.evaluation.comparisons.cost` — what each entrant of a headline run cost.

Each computes a JSON-ready document and renders its Markdown separately; a file it cannot
use is a :class:`ComparisonInputError` naming the file and the field.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any


class ComparisonInputError(ValueError):
    """An input file a comparison cannot use (the message names the file and the field)."""


def read_json(path: str | Path, what: str) -> Any:
    """The JSON content of ``path`` (``what`` it should be, for the message);
    :class:`ComparisonInputError` if it is missing or not JSON."""
    try:
        return json.loads(Path(path).read_text())
    except FileNotFoundError:
        raise ComparisonInputError(f"{path}: no such file (expected {what})") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ComparisonInputError(f"{path}: not readable as {what} ({exc})") from None


def field(doc: Any, path: str | Path, *keys: str) -> Any:
    """``doc[keys[0]][keys[1]]…``; :class:`ComparisonInputError` naming ``path`` and the
    field (``a.b.c``) where it is missing or not an object."""
    cur = doc
    for k, key in enumerate(keys):
        if not isinstance(cur, dict) or key not in cur:
            raise ComparisonInputError(f"{path}: no field {'.'.join(keys[: k + 1])}")
        cur = cur[key]
    return cur
