"""Every Python snippet of the documentation site (the ```python blocks of docs/*.md) runs
as written, each in a fresh namespace.

A snippet whose first line is ``# client: <module>`` needs that library: it is skipped,
naming it, when the library is not installed (CleanRL is a set of scripts: its snippet is
plain Gymnasium and always runs). A snippet whose first line is ``# slow`` is marked slow.
"""

from __future__ import annotations

import importlib
import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)
CLIENT = re.compile(r"# client: ([\w.]+)")


def snippets() -> list[tuple[str, str]]:
    """(id, code) of every Python block of the pages, in page and block order."""
    out = []
    for page in sorted(DOCS.glob("*.md")):
        for i, code in enumerate(BLOCK.findall(page.read_text()), 1):
            out.append((f"{page.stem}-{i}", code))
    return out


def _params() -> list:
    params = []
    for name, code in snippets():
        marks = [pytest.mark.slow] if code.startswith("# slow") else []
        params.append(pytest.param(code, id=name, marks=marks))
    return params


def test_the_pages_have_snippets_and_one_per_rl_client() -> None:
    clients = [
        m.group(1)
        for name, code in snippets()
        if name.startswith("getting-started-") and (m := CLIENT.match(code))
    ]
    assert clients == ["stable_baselines3", "cleanrl", "ray.rllib", "torchrl"]
    assert len(snippets()) >= 8


def _require(client: str) -> None:
    if client == "cleanrl":  # CleanRL is a set of scripts: its snippet is plain Gymnasium
        return
    try:
        found = importlib.util.find_spec(client) is not None
    except ModuleNotFoundError:
        found = False
    if not found:
        pytest.skip(f"{client} is not installed")
    try:  # e.g. ray's wheel carries ray.rllib without its dependencies (ray[rllib])
        importlib.import_module(client)
    except ImportError as exc:
        pytest.skip(f"{client} is installed without its dependencies: {exc}")


@pytest.mark.parametrize("code", _params())
def test_snippet_runs(code: str, request: pytest.FixtureRequest) -> None:
    if m := CLIENT.match(code):
        _require(m.group(1))
    name = request.node.callspec.id
    exec(compile(code, f"docs ({name})", "exec"), {"__name__": "__snippet__"})
