"""``python -m agents.capacity``: per-seed capacities and paired verdicts
(:mod:`agents.evaluation.capacity_benchmark`)."""

from agents.evaluation.capacity_benchmark import main

if __name__ == "__main__":
    raise SystemExit(main())
