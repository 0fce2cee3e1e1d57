"""Print the README's headline table from an evaluation's ``results.json``.

    python -m agents.evaluate --controllers passive pid lqr ppo --scenarios paper \\
        --distance-km 10 --seeds 2 --out reports/headline
    python scripts/headline_table.py reports/headline/results.json

Per scenario and controller: P(unsteady) of each unit (FL, FR, RL, RR) with its 95 %
interval, RMS gap excursion, contacts, ISO 2631-1 weighted vertical acceleration and RMS
current deviation — all read from the file, nothing computed here but formatting.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from hyperloop_env.sts import format_probability

FLOOR = 1e-15
"""Fitted-law probabilities below this are shown as "< 1e-15": they are extrapolations of
the fitted tail ten or more standard deviations out, which no simulated distance resolves
(the exact values are in results.json and the per-unit tables of report.md)."""


def _fmt_p(p: float) -> str:
    return f"< {FLOOR:.0e}" if p < FLOOR else format_probability(p)


def _p(unit: dict) -> str:
    p = unit["p_unsteady"]
    if p is None:
        return "n/a"
    lo, hi = unit["p_unsteady_ci"]
    if p >= 1.0:
        return "1"
    if hi < FLOOR:
        return f"< {FLOOR:.0e}"
    return f"{_fmt_p(p)} [{_fmt_p(lo)}, {_fmt_p(hi)}]"


def _f(x: float | None, fmt: str) -> str:
    return "–" if x is None else format(x, fmt)


def table(results: dict) -> str:
    rows = [
        "| scenario | controller | P(unsteady) FL | FR | RL | RR | RMS gap [mm] | contacts "
        "| W_k [m/s²] | RMS ΔI [A] |",
        "|---|---|---|---|---|---|---:|---|---:|---:|",
    ]
    res = sorted(
        results["results"],
        key=lambda r: (
            results["settings"]["scenarios"].index(r["metrics"]["scenario"]),
            results["settings"]["controllers"].index(r["metrics"]["controller"]),
        ),
    )
    for r in res:
        m = r["metrics"]
        units = {u["name"]: u for u in r["sts"]["units"]}
        contacts = f"{m['n_contact_episodes']}/{m['n_episodes']}"
        if m["n_contact_episodes"]:
            contacts += f" ({m['contact_kind']} at {m['time_to_first_contact_s']:.2f} s)"
        rows.append(
            f"| {m['scenario']} | {m['controller']} | "
            + " | ".join(_p(units[n]) for n in ("FL", "FR", "RL", "RR"))
            + f" | {_f(m['rms_gap_mm'], '.3f')} | {contacts} | {_f(m['a_wz_m_s2'], '.2f')} | "
            f"{_f(m['rms_current_dev_A'], '.1f')} |"
        )
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description="README headline table from results.json")
    ap.add_argument("results", type=Path, help="results.json written by agents.evaluate")
    args = ap.parse_args(argv)
    if not args.results.is_file():
        ap.error(f"no such file: {args.results}")
    data = json.loads(args.results.read_text())
    print(f"Command: `{data['settings'].get('command', '?')}`\n")
    print(table(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
