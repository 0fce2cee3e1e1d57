"""A score's report: Markdown (:func:`markdown`, with the ride comfort section of
:func:`comfort_markdown`) and a figure of the controller's median capacity among the
published entrants' (:func:`plot_score`), rendered from the result of
:func:`agents.evaluation.score.score`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from agents.evaluation.render import interval, significant, table
from agents.evaluation.score import SYMBOL


def _theta(c: dict[str, Any]) -> str:
    if c["theta"] is None:
        med = c.get("median_empirical")
        return f"{significant(med)} (empirical)" if med is not None else "n/a"
    ci = c.get("theta_ci") or [None, None]
    band = f" {interval(ci[0], ci[1])}" if ci[0] is not None else ""
    cens = f" ({c['n_censored']} cens.)" if c["n_censored"] else ""
    return f"{significant(c['theta'])}{band}{cens}"


def _kinds(k: dict[str, int]) -> str:
    return ", ".join(f"{kind} {n}" for kind, n in k.items())


def markdown(res: dict[str, Any]) -> str:
    """The score as Markdown (module docstring)."""
    sc, fp = res["scope"], res["fingerprint"]
    head = [
        f"# {res['controller']} on the {res['benchmark']} benchmark\n\n",
        f"`{res['entry']}`, seeds {sc['seeds'][0]}–{sc['seeds'][1]}"
        + (" (quick: roughness on the first seeds only)" if res["quick"] else "")
        + f"; fingerprint {fp['digest']} (published {res['published_fingerprint']})"
        + (f"; **differs in {', '.join(fp['differs_in'])}**" if fp["differs_in"] else "")
        + (f"; guard: `{res['guard']['entrant']}` re-flown bit for bit" if res["guard"] else "")
        + ".\n\n",
        "## Median capacity θ, placement and what sets the capacity\n\n",
        table(
            (
                "condition",
                "family",
                "θ (95 % interval)",
                "rank",
                "contact at capacity",
                "P(unsteady) gap / guidance at the suite's levels",
            ),
            (
                (
                    c["condition"],
                    c["family"],
                    _theta(c),
                    f"{c['placement']['rank']} of {c['placement']['of']}",
                    _kinds(c["contact_at_capacity"]),
                    " / ".join(
                        f"{significant(s['p_unsteady'])}, {significant(s['p_unsteady_guidance'])}"
                        for s in c["sts_at_levels"]
                    ),
                )
                for c in res["cells"]
            ),
        ),  # fmt: skip
        "\n## Verdicts against every published entrant\n\n",
        "`>` above, `<` below, `=` equivalent (ratio within ±5 %), `?` undecided (paired "
        "bootstrap interval and Wilcoxon test on the common seeds).\n\n",
    ]
    entrants = [v["entrant"] for v in res["cells"][0]["verdicts"]]
    rows = [
        (f"{c['condition']} {c['family']}", *(SYMBOL[v["verdict"]] for v in c["verdicts"]))
        for c in res["cells"]
    ]
    e = res["leaderboard"]
    tail = [
        table(("cell", *entrants), rows),
        *(comfort_markdown(res) if res.get("comfort") else []),
        "\n## Leaderboard entry\n\n",
        f"`{e['controller']}`: above {e['above']}, below {e['below']}, equivalent "
        f"{e['equivalent']}, undecided {e['undecided']} of the paired verdicts.\n",
    ]
    return "".join(head + tail)


COMFORT_HEADER = ("condition", "controller", "a_wz [m/s²]", "ratio (paired) [95 %]", "verdict")


def _3(x: float) -> str:
    return f"{x:.3f}"


def _a_wz(r: dict[str, Any]) -> str:
    mean = r["a_wz_mean_m_s2"]
    touched = f" ({r['contacts']} touched)" if r["contacts"] else ""
    return (f"{mean:.4f}" if mean is not None else "n/a") + touched


def comfort_markdown(res: dict[str, Any]) -> list[str]:
    """The ride comfort section of a score: per condition the controller's mean a_wz, then
    each published entrant's with the paired ratio and the verdict."""
    ride, name = res["comfort"], res["controller"]
    first, last = ride["seeds"]
    quick = (
        f"; --quick: the first {ride['n_seeds']} of the {ride['published_seeds']} published"
        if res["quick"]
        else ""
    )
    rows = []
    for c in ride["cells"]:
        rows.append((c["condition"], f"**{name}**", _a_wz(c), "—", ""))
        for v in c["verdicts"]:
            ratio = (
                "—" if v["ratio"] is None else f"{v['ratio']:.3f} {interval(v['lo'], v['hi'], _3)}"
            )
            rows.append((c["condition"], v["entrant"], _a_wz(v), ratio, v["verdict"]))
    n = ride["summary"]
    return [
        "\n## Ride comfort against the published entrants\n\n",
        f"ISO 2631-1 W_k-weighted RMS heave acceleration a_wz [m/s²], mean over "
        f"{ride['n_seeds']} seeds ({first}–{last}{quick}) × {ride['distance_km']:g} km, one "
        "run per seed on the condition's own irregularity; each published entrant's on the "
        f"same seeds and the paired ratio `{name}` / entrant (geometric mean of the per-seed "
        "ratios, paired bootstrap 95 % interval, Wilcoxon test, equivalent within ±5 %). "
        "Lower is smoother; a run that touched is left out of both sides of a pair.\n\n",
        table(COMFORT_HEADER, rows, "llrll"),
        f"\n`{name}` rides smoother than {n['smoother']}, equivalent to {n['equivalent']}, "
        f"rougher than {n['rougher']} and undecided against {n['undecided']} of the "
        f"{sum(n.values())} entrant × condition pairs.\n",
    ]


