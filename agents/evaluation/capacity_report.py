"""The capacity benchmark's report, rendered from its ``headline.json`` content alone:
the Markdown report, the CSV, the README's headline block, the verdict matrices and the
cost table (:mod:`agents.evaluation.capacity_benchmark` computes; this module only
renders)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from agents.evaluation.render import NA, interval, significant, table
from agents.evaluation.vocabulary import canonical


def capacity_text(r: dict[str, Any]) -> str:
    if r["theta"] is None:
        med = r.get("median_empirical")
        if r["status"] == "all_censored":
            return "> upper bound"
        return f"{significant(med)} (empirical)" if med is not None else NA
    cens = f" ({r['n_censored']} cens.)" if r["n_censored"] else ""
    ci = r["theta_ci"]
    band = f" {interval(ci[0], ci[1])}" if ci and ci[0] is not None else ""
    return f"{significant(r['theta'])}{band}{cens}"


_SHORT = {"A above B": ">", "B above A": "<", "equivalent": "=", "undecided": "?"}


_FLIP = {">": "<", "<": ">"}


def _oriented(
    cell: dict[tuple[str, str], dict[str, Any]], a: str, b: str
) -> tuple[str, float | None]:
    """(symbol, ratio of median capacities) of row ``a`` against column ``b``, from the
    pair's verdict stored as (a, b) or as (b, a)."""
    v = cell.get((a, b))
    if v is not None:
        return _SHORT[v["verdict"]], v["ratio"]
    v = cell[(b, a)]
    sym = _SHORT[v["verdict"]]
    return _FLIP.get(sym, sym), (None if v["ratio"] is None else 1.0 / v["ratio"])


def _matrix(labels: Sequence[str], corner: str, text: Any) -> str:
    """A row-vs-column Markdown matrix of the entrants; ``text(a, b)`` fills a cell."""
    rows = ((a, *("—" if a == b else text(a, b) for b in labels)) for a in labels)
    return table((corner, *labels), rows)


def _cells(h: dict[str, Any], cond: str, fam: str) -> dict[tuple[str, str], dict[str, Any]]:
    return {
        (v["a"], v["b"]): v for v in h["verdicts"] if v["condition"] == cond and v["family"] == fam
    }


def verdict_table(h: dict[str, Any], cond: str, fam: str, labels: Sequence[str]) -> str:
    """Row entrant vs column entrant: ">" row above column, "<" below, "=" equivalent,
    "?" undecided (with the ratio of median capacities)."""
    cell = _cells(h, cond, fam)

    def text(a: str, b: str) -> str:
        sym, ratio = _oriented(cell, a, b)
        return f"{sym} {significant(ratio)}"

    return _matrix(labels, "", text)


def capacity_table(
    h: dict[str, Any], families: Sequence[str], labels: Sequence[str], conditions: Sequence[str]
) -> str:
    by = {(r["condition"], r["family"], r["entrant"]): r for r in h["capacities"]}
    ref = families[0]
    first = by[(conditions[0], ref, labels[0])]
    st0 = first.get("sts_at_levels") or []
    old = None if st0 else first.get("sts_at_start")  # a headline.json from before the levels
    head = ["condition", "entrant", *(f"θ {f}" for f in families)]
    if st0:
        at = " / ".join(f"{x['severity']:g}" for x in st0)
        head += [f"P(unsteady) gap @ {ref} {at}", f"P(unsteady) guidance @ {ref} {at}"]
    elif old:
        head.append(f"P(unst.) gap / guidance @ {ref} {old['severity']:g}")
    rows = []
    for cond in conditions:
        for lab in labels:
            cells = [capacity_text(by[(cond, f, lab)]) for f in families]
            if st0:
                sts = [canonical(x) for x in by[(cond, ref, lab)]["sts_at_levels"]]
                cells.append(" / ".join(significant(x["p_unsteady"]) for x in sts))
                cells.append(" / ".join(significant(x["p_unsteady_guidance"]) for x in sts))
            elif old:
                st = canonical(by[(cond, ref, lab)]["sts_at_start"])
                cells.append(
                    f"{significant(st['p_unsteady'])} / {significant(st['p_unsteady_guidance'])}"
                )
            rows.append((_cond(cond), lab, *cells))
    return table(head, rows)


