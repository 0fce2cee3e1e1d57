"""Seeds of the evaluation CLIs: one definition, one set of flags, one check.

**Seeds are disjoint by purpose** (:data:`SEED_RANGES`): training below
:data:`TRAIN_SEED_LIMIT`, evaluation from :data:`EVAL_SEED0`, the Ray Tune validation from
:data:`VALIDATION_SEED0`, the benchmark suite's calibration from :data:`CALIBRATION_SEED0`
(:mod:`agents.evaluation.benchmark` re-exports these constants).

Every evaluation CLI (``python -m agents.evaluate``, ``agents.fragility``,
``agents.benchmark``, ``agents.reproduce_paper``) takes the same flags
(:func:`add_seed_arguments`):

* ``--seeds N``: the number of seeds (each CLI keeps its own default);
* ``--seed0 S``: the first seed, default :data:`EVAL_SEED0` (the evaluation range), so the
  seeds are ``S, S + 1, …, S + N − 1``;
* ``--seed-list S [S …]``: explicit seeds instead (distinct, non-negative; replaces
  ``--seeds`` and excludes ``--seed0``);
* ``--allow-training-seeds``: evaluate a learned agent on seeds of its training range
  anyway. Without it a learned agent (a registered learned controller such as ``ppo``, or a
  path to a saved model) on a seed below :data:`TRAIN_SEED_LIMIT` is refused with one error
  line naming the flag (:func:`check_evaluation_seeds`), and so is one on a seed its
  training log records as used in training (:func:`recorded_training_seeds`: ``train.py``
  keeps every seed of a run in the training range, an agent trained elsewhere may not).
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

TRAIN_SEED_LIMIT = 100_000
"""Training runs use seeds below this (``train.py`` keeps every seed of a run below it:
:mod:`agents.training.seeding`)."""
EVAL_SEED0 = 1_000_000
"""The evaluation seeds: EVAL_SEED0, EVAL_SEED0 + 1, … (the default of every evaluation CLI)."""
VALIDATION_SEED0 = 2_000_000
"""The Ray Tune validation seeds (:mod:`agents.training.tune`)."""
CALIBRATION_SEED0 = 3_000_000
"""The suite calibration's seeds (``hyperloop calibrate``)."""
SEED_RANGES: dict[str, tuple[int, int]] = {
    "training": (0, TRAIN_SEED_LIMIT - 1),
    "evaluation": (EVAL_SEED0, VALIDATION_SEED0 - 1),
    "validation": (VALIDATION_SEED0, CALIBRATION_SEED0 - 1),
    "calibration": (CALIBRATION_SEED0, 3_999_999),
}

CLI_NAMES: tuple[str, str, str, str] = (
    "--seeds",
    "--seed0",
    "--seed-list",
    "--allow-training-seeds",
)
"""How the CLIs call the count, the first seed, the explicit list and the permission."""
API_NAMES: tuple[str, str, str, str] = ("seeds", "seed0", "seeds", "allow_training_seeds=True")
"""The same as keyword arguments of the Python functions."""

__all__ = [
    "API_NAMES",
    "CALIBRATION_SEED0",
    "CLI_NAMES",
    "EVAL_SEED0",
    "SEED_RANGES",
    "TRAIN_SEED_LIMIT",
    "VALIDATION_SEED0",
    "add_seed_arguments",
    "check_evaluation_seeds",
    "is_learned",
    "recorded_training_seeds",
    "resolve",
    "seed_list",
    "seeds_from_args",
]


def _is_int(x: object) -> bool:
    return isinstance(x, int | np.integer) and not isinstance(x, bool)


