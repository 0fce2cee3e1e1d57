"""Evaluation: closed-loop rollouts, STS metrics, reports, figures, paper reproduction.

* :mod:`.rollout` — one episode of a controller in the environment;
* :mod:`.metrics` — the STS report and scalar metrics of a set of episodes;
* :mod:`.figures` — every figure (Agg backend); :mod:`.render` — the Markdown tables and
  number formatters of every report; :mod:`.report` — an evaluation's Markdown/JSON/CSV;
* :mod:`.vocabulary` — the one table of output names (key → unit, meaning) and the
  aliases of older names;
* :mod:`.evaluate` — controllers × scenarios × seeds (``python -m agents.evaluate``);
* :mod:`.reproduce_paper` — the paper's study (``python -m agents.reproduce_paper``);
* :mod:`.fragility` — contact probability against a disturbance's severity, lognormal
  fragility fits (``python -m agents.fragility``), with :mod:`.streaming` (accumulators
  for long runs), :mod:`.batch_rollout` (batched/single blocks of seeds),
  :mod:`.backends` (local processes or Ray) and :mod:`.fragility_fit` (MLE, intervals);
* :mod:`.seeds` — the seed ranges by purpose and the seed flags of every evaluation CLI
  (``--seed0``, default the evaluation range; ``--seed-list``; ``--allow-training-seeds``).
"""