def compact_verdicts(
    h: dict[str, Any], cond: str, families: Sequence[str], labels: Sequence[str]
) -> str:
    """One matrix per condition: each cell holds one symbol per family (row vs column)."""
    cells = {f: _cells(h, cond, f) for f in families}
    return _matrix(
        labels,
        "row vs column",
        lambda a, b: " ".join(_oriented(cells[f], a, b)[0] for f in families),
    )


TARGET_DECIDED = 0.8
"""The issue's target: at least 80 % of the pairs decided (above, below or equivalent)."""


def readme_block(doc: dict[str, Any]) -> str:
    """The README's headline block, from headline.json alone."""
    st, h = doc["settings"], doc["headline"]
    labels, fams, conds = st["entrants"], st["families"], st["conditions"]
    frac = h["decided_fraction"] or 0.0
    out = [
        f"Median capacity θ per family (lognormal fit of {st['seeds']} per-seed capacities"
        f"{_reduced_text(st)}, right-censoring by maximum likelihood, 95 % bootstrap "
        "interval):\n\n",
        capacity_table(h, fams, labels, conds),
    ]
    if not h["pairs"]:
        out.append(f"\n{_pairs_text(h)} Wall time {st['wall_s'] / 60:.1f} min.\n")
        return "".join(out)
    out += [
        "\nVerdicts, row entrant vs column entrant, one symbol per family ("
        + ", ".join(fams)
        + "): `>` above, `<` below, `=` equivalent (ratio of median "
        "capacities within ±5 %), `?` undecided (paired bootstrap interval of the ratio "
        "and Wilcoxon signed-rank test on the common seeds).\n",
    ]
    for cond in conds:
        out.append(f"\n**{_cond(cond)}**\n\n")
        out.append(compact_verdicts(h, cond, fams, labels))
    out.append(
        f"\nPairs decided: {h['decided']} of {h['pairs']} ({100 * frac:.0f} %); target ≥ "
        f"{100 * TARGET_DECIDED:.0f} %: **{'met' if frac >= TARGET_DECIDED else 'not met'}**. "
        f"Wall time {st['wall_s'] / 60:.1f} min, {st['workers']} workers.\n"
    )
    return "".join(out)