def published_comfort_table(ride: dict[str, Any]) -> str:
    """The published ride comfort (:func:`agents.evaluation.published.load_published_comfort`)
    as Markdown: each entrant's mean a_wz per condition (runs that touched counted), with
    where and how it was flown."""
    n, (first, last) = len(ride["seeds"]), (ride["seeds"][0], ride["seeds"][-1])
    rows = []
    for lab in ride["entrants"]:
        cells = []
        for cond in ride["conditions"]:
            vals = ride["a_wz_m_s2"][cond][lab]
            kept = [v for v in vals if v is not None]
            touched = len(vals) - len(kept)
            mean = f"{sum(kept) / len(kept):.3f}" if kept else "n/a"
            cells.append(mean + (f" ({touched} touched)" if touched else ""))
        rows.append((f"`{lab}`", *cells))
    m = ride["machine"]
    return (
        f"Mean a_wz [m/s²] over {n} seeds ({first}–{last}) × {ride['distance_km']:g} km per "
        f"entrant and condition (`{ride['command']}`, {ride['date'][:10]}, {m.get('cpus')} "
        f"CPUs, Python {m.get('python')}):\n\n"
        + table(("entrant", *ride["conditions"]), rows, "l" + "r" * len(ride["conditions"]))
    )


def plot_score(res: dict[str, Any], published: dict[str, Any], path: str | Path) -> Path:
    """Per cell, the published entrants' median capacities (grey) and the scored
    controller's (red), log scale."""
    from agents.evaluation.figures import _pyplot, save_figure

    plt = _pyplot()
    cells = res["cells"]
    fig, ax = plt.subplots(figsize=(8, 0.45 * len(cells) + 1.2))
    for i, c in enumerate(cells):
        pub = published["cells"][c["condition"]][c["family"]]
        vals = [e["theta"] or e["median_empirical"] for e in pub.values()]
        ax.scatter([v for v in vals if v], [i] * sum(1 for v in vals if v), c="0.6", s=14)
        mine = c["theta"] or c["median_empirical"]
        if mine:
            ax.scatter([mine], [i], c="tab:red", s=40, zorder=3)
    ax.set_yticks(range(len(cells)), [f"{c['condition']} {c['family']}" for c in cells])
    ax.set_xscale("log")
    ax.set_xlabel("median capacity θ (the family's severity unit)")
    ax.set_title(f"{res['controller']} (red) among the published entrants")
    fig.tight_layout()
    return save_figure(fig, path)
