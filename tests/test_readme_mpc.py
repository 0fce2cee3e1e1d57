"""The MPC-vs-LQR tables of the comparison page (docs/comparison.md) are the ones
docs/benchmark/mpc-vs-lqr/headline.json and docs/benchmark/mpc-preview-vs-lqr/
headline.json give (written by the commands the page shows, ``hyperloop capacity
--entrants lqr mpc ...`` and ``--entrants lqr mpc-preview ...``)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RUNS = {
    "mpc": ROOT / "docs" / "benchmark" / "mpc-vs-lqr" / "headline.json",
    "mpc-preview": ROOT / "docs" / "benchmark" / "mpc-preview-vs-lqr" / "headline.json",
}
LABEL = {
    "1000 straight": "paper-1000-straight",
    "1000 R200": "paper-1000-curved",
    "2000 straight": "paper-2000-straight",
    "2000 R200": "paper-2000-curved",
}


def _verdict(word: str, ctrl: str) -> str:
    """The page's wording → the JSON's verdict of A = lqr vs B = ``ctrl``."""
    return {
        "equivalent": "equivalent",
        f"`{ctrl}` below": "A above B",
        f"`{ctrl}` above": "B above A",
        "undecided": "undecided",
    }[word]


def _g3(x: float) -> str:
    return f"{x:.3g}"


def _theta(c: dict) -> str:
    lo, hi = c["theta_ci"]
    return f"{_g3(c['theta'])} [{_g3(lo)}, {_g3(hi)}]"


def _table(section: str, ctrl: str) -> list[str]:
    """The rows of the table whose header names θ roughness of ``ctrl``."""
    head = f"| condition | θ roughness `lqr` | θ roughness `{ctrl}` |"
    assert section.count(head) == 1, head
    rows = []
    for line in section.split(head, 1)[1].split("\n")[2:]:
        if not line.startswith("|"):
            break
        rows.append(line)
    return rows


@pytest.mark.parametrize("ctrl", sorted(RUNS))
def test_mpc_table_matches_the_json(ctrl: str) -> None:
    doc = json.loads(RUNS[ctrl].read_text())
    h = doc["headline"]
    caps = {(c["condition"], c["entrant"]): c for c in h["capacities"]}
    verdicts = {v["condition"]: v for v in h["verdicts"]}
    section = (ROOT / "docs" / "comparison.md").read_text()
    rows = _table(section, ctrl)
    assert len(rows) == 4
    for row in rows:
        assert re.match(r"^\| (1000|2000) ", row)
        label, th_lqr, th_c, ratio, verdict = [c.strip() for c in row.strip("|").split("|")]
        cond = LABEL[label]
        assert th_lqr == _theta(caps[(cond, "lqr")])
        assert th_c == _theta(caps[(cond, ctrl)])
        v = verdicts[cond]
        assert (v["a"], v["b"]) == ("lqr", ctrl)
        assert ratio == _g3(1.0 / v["ratio"])  # ctrl / lqr
        assert _verdict(verdict.split(" (")[0], ctrl) == v["verdict"]
