"""Copy a finished run into ``agents/shipped/<algo>/`` (``train.py --ship``).

Shipping changes the project's files: it is allowed only where the package is a source
checkout (run from the repository, or an editable install), never into an installed copy
(site-packages), where a run would silently replace the agent every user of that
environment gets (:func:`check_ship_destination`).
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from agents.installation import DISTRIBUTION

SHIP_FILES = ("model.zip", "vecnormalize.pkl", "training_log.json")
SHIP_REPORT_FILES = ("report.md", "summary.csv", "results.json")


class ShipError(ValueError):
    """``--ship`` cannot write where it would have to (module docstring)."""


def source_checkout() -> Path | None:
    """The root of the source checkout this ``agents`` package lives in (the directory
    whose ``pyproject.toml`` names this project), or None for an installed copy."""
    from agents.controllers.learned import SHIPPED_DIR

    root = SHIPPED_DIR.parents[1]
    try:
        meta = tomllib.loads((root / "pyproject.toml").read_text())
    except (OSError, ValueError):
        return None
    return root if meta.get("project", {}).get("name") == DISTRIBUTION else None


def check_ship_destination(name: str) -> Path:
    """Where ``--ship`` would write the agent ``name``; :class:`ShipError` if the package
    is not a source checkout (an installed wheel: the files belong to the installation)."""
    from agents.controllers.learned import SHIPPED_DIR, shipped_path

    if source_checkout() is None:
        raise ShipError(
            f"--ship writes the agent into the package's own agents/shipped/{name}/, and this "
            f"package is an installed copy ({SHIPPED_DIR.parent}), not a source checkout: "
            "keep the run directory (--out) and load it with make_controller(algo, "
            "path=...), or ship from a checkout (git clone, then pip install -e .)"
        )
    return shipped_path(name)


def _copy(src: Path, dst: Path) -> None:
    """Copy ``src`` to ``dst`` atomically: an interrupted copy leaves the old file."""
    import shutil

    from agents.evaluation.outputs import atomic_path

    with atomic_path(dst) as tmp:
        shutil.copy2(src, tmp)


def ship(out: Path, algo: str) -> Path:
    """Copy a finished run into ``agents/shipped/<algo>/`` (model, VecNormalize statistics,
    training log, the EvalCallback curve as CSV and the STS report tables, no figures);
    :class:`ShipError` unless the package is a source checkout. Every file is written
    atomically (an interrupted copy leaves the agent shipped before, file by file)."""
    import numpy as np

    from agents.evaluation.outputs import atomic_write_text

    dest = check_ship_destination(algo)
    dest.mkdir(parents=True, exist_ok=True)
    for name in SHIP_FILES:
        _copy(out / name, dest / name)
    curve = out / "eval" / "evaluations.npz"
    if curve.exists():
        d = np.load(curve)
        rows = ["timesteps,mean_reward,std_reward,mean_ep_length"]
        for t, r, n in zip(d["timesteps"], d["results"], d["ep_lengths"], strict=True):
            rows.append(f"{int(t)},{float(np.mean(r)):.2f},{float(np.std(r)):.2f},{np.mean(n):.1f}")
        atomic_write_text(dest / "eval_curve.csv", "\n".join(rows) + "\n")
    for name in SHIP_REPORT_FILES:
        src = out / "report" / name
        if src.exists():
            text = src.read_text()
            if name.endswith(".md"):  # the figures stay in the run directory
                text = "\n".join(ln for ln in text.splitlines() if not ln.startswith("![")) + "\n"
            atomic_write_text(dest / f"eval_{name}", text)
    return dest
