"""Training presets as data files (``agents/training/presets/*.json``; see its README).

``DEFAULTS`` is ``defaults.json``; every other file is a preset applied on top of it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from agents.controllers.registry import default_controllers

PRESET_DIR = Path(__file__).resolve().parent / "presets"
ALGOS: tuple[str, ...] = ("ppo", "sac")
VEC_MODES: tuple[str, ...] = ("native", "dummy", "subproc")
BASELINES: tuple[str, ...] = tuple(default_controllers())
"""The baselines a trained agent is compared with: the registry's default controllers."""


def _load(path: Path) -> dict[str, Any]:
    data = json.loads(path.read_text())
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a JSON object of options")
    return data


DEFAULTS: dict[str, Any] = _load(PRESET_DIR / "defaults.json")
PRESETS: dict[str, dict[str, Any]] = {
    p.stem: _load(p) for p in sorted(PRESET_DIR.glob("*.json")) if p.stem != "defaults"
}


def load_preset(name: str) -> dict[str, Any]:
    """A named preset or a JSON file of options (ValueError naming the problem)."""
    if name in PRESETS:
        return dict(PRESETS[name])
    path = Path(name)
    if path.suffix == ".json" and path.exists():
        try:
            data = _load(path)
        except ValueError as exc:
            raise ValueError(f"--preset {name}: not a JSON object of options ({exc})") from None
        unknown = sorted(set(data) - set(DEFAULTS))
        if unknown:
            raise ValueError(
                f"--preset {name}: unknown option(s) {unknown}; valid: {sorted(DEFAULTS)}"
            )
        return data
    raise ValueError(f"unknown preset {name!r}; valid presets: {list(PRESETS)} or a .json file")
