"""scripts/target_check.py combines capacity runs only where they are the same flights; a
run that flew an entrant on its first N seeds agrees with one that flew all of them."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _script():  # noqa: ANN202
    spec = importlib.util.spec_from_file_location(
        "target_check", ROOT / "scripts" / "target_check.py"
    )
    mod = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(mod)  # type: ignore[union-attr]
    return mod


def test_runs_on_fewer_seeds_merge_where_they_agree() -> None:
    tc = _script()
    full = {"seeds": [1, 2, 3], "capacity": [0.5, 0.6, 0.7], "censored": [False] * 3}
    part = {"seeds": [1, 2], "capacity": [0.5, 0.6], "censored": [False] * 2}
    assert tc._merge(part, full, "x") is full and tc._merge(full, part, "x") is full
    other = {"seeds": [1, 2], "capacity": [0.5, 0.61], "censored": [False] * 2}
    with pytest.raises(SystemExit, match="not the same flights"):
        tc._merge(other, full, "x")
    elsewhere = {"seeds": [1, 4], "capacity": [0.5, 0.6], "censored": [False] * 2}
    with pytest.raises(SystemExit, match="not the same flights"):
        tc._merge(full, elsewhere, "x")
