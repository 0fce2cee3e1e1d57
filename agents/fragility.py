"""``python -m agents.fragility``: the fragility CLI (:mod:`agents.evaluation.fragility`)."""

from agents.evaluation.fragility import main

if __name__ == "__main__":
    raise SystemExit(main())
