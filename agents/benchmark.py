"""``python -m agents.benchmark``: the benchmark suite and headline
(:mod:`agents.evaluation.benchmark`)."""

from agents.evaluation.benchmark import main

if __name__ == "__main__":
    raise SystemExit(main())
