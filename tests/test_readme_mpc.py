"""The README's MPC-vs-LQR table ("Controllers that set the bar: where they stand") is the
one docs/benchmark/mpc-vs-lqr/headline.json gives (written by the command the README
shows, ``python -m agents.capacity --entrants lqr mpc ...``)."""

from __future__ import annotations

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "benchmark" / "mpc-vs-lqr" / "headline.json"
LABEL = {
    "1000 straight": "paper-1000-straight",
    "1000 R200": "paper-1000-curved",
    "2000 straight": "paper-2000-straight",
    "2000 R200": "paper-2000-curved",
}
VERDICT = {"equivalent": "equivalent", "`mpc` below": "A above B", "undecided": "undecided"}
"""README wording → the JSON's verdict of A = lqr vs B = mpc (``mpc`` below: A above B)."""


def _g3(x: float) -> str:
    return f"{x:.3g}"


def _theta(c: dict) -> str:
    lo, hi = c["theta_ci"]
    return f"{_g3(c['theta'])} [{_g3(lo)}, {_g3(hi)}]"


def test_readme_mpc_table_matches_the_json() -> None:
    doc = json.loads(DOC.read_text())
    h = doc["headline"]
    caps = {(c["condition"], c["entrant"]): c for c in h["capacities"]}
    verdicts = {v["condition"]: v for v in h["verdicts"]}
    text = (ROOT / "README.md").read_text()
    section = text.split("## Controllers that set the bar: where they stand", 1)[1]
    rows = [r for r in section.split("\n") if re.match(r"^\| (1000|2000) ", r)]
    assert len(rows) == 4
    for row in rows:
        label, th_lqr, th_mpc, ratio, verdict = [c.strip() for c in row.strip("|").split("|")]
        cond = LABEL[label]
        assert th_lqr == _theta(caps[(cond, "lqr")])
        assert th_mpc == _theta(caps[(cond, "mpc")])
        v = verdicts[cond]
        assert (v["a"], v["b"]) == ("lqr", "mpc")
        assert ratio == _g3(1.0 / v["ratio"])  # mpc / lqr
        word = verdict.split(" (")[0]
        assert VERDICT[word] == v["verdict"]
