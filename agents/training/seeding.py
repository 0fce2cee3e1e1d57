"""The seeds a training run uses: all of them inside the training range.

Seeds are disjoint by purpose (:data:`agents.evaluation.seeds.SEED_RANGES`): a training run
uses seeds in ``[0, TRAIN_SEED_LIMIT − 1]`` only, so an evaluation on the evaluation seeds
(from :data:`~agents.evaluation.seeds.EVAL_SEED0`) never replays an episode the agent was
trained on. With ``--seed S``, ``--n-envs N`` and ``E`` evaluation environments
(:func:`eval_env_count`):

* the training envs use ``S … S + N − 1`` (SB3 seeds env ``i`` with ``S + i``);
* the evaluation envs of the ``EvalCallback`` use ``S + EVAL_SEED_OFFSET … + E − 1``;
* a resumed run re-seeds its training envs (fresh episodes for the new segment) with
  :func:`resume_seed`: derived from ``S`` and the step count, inside the range.

:func:`seed_problem` tells why a ``--seed`` does not fit; :func:`seed_record` is what the
training log records (``training_seeds``), which
:func:`agents.evaluation.seeds.check_evaluation_seeds` reads back.
"""

from __future__ import annotations

import numpy as np

from agents.evaluation.seeds import EVAL_SEED0, TRAIN_SEED_LIMIT

EVAL_SEED_OFFSET = 10_000
"""The evaluation environments of a run are seeded from ``seed + EVAL_SEED_OFFSET``."""
EVAL_ENVS_MAX = 4
"""At most this many evaluation environments (``min(eval_episodes, EVAL_ENVS_MAX)``)."""


def eval_env_count(eval_episodes: int) -> int:
    """The number of evaluation environments of a run."""
    return min(int(eval_episodes), EVAL_ENVS_MAX)


def eval_env_seed(seed: int) -> int:
    """The first seed of a run's evaluation environments."""
    return int(seed) + EVAL_SEED_OFFSET


def largest_seed(n_envs: int, eval_envs: int) -> int:
    """The largest ``--seed`` whose derived seeds all stay below ``TRAIN_SEED_LIMIT``
    (negative: none does)."""
    return TRAIN_SEED_LIMIT - max(int(n_envs), EVAL_SEED_OFFSET + int(eval_envs))


def seed_problem(seed: int, n_envs: int, eval_envs: int) -> str | None:
    """None if every seed a run with ``--seed seed`` derives lies in the training range,
    else a message naming ``--seed`` and the range."""
    top = largest_seed(n_envs, eval_envs)
    if 0 <= seed <= top:
        return None
    lo, hi = 0, TRAIN_SEED_LIMIT - 1
    fits = f"--seed must be in [0, {top}]" if top >= 0 else "no --seed fits"
    return (
        f"--seed {seed}: a run trains on seeds of the training range [{lo}, {hi}] only (the "
        f"evaluation seeds start at {EVAL_SEED0}); its {n_envs} training envs use seed … "
        f"seed + {n_envs - 1} and its {eval_envs} evaluation envs seed + {EVAL_SEED_OFFSET} "
        f"… seed + {EVAL_SEED_OFFSET + eval_envs - 1}, so {fits} (with --n-envs {n_envs})"
    )


def resume_seed(seed: int, steps: int, n_envs: int) -> int:
    """The seed a run resumed at ``steps`` gives its training envs: derived from ``seed``
    and ``steps`` (a different stream of episodes per segment, the same on every rerun),
    with all ``n_envs`` env seeds inside the training range."""
    starts = TRAIN_SEED_LIMIT - int(n_envs) + 1
    if starts < 1:
        raise ValueError(f"{n_envs} envs do not fit into the training seeds")
    mixed = np.random.SeedSequence([int(seed), int(steps)]).generate_state(1, np.uint64)[0]
    return int(mixed % np.uint64(starts))


def seed_record(
    seed: int, n_envs: int, eval_envs: int, resumed_at: int | None = None
) -> dict[str, list[int] | None]:
    """The seeds a run (segment) used, as the training log records them
    (``training_seeds``): ``range``, the training range every seed of the run lies in;
    ``envs``, ``eval_envs`` and ``resume_envs`` (None unless resumed) as ``[first, last]``."""
    ev = eval_env_seed(seed)
    resume = None
    if resumed_at is not None:
        r = resume_seed(seed, resumed_at, n_envs)
        resume = [r, r + n_envs - 1]
    return {
        "range": [0, TRAIN_SEED_LIMIT - 1],
        "envs": [seed, seed + n_envs - 1],
        "eval_envs": [ev, ev + eval_envs - 1],
        "resume_envs": resume,
    }
