"""What an installed copy of the package needs: its data files.

* Data files (PID design, benchmark suite, training presets, shipped agents) are package
  data (``[tool.setuptools.package-data]`` in ``pyproject.toml``). A missing one is an
  error naming the file (:func:`require_data_file`), never a silent fallback to other
  values.
"""

from __future__ import annotations

from pathlib import Path

DISTRIBUTION = "hyperloop-suspension-gym"


def require_data_file(path: str | Path, what: str) -> Path:
    """``path`` if it is a file, else ``FileNotFoundError`` naming it (a data file of the
    package is missing: the installation is incomplete)."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(
            f"{what}: data file {p} is missing (it is package data of {DISTRIBUTION}; "
            "reinstall the package, or restore the file in a checkout)"
        )
    return p
