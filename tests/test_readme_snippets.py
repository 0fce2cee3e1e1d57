"""The README's Python snippets run as written (the snippets of the documentation site,
RL libraries included, run in ``tests/test_docs_snippets.py``)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BLOCK = re.compile(r"```python\n(.*?)```", re.S)


def snippets() -> list[str]:
    return BLOCK.findall((ROOT / "README.md").read_text())


def test_the_readme_has_the_environment_example() -> None:
    (code,) = snippets()
    assert 'gym.make("HyperloopSuspension-v0"' in code and "gym.make_vec(" in code


@pytest.mark.parametrize("code", snippets())
def test_snippet_runs(code: str) -> None:
    exec(compile(code, "README.md", "exec"), {"__name__": "__snippet__"})
