"""What an installed copy of the package needs: its data files and the optional extras.

* Data files (PID design, benchmark suite, training presets, shipped agents) are package
  data (``[tool.setuptools.package-data]`` in ``pyproject.toml``). A missing one is an
  error naming the file (:func:`require_data_file`), never a silent fallback to other
  values.
* The optional dependencies are the extras ``train`` (Stable-Baselines3, torch), ``ray``
  and ``tune``; :func:`require_extra` raises :class:`MissingExtraError` with the
  ``pip install "hyperloop-suspension-gym[<extra>]"`` line to run.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

DISTRIBUTION = "hyperloop-suspension-gym"

EXTRAS: dict[str, tuple[str, ...]] = {
    "train": ("stable_baselines3", "torch"),
    "ray": ("ray",),
    "tune": ("ray",),
}
"""Top-level modules each extra provides (checked without importing them)."""


class MissingExtraError(ImportError):
    """An optional dependency of an extra is not installed (the message names the extra)."""


def install_command(extra: str) -> str:
    """``pip install "hyperloop-suspension-gym[<extra>]"``."""
    if extra not in EXTRAS:
        raise ValueError(f"unknown extra {extra!r}; known: {sorted(EXTRAS)}")
    return f'pip install "{DISTRIBUTION}[{extra}]"'


def missing_modules(extra: str) -> list[str]:
    """The modules of ``extra`` that cannot be found (empty if it is installed)."""
    if extra not in EXTRAS:
        raise ValueError(f"unknown extra {extra!r}; known: {sorted(EXTRAS)}")
    out = []
    for mod in EXTRAS[extra]:
        try:
            found = importlib.util.find_spec(mod) is not None
        except (ImportError, ValueError):
            found = False
        if not found:
            out.append(mod)
    return out


def missing_extra_message(extra: str, what: str, missing: list[str] | None = None) -> str:
    """One line: ``<what> needs <modules> (the [<extra>] extra): pip install "...[<extra>]"``."""
    miss = missing if missing is not None else list(EXTRAS[extra])
    return (
        f"{what} needs {', '.join(miss)}, not installed (the [{extra}] extra): "
        f"{install_command(extra)}"
    )


def require_extra(extra: str, what: str) -> None:
    """Raise :class:`MissingExtraError` (one line naming the extra and the install
    command) if a module of ``extra`` is missing; ``what`` names the feature."""
    miss = missing_modules(extra)
    if miss:
        raise MissingExtraError(missing_extra_message(extra, what, miss), name=miss[0])


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
