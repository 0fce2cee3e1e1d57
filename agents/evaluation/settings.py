"""What every study shares, declared once: :class:`Settings`.

Each field carries its flag, its documentation (with the unit), its default and its check
in the field's metadata; :mod:`agents.cli.options` generates every subcommand's flags from
these declarations, so a flag has one name, one default and one help text wherever it
appears (``tests/agents/test_cli.py`` checks it). A study that needs a different default
for one of the per-study fields (:data:`PER_STUDY`: the number of seeds, the distance and
the output folder) states it in its command module.

``Settings(...)`` checks every value (``ValueError`` naming the flag); numbers given as
NumPy scalars are numbers.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from agents.evaluation.seeds import EVAL_SEED0, TRAIN_SEED_LIMIT
from hyperloop_env.json_values import python_number

BACKENDS = ("local", "ray")
MAGNETS = ("repelling", "attracting")
ACTUATORS = ("levitation", "levitation+guidance")
PER_STUDY = ("seeds", "distance_km", "out")
"""Fields whose default each study sets (its own number of seeds, distance and folder)."""


def default_workers() -> int:
    """One worker per CPU of this machine (results never depend on the number)."""
    return max(1, os.cpu_count() or 1)


def _int(lo: int) -> Any:
    def check(v: Any) -> str | None:
        if isinstance(v, bool) or not isinstance(v, int) or v < lo:
            return f"must be an integer >= {lo}"
        return None

    return check


def _number(lo: float, strict: bool) -> Any:
    def check(v: Any) -> str | None:
        ok = not isinstance(v, bool) and isinstance(v, int | float) and math.isfinite(v)
        if not ok or (v <= lo if strict else v < lo):
            return f"must be a finite number {'>' if strict else '>='} {lo:g}"
        return None

    return check


def _choice(options: tuple[str, ...]) -> Any:
    def check(v: Any) -> str | None:
        return None if v in options else f"must be one of {', '.join(options)}"

    return check


def _seed_list(v: Any) -> str | None:
    if v is None:
        return None
    if not isinstance(v, tuple | list) or not v or _int(0)(v[0]) is not None:
        return "must be a non-empty list of integers >= 0"
    if any(_int(0)(s) for s in v):
        return "must hold integers >= 0"
    return None  # distinct and enough of them: agents.evaluation.seeds.seed_list


def _opt(flag: str, help: str, default: Any, check: Any = None, **argparse: Any) -> Any:
    """A settings field: its default and, in the metadata, the flag, the help (with the
    unit), the check and extra ``argparse`` keywords (``choices``, ``metavar``, ``nargs``,
    ``aliases``, ``negated``: a ``--no-x`` flag that sets the field to False)."""
    meta = {"flag": flag, "help": help, "check": check, "argparse": argparse}
    if callable(default):
        return field(default_factory=default, metadata=meta)
    return field(default=default, metadata=meta)


@dataclass(frozen=True)
class Settings:
    """What the studies share (module docstring). Units are in the field's help."""

    seeds: int | None = _opt(
        "--seeds",
        "number of seeds (runs per controller and condition, or per level): --seed0, "
        "--seed0 + 1, …",
        None,
        lambda v: None if v is None else _int(1)(v),
        type=int,
    )
    seed0: int = _opt(
        "--seed0",
        f"first seed: S, S+1, … (the evaluation range starts at {EVAL_SEED0}; "
        f"training uses seeds < {TRAIN_SEED_LIMIT})",
        EVAL_SEED0,
        _int(0),
        type=int,
        metavar="S",
        group="seeds",
    )
    seed_list: tuple[int, ...] | None = _opt(
        "--seed-list",
        "explicit seeds (distinct, >= 0) instead of --seeds/--seed0",
        None,
        _seed_list,
        metavar="S",
        nargs="+",
        type=int,
        group="seeds",
    )
    allow_training_seeds: bool = _opt(
        "--allow-training-seeds",
        f"let a learned agent run on seeds < {TRAIN_SEED_LIMIT} (its training range; "
        "refused otherwise)",
        False,
    )
    distance_km: float | None = _opt(
        "--distance-km",
        "distance per run [km]",
        None,
        lambda v: None if v is None else _number(0.0, True)(v),
        type=float,
    )
    magnet: str = _opt(
        "--magnet",
        "magnet arrangement of the vehicle: repelling | attracting",
        "repelling",
        _choice(MAGNETS),
        choices=MAGNETS,
    )
    actuators: str = _opt(
        "--actuators",
        "actuated currents: levitation (the four levitation coils) or levitation+guidance "
        "(the guidance pairs too)",
        "levitation",
        _choice(ACTUATORS),
        choices=ACTUATORS,
    )
    settle_s: float = _opt(
        "--settle-s",
        "settling time discarded at the start of every run [s]",
        1.0,
        _number(0.0, False),
        type=float,
    )
    n_boot: int = _opt(
        "--n-boot",
        "bootstrap replicates of the STS intervals (0: none)",
        200,
        _int(0),
        type=int,
    )
    n_boot_fit: int = _opt(
        "--n-boot-fit",
        "bootstrap replicates of the fragility or capacity fit's intervals",
        1000,
        _int(1),
        type=int,
        aliases=("--n-boot-fragility",),
    )
    workers: int = _opt(
        "--workers",
        "local worker processes (default: one per CPU); results do not depend on it",
        default_workers,
        _int(1),
        type=int,
    )
    backend: str = _opt(
        "--backend",
        "where the runs fly: local (this machine) or ray (a Ray cluster; the ray extra)",
        "local",
        _choice(BACKENDS),
        choices=BACKENDS,
    )
    address: str | None = _opt(
        "--address",
        "Ray cluster address ('auto', 'ray://host:10001'; with --backend ray; none: a local Ray)",
        None,
        lambda v: None if v is None or isinstance(v, str) else "must be an address",
    )
    out: Path | None = _opt(
        "--out",
        "output folder (new or empty, unless --overwrite or --resume)",
        None,
        None,
        type=Path,
    )
    overwrite: bool = _opt(
        "--overwrite", "replace a previous report in --out (its files are removed first)", False
    )
    resume: bool = _opt(
        "--resume",
        "continue an interrupted run in --out (its finished parts are kept, not rerun)",
        False,
    )
    progress: bool = _opt(
        "--no-progress", "no progress bar", True, negated=True, aliases=("--quiet",)
    )
    figures: bool = _opt("--no-figures", "skip the PNG figures", True, negated=True)

    def __post_init__(self) -> None:
        for f in fields(self):
            v = python_number(getattr(self, f.name))
            if isinstance(v, list):
                v = tuple(python_number(x) for x in v)
            object.__setattr__(self, f.name, v)
            check_setting(f.name, v)
        if self.address is not None and self.backend != "ray":
            raise ValueError("--address needs --backend ray")
        if self.resume and self.overwrite:
            raise ValueError("--resume continues a run, --overwrite deletes it: pass one")


def check_setting(name: str, value: Any, required: bool = False) -> None:
    """``ValueError`` naming the flag unless ``value`` is a valid value of the setting
    ``name`` (its declared check; ``required``: None is refused too) — for a study's spec
    that takes a shared setting without a :class:`Settings`."""
    f = settings_field(name)
    check = f.metadata["check"]
    v = python_number(value)
    problem = "must be given" if required and v is None else None
    problem = problem or (check(v) if check is not None else None)
    if problem:
        raise ValueError(f"{f.metadata['flag']} {problem}, got {value!r}")


def settings_field(name: str) -> Any:
    """The declaration (``dataclasses.Field``) of the setting ``name``."""
    for f in fields(Settings):
        if f.name == name:
            return f
    raise KeyError(f"no setting {name!r}; settings: {[f.name for f in fields(Settings)]}")
