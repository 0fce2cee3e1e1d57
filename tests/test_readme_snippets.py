"""The README's snippets for RL libraries run as written (a snippet whose library is not
installed is skipped, naming it)."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BLOCK = re.compile(r"```python\n# client: ([\w.]+)[^\n]*\n(.*?)```", re.S)


def snippets() -> list[tuple[str, str]]:
    return BLOCK.findall((ROOT / "README.md").read_text())


def test_the_readme_has_a_snippet_per_client() -> None:
    assert [c for c, _ in snippets()] == ["stable_baselines3", "cleanrl", "ray.rllib", "torchrl"]


@pytest.mark.parametrize(("client", "code"), snippets(), ids=[c for c, _ in snippets()])
def test_snippet_runs(client: str, code: str) -> None:
    if client != "cleanrl":  # CleanRL is a set of scripts: its snippet is plain Gymnasium
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
    exec(compile(code, f"README.md ({client} snippet)", "exec"), {"__name__": "__snippet__"})