def seed_list(
    n: int | None,
    seed0: int = EVAL_SEED0,
    explicit: Sequence[int] | None = None,
    *,
    min_n: int = 1,
    names: tuple[str, str, str, str] = CLI_NAMES,
) -> list[int]:
    """The seeds: ``explicit`` if given (non-empty, distinct, non-negative integers, at
    least ``min_n``), else ``seed0, seed0 + 1, …, seed0 + n − 1`` (``n >= min_n``,
    ``seed0 >= 0``). A ``ValueError`` names the flag (``names``: count, first seed, list)."""
    n_name, s0_name, list_name = names[:3]
    if explicit is not None:
        if isinstance(explicit, str | bytes) or not isinstance(explicit, Iterable):
            raise ValueError(f"{list_name} must be a list of seeds, got {explicit!r}")
        out = list(explicit)
        bad = [s for s in out if not _is_int(s) or s < 0]
        if bad:
            raise ValueError(f"{list_name} must hold non-negative integers, got {bad[:3]}")
        out = [int(s) for s in out]
        if not out:
            raise ValueError(f"{list_name} must not be empty")
        if len(set(out)) != len(out):
            dup = sorted({s for s in out if out.count(s) > 1})
            raise ValueError(f"{list_name} must hold distinct seeds; repeated: {dup[:3]}")
        if len(out) < min_n:
            raise ValueError(f"{list_name} needs at least {min_n} seeds, got {len(out)}")
        return out
    if not _is_int(n) or n < min_n:  # type: ignore[operator]
        raise ValueError(f"{n_name} must be an integer >= {min_n}, got {n!r}")
    if not _is_int(seed0) or seed0 < 0:
        raise ValueError(f"{s0_name} must be an integer >= 0, got {seed0!r}")
    return list(range(int(seed0), int(seed0) + int(n)))  # type: ignore[arg-type]


def resolve(
    seeds: int | Iterable[int],
    seed0: int = EVAL_SEED0,
    *,
    min_n: int = 1,
    names: tuple[str, str, str, str] = API_NAMES,
) -> list[int]:
    """The seeds of a Python API call: ``seeds`` is a count (from ``seed0``: the evaluation
    range by default) or an explicit list (:func:`seed_list`, errors naming ``names``)."""
    if seeds is None or _is_int(seeds) or isinstance(seeds, bool | float | str | bytes):
        return seed_list(seeds, seed0, min_n=min_n, names=names)  # type: ignore[arg-type]
    return seed_list(None, seed0, list(seeds), min_n=min_n, names=names)


def is_learned(controller: str) -> bool:
    """Whether ``controller`` is a learned agent: a learned registry name (``ppo``,
    ``ppo-guidance`` …; an entrant's ``+g`` suffix and a ``shielded:`` prefix ignored) or a
    path to a saved model (a ``.zip`` file, or a directory holding ``model.zip``)."""
    from agents.controllers.learned import MODEL_FILE
    from agents.controllers.registry import controller_spec, unshielded

    name = str(controller)
    base = unshielded(name[:-2] if name.endswith("+g") else name)
    spec = controller_spec(base)
    if spec is not None:
        return spec.kind == "learned"
    if base.endswith(".zip"):
        return True
    try:
        return (Path(base) / MODEL_FILE).is_file()
    except (OSError, ValueError):
        return False


def _training_log(controller: str) -> dict[str, Any] | None:
    """The training log (``training_log.json``) of a learned agent: of its shipped folder
    for a registry name, beside the model (or one folder up: a checkpoint's, the best
    model's) for a path; None if there is none or it is unreadable."""
    from agents.controllers.learned import SHIPPED_DIR
    from agents.controllers.registry import controller_spec, unshielded

    name = str(controller)
    base = unshielded(name[:-2] if name.endswith("+g") else name)
    spec = controller_spec(base)
    if spec is not None:
        folders = [SHIPPED_DIR / spec.shipped] if spec.shipped else []
    elif base.endswith(".zip"):
        folders = [Path(base).parent, Path(base).parent.parent]
    else:
        folders = [Path(base)]
    for folder in folders:
        try:
            log = json.loads((folder / "training_log.json").read_text())
        except (OSError, ValueError):
            continue
        return log if isinstance(log, dict) else None
    return None


def _span(value: Any) -> tuple[int, int] | None:
    if isinstance(value, list | tuple) and len(value) == 2 and all(_is_int(v) for v in value):
        return int(value[0]), int(value[1])
    return None


def _legacy_training_seeds(log: dict[str, Any]) -> list[tuple[int, int]]:
    """The seeds of a run whose log predates ``training_seeds``: its envs from ``seed``,
    its evaluation envs from ``seed + 10 000`` (mod 2**32, at most 4) and, if it was
    resumed, the envs re-seeded from a draw of ``SeedSequence([seed, steps])``."""
    seed, n_envs = log.get("seed"), log.get("n_envs", 1)
    if not _is_int(seed) or not _is_int(n_envs):
        return []
    seed, n_envs = int(seed), int(n_envs)
    ev = (seed + 10_000) % 2**32
    spans = [(seed, seed + n_envs - 1), (ev, ev + 3)]
    steps = (log.get("resumed_from") or {}).get("num_timesteps")
    if _is_int(steps):
        r = int(np.random.SeedSequence([seed, int(steps)]).generate_state(1)[0])
        spans.append((r, r + n_envs - 1))
    return spans


