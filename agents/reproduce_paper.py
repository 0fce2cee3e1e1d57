"""``python -m agents.reproduce_paper``: the paper reproduction
(:mod:`agents.evaluation.reproduce_paper`)."""

from agents.evaluation.reproduce_paper import main

if __name__ == "__main__":
    raise SystemExit(main())