def cost_table(doc: dict[str, Any]) -> str:
    """Per entrant of a headline run (``settings.tasks``; Markdown, ``hyperloop compare cost``):
    the seeds it flew, the worker-minutes of its tasks' flights (``wall_s``: the engine) and,
    where recorded, of the paper's STS of the levels' runs (``sts_s``), the flights'
    worker-seconds per seed and that relative to ``lqr``'s, the idle rows' share of its
    control steps, and its share of all recorded worker time."""
    st = doc["settings"]
    tasks = st.get("tasks")
    if not tasks:
        raise ValueError("headline.json has no settings.tasks (a run from before they were kept)")
    keys = ("wall_s", "sts_s", "steps", "run_steps")
    per: dict[str, dict[str, float]] = {}
    for t in tasks:
        p = per.setdefault(t["entrant"], dict.fromkeys((*keys, "tasks"), 0.0))
        for k in keys:
            p[k] += t.get(k) or 0.0
        p["seeds"] = t["seeds"]
        p["tasks"] += 1
    has_sts = any("sts_s" in t for t in tasks)
    total = sum(p["wall_s"] + p["sts_s"] for p in per.values())
    ref = per.get("lqr")
    ref_seed = ref["wall_s"] / (ref["seeds"] * ref["tasks"]) if ref else None
    head = ["entrant", "seeds", "flights worker-min"]
    head += ["STS worker-min"] if has_sts else []
    head += ["flights worker-s per seed", "per seed / `lqr`", "idle steps", "share of worker time"]
    lines = ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    for lab in st["entrants"]:
        p = per[lab]
        s_seed = p["wall_s"] / (p["seeds"] * p["tasks"])
        cells = [lab, str(int(p["seeds"])), f"{p['wall_s'] / 60:.1f}"]
        cells += [f"{p['sts_s'] / 60:.1f}"] if has_sts else []
        cells += [
            f"{s_seed:.1f}",
            f"{s_seed / ref_seed:.2f}" if ref_seed else "n/a",
            f"{100 * (1.0 - p['run_steps'] / p['steps']):.0f} %",
            f"{100 * (p['wall_s'] + p['sts_s']) / total:.1f} %",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    lines.append(
        f"\nRecorded worker time {total / 60:.1f} min on {st['workers']} workers; wall time "
        f"{st['wall_s'] / 60:.1f} min."
    )
    return "\n".join(lines) + "\n"


def _pairs_text(h: dict[str, Any]) -> str:
    """ "Pairs decided: 7 of 9 (78 %)." — or, for a run of one entrant, that it has none."""
    if not h["pairs"]:
        return "One entrant: no pairs to compare, no verdicts."
    return f"Pairs decided: {h['decided']} of {h['pairs']} ({100 * h['decided_fraction']:.0f} %)."


def _reduced_text(st: dict[str, Any]) -> str:
    """ ", mpc: the first 16 (its pairs on those)" for the entrants flown on fewer seeds."""
    red = st.get("entrant_seeds") or {}
    if not red:
        return ""
    items = ", ".join(f"{lab}: the first {k}" for lab, k in red.items())
    return f" ({items}; {'its' if len(red) == 1 else 'their'} pairs on those seeds)"


def _cond(cond: str) -> str:
    return cond.replace("paper-", "").replace("-curved", " R200").replace("-", " ")


def markdown(doc: dict[str, Any], analysis: dict[str, Any]) -> str:
    st, h = doc["settings"], doc["headline"]
    labels, fams, conds = st["entrants"], st["families"], st["conditions"]
    out = [
        "# Capacities and verdicts\n",
        f"{st['seeds']} evaluation seeds ({st['seed_range'][0]}–{st['seed_range'][1]}) × "
        f"{st['distance_km']:g} km per run, common to every entrant{_reduced_text(st)}; "
        "capacity = the smallest "
        f"severity at which the run touches (bracket ratio ≤ {st['ratio']:g}). "
        f"Wall time {st['wall_s'] / 60:.1f} min ({st['workers']} workers). "
        f"{_pairs_text(h)}\n",
        "## Median capacity θ (lognormal fit, right-censoring by ML; 95 % bootstrap interval)\n",
        capacity_table(h, fams, labels, conds),
    ]
    if h["pairs"]:
        out.append(
            "\n## Verdicts (row vs column: > above, < below, = equivalent within ±5 %, "
            "? undecided; ratio of median capacities, paired on common seeds)\n"
        )
    for cond in conds if h["pairs"] else ():
        for fam in fams:
            cell = analysis[cond][fam]
            out.append(f"\n### {cond}, {fam} (decided {cell['decided_fraction']:.0%})\n\n")
            out.append(verdict_table(h, cond, fam, labels))
    out.append("\n## Non-monotone and censored seeds\n\n")
    out.append(
        table(
            ("condition", "family", "entrant", "right-censored", "left-censored", "non-monotone"),
            (
                (r["condition"], r["family"], r["entrant"], *counts)
                for r in h["capacities"]
                if any(counts := (r["n_censored"], r["left_censored"], r["non_monotone"]))
            ),
            "lllrrr",
        )
    )
    out.append(contact_table(analysis, conds, fams, labels))
    return "".join(out)


def contact_table(
    analysis: dict[str, Any], conds: Sequence[str], fams: Sequence[str], labels: Sequence[str]
) -> str:
    """What sets each capacity: per condition × family × entrant, the seeds whose run at
    the capacity touched with the levitation gap (``gap``), the guidance gap (``lateral``)
    or both (empty for a run recorded before the breakdown was kept)."""
    rows = []
    for cond in conds:
        for fam in fams:
            for lab in labels:
                kinds = analysis[cond][fam]["entrants"][lab].get("contact_at_capacity")
                if kinds:
                    text = ", ".join(f"{k} {n}" for k, n in kinds.items())
                    rows.append((_cond(cond), fam, lab, text))
    if not rows:
        return ""
    return "\n## What sets the capacity (first contact of the run at it, seeds)\n\n" + table(
        ("condition", "family", "entrant", "contact at the capacity"), rows
    )


def csv_text(doc: dict[str, Any]) -> str:
    import csv
    import io

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(
        [
            "condition",
            "family",
            "entrant",
            "theta",
            "theta_lo",
            "theta_hi",
            "beta",
            "median_empirical",
            "n",
            "n_censored",
            "non_monotone",
            "binary_theta",
        ]
    )
    for r in doc["headline"]["capacities"]:
        ci = r["theta_ci"] or [None, None]
        w.writerow(
            [
                r["condition"],
                r["family"],
                r["entrant"],
                r["theta"],
                ci[0],
                ci[1],
                r["beta"],
                r["median_empirical"],
                r["n"],
                r["n_censored"],
                r["non_monotone"],
                r["binary_theta"],
            ]
        )
    return buf.getvalue()