def recorded_training_seeds(controller: str) -> list[tuple[int, int]]:
    """The seeds (``[first, last]`` spans) a learned agent's training log records as used
    in training: its ``training_seeds`` (``train.py``: the training range, which holds
    every seed of the run), or those derived from ``seed`` and ``n_envs`` in an older log;
    empty without a log."""
    log = _training_log(controller)
    if log is None:
        return []
    record = log.get("training_seeds")
    if isinstance(record, dict) and _span(record.get("range")) is not None:
        spans = [record.get(k) for k in ("range", "envs", "eval_envs", "resume_envs")]
        return [s for s in map(_span, spans) if s is not None]
    return _legacy_training_seeds(log)


def _shown(seeds: Sequence[int]) -> str:
    return ", ".join(map(str, seeds[:3])) + (", …" if len(seeds) > 3 else "")


def check_evaluation_seeds(
    controllers: Iterable[str],
    seeds: Sequence[int],
    allow: bool = False,
    *,
    names: tuple[str, str, str, str] = CLI_NAMES,
) -> None:
    """Refuse a learned agent on seeds of the training range (below
    :data:`TRAIN_SEED_LIMIT`), or on seeds its training log records as training seeds
    (:func:`recorded_training_seeds`), unless ``allow``: ``ValueError`` with one line
    naming the permission flag (``names[3]``)."""
    if allow:
        return
    learned = [c for c in controllers if is_learned(c)]
    if not learned:
        return
    inside = sorted(int(s) for s in seeds if s < TRAIN_SEED_LIMIT)
    if inside:
        raise ValueError(
            f"seeds {_shown(inside)} lie in the training range (< {TRAIN_SEED_LIMIT}) of the "
            f"learned agent(s) {', '.join(learned)}: evaluate on the evaluation range "
            f"({names[1]} {EVAL_SEED0}, the default) or pass {names[3]}"
        )
    for c in learned:
        spans = recorded_training_seeds(c)
        used = sorted(int(s) for s in seeds if any(lo <= s <= hi for lo, hi in spans))
        if used:
            recorded = ", ".join(f"{lo} … {hi}" for lo, hi in spans)
            raise ValueError(
                f"seeds {_shown(used)} were training seeds of the learned agent {c} (its "
                f"training log records {recorded}): evaluate on seeds it was not trained "
                f"on ({names[1]} S, {names[2]} S …) or pass {names[3]}"
            )


def add_seed_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--seed0``, ``--seed-list`` (mutually exclusive) and ``--allow-training-seeds``
    (module docstring); the CLI keeps its own ``--seeds``."""
    g = parser.add_mutually_exclusive_group()
    g.add_argument(
        "--seed0",
        type=int,
        default=EVAL_SEED0,
        metavar="S",
        help=f"first seed: S, S+1, … (default {EVAL_SEED0}, the evaluation range; "
        f"training uses seeds < {TRAIN_SEED_LIMIT})",
    )
    g.add_argument(
        "--seed-list",
        type=int,
        nargs="+",
        default=None,
        metavar="S",
        help="explicit seeds (distinct, >= 0) instead of --seeds/--seed0",
    )
    parser.add_argument(
        "--allow-training-seeds",
        action="store_true",
        help=f"let a learned agent run on seeds < {TRAIN_SEED_LIMIT} "
        "(its training range; refused otherwise)",
    )


def seeds_from_args(
    args: argparse.Namespace, controllers: Iterable[str], *, min_n: int = 1
) -> list[int]:
    """The seeds the parsed ``args`` ask for (``--seeds``/``--seed0``/``--seed-list``),
    checked against ``controllers`` (:func:`check_evaluation_seeds`); ``ValueError`` naming
    the flag otherwise."""
    seeds = seed_list(args.seeds, args.seed0, args.seed_list, min_n=min_n)
    check_evaluation_seeds(controllers, seeds, args.allow_training_seeds)
    return seeds
