"""``evaluate(..., workers=W)``: the cases on worker processes give the same report, numbers
and figures as in this process."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from agents.evaluation import evaluate as ev

SHORT = {"distance_km": 0.3, "seeds": 2, "settle_s": 0.1, "n_boot": 10, "progress": False}


def _numbers(out: Path) -> dict:
    """results.json without the wall times (the only fields that may differ)."""
    data = json.loads((out / "results.json").read_text())
    data["settings"].pop("wall_s")
    for r in data["results"]:
        r["metrics"].pop("wall_s", None)
    return data


def test_two_workers_give_the_same_results_and_figures(tmp_path: Path) -> None:
    outs = {}
    for w in (1, 2):
        outs[w] = tmp_path / f"w{w}"
        ev.evaluate(
            ["passive", "lqr"], ["paper-1000-straight", "paper-2000-curved"],
            out_dir=outs[w], workers=w, **SHORT,
        )  # fmt: skip
    one, two = _numbers(outs[1]), _numbers(outs[2])
    assert [r["metrics"]["controller"] for r in two["results"]] == ["passive"] * 2 + ["lqr"] * 2
    assert one == two
    figs = sorted(p.name for p in (outs[1] / "figures").iterdir())
    assert len(figs) == 4 * 3 + 1
    assert figs == sorted(p.name for p in (outs[2] / "figures").iterdir())
    for name in figs:
        assert (outs[1] / "figures" / name).read_bytes() == (
            outs[2] / "figures" / name
        ).read_bytes()


@pytest.mark.parametrize("bad", [0, -1, True, 1.5, "2"])
def test_workers_must_be_a_positive_int(bad: object, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="workers"):
        ev.evaluate(
            ["passive"], ["paper-1000-straight"], out_dir=tmp_path / "o", workers=bad, **SHORT
        )
    assert not (tmp_path / "o").exists()
