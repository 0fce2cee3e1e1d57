"""``python -m agents.evaluate``: the evaluation CLI (:mod:`agents.evaluation.evaluate`)."""

from agents.evaluation.evaluate import main

if __name__ == "__main__":
    raise SystemExit(main())
