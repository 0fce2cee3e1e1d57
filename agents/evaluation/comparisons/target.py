"""Is a learned agent resolved above the best classical controller? (``hyperloop compare
target``)

The per-seed roughness capacities of every named controller are read from capacity runs
(``hyperloop capacity`` / ``hyperloop headline``: ``headline.json``; the first run that has
an entrant wins). Runs are only combined when they flew the same seeds with the same
search settings, and a controller that two runs share must have the same per-seed
capacities in both (the runs are deterministic: that is the proof that the pairs are
paired); otherwise :class:`TargetInputError`. For each paper condition every learned agent
is compared with every classical controller by
:func:`agents.evaluation.capacity_stats.compare_paired` (paired bootstrap interval,
Wilcoxon test, ±5 % equivalence). A learned agent **meets the target at a condition** when
it is resolved above every classical controller there and its W_k comfort (the comfort
file of ``hyperloop compare comfort``, paired a_wz against the same seeds' runs) is no
worse than each classical controller's that the comfort file compares (verdict ``below``
or ``equivalent`` against its reference, and not above the other classical controllers'
mean a_wz by more than 5 %). The target: one learned agent meets it at ≥ 2 of the 4
conditions. :func:`run` writes ``target.json`` and ``target.md``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agents.evaluation.capacity_stats import compare_paired, on_common_seeds
from agents.evaluation.comparisons import ComparisonInputError, field, read_json
from agents.evaluation.outputs import atomic_write_text
from hyperloop_env.scenarios import PAPER_SCENARIOS

FAMILY = "roughness"
SAME = ("seeds", "distance_km", "ratio", "step", "check_above", "searches")
"""The settings two capacity runs must share to be combined."""
FILES = ("target.json", "target.md")
MIN_CONDITIONS = 2
"""Conditions (of the four) at which one learned agent must meet the target."""


def classical_entrants(learned: tuple[str, ...]) -> tuple[str, ...]:
    """Every classical headline entrant with the actuators the ``learned`` agents fly
    (``passive``, the uncontrolled reference, aside), labelled as the headline labels them:
    ``pid``, ``lqr``, ``lqr-preview``, ``mpc`` for the levitation currents; ``pid+g``,
    ``lqr+g``, ``lqr-preview+g`` with the guidance pairs. ``ValueError`` if the agents fly
    different actuator sets (check them separately)."""
    from agents.controllers import registry
    from agents.evaluation.entrants import entrant_actuators, entrant_label

    acts = {entrant_actuators(name)[1] for name in learned}
    if len(acts) != 1:
        raise ValueError(
            f"--learned: {list(learned)} fly different actuator sets ({sorted(acts)}); "
            "check each set on its own or name --classical"
        )
    (act,) = acts
    return tuple(
        entrant_label(n, act)
        for n in registry.entrants(act)
        if n != "passive" and registry.controller_spec(n).kind != "learned"
    )


class TargetInputError(ComparisonInputError):
    """A capacity run or comfort file the target check cannot use, or runs that are not
    the same flights (the message names the file and the field)."""


@dataclass(frozen=True)
class TargetSpec:
    """What a target check compares: the ``learned`` agents against the ``classical``
    controllers, from the capacity ``runs`` (``headline.json`` files) and, optionally, a
    ``comfort`` file; checked on construction (``ValueError`` naming the flag)."""

    learned: tuple[str, ...]
    classical: tuple[str, ...]  # empty: every classical entrant (classical_entrants)
    runs: tuple[Path, ...]
    comfort: Path | None = None

    def __post_init__(self) -> None:
        if self.learned and not self.classical:
            object.__setattr__(self, "classical", classical_entrants(self.learned))
        for flag, v in (("--learned", self.learned), ("--classical", self.classical)):
            if not v:
                raise ValueError(f"{flag}: name at least one controller")
        if not self.runs:
            raise ValueError("--runs: name at least one capacity run (headline.json)")
        both = sorted(set(self.learned) & set(self.classical))
        if both:
            raise ValueError(f"--learned and --classical both name {both}")


def load_capacities(runs: list[Path]) -> tuple[dict[str, dict[str, Any]], dict[str, Any]]:
    """{condition: {entrant: {"seeds", "capacity", "censored"}}} over the runs, and the
    common settings; :class:`TargetInputError` if a run is not a capacity run or the runs
    are not comparable."""
    caps: dict[str, dict[str, Any]] = {}
    ref: dict[str, Any] | None = None
    for path in runs:
        doc = read_json(path, "a capacity run's headline.json")
        s = field(doc, path, "settings")
        mine = {k: s.get(k) for k in SAME}
        mine["searches"] = (s.get("searches") or {}).get(FAMILY)
        mine["seed_range"] = s.get("seed_range")
        if ref is None:
            ref = mine
        elif mine != ref:
            raise TargetInputError(f"{path}: other seeds or search settings than {runs[0]}")
        analysis = field(doc, path, "analysis")
        if not isinstance(analysis, dict):
            raise TargetInputError(f"{path}: field analysis is not an object")
        for cond in analysis:
            entrants = field(doc, path, "analysis", cond, FAMILY, "entrants")
            for name in entrants:
                at = ("analysis", cond, FAMILY, "entrants", name)
                row = {k: field(doc, path, *at, k) for k in ("seeds", "capacity", "censored")}
                have = caps.setdefault(cond, {}).get(name)
                if have is None:
                    caps[cond][name] = row
                elif have != row:
                    caps[cond][name] = merge_rows(have, row, f"{path}: {name} on {cond}")
    assert ref is not None
    return caps, ref


def merge_rows(have: dict[str, Any], row: dict[str, Any], what: str) -> dict[str, Any]:
    """The one of two runs' per-seed results of a controller that has more seeds, if they
    agree on the seeds they share (a run may fly an entrant on the first N seeds only:
    ``settings.entrant_seeds``); :class:`TargetInputError` otherwise."""
    small, big = sorted((have, row), key=lambda r: len(r["seeds"]))
    pos = {sd: k for k, sd in enumerate(big["seeds"])}
    if not set(small["seeds"]) <= set(pos) or any(
        (small["capacity"][k], small["censored"][k])
        != (big["capacity"][pos[sd]], big["censored"][pos[sd]])
        for k, sd in enumerate(small["seeds"])
    ):
        raise TargetInputError(
            f"{what} has other per-seed capacities than in an earlier run: the runs are not "
            "the same flights"
        )
    return big


def comfort_rows(path: Path | None) -> dict[tuple[str, str], dict[str, Any]]:
    """The rows of a comfort file by (condition, controller), and its reference under
    ``("reference", "")``; {} without a file."""
    if path is None:
        return {}
    doc = read_json(path, "the comfort.json of hyperloop compare comfort")
    rows = field(doc, path, "rows")
    ref = field(doc, path, "reference")
    out = {}
    for k, r in enumerate(rows):
        for key in ("condition", "controller"):
            if not isinstance(r, dict) or key not in r:
                raise TargetInputError(f"{path}: rows[{k}] has no {key!r}")
        out[(r["condition"], r["controller"])] = r
    return out | {("reference", ""): {"controller": ref}}


def comfort_ok(
    comfort: dict[tuple[str, str], dict[str, Any]], cond: str, agent: str, classical: list[str]
) -> tuple[bool | None, str]:
    """(no worse than every classical controller's W_k, why); None without data."""
    mine = comfort.get((cond, agent))
    if mine is None:
        return None, "no comfort data"
    ref = comfort[("reference", "")]["controller"]
    why = []
    ok = True
    for c in classical:
        other = comfort.get((cond, c))
        if other is None:
            return None, f"no comfort data for {c}"
        if c == ref:
            v = mine["vs_reference"]
            good = v["verdict"] in ("B above A", "equivalent") or (
                v["hi"] is not None and v["hi"] <= 1.05
            )
            why.append(f"a_wz / {c} {v['ratio']:.3f} [{v['lo']:.3f}, {v['hi']:.3f}]")
        else:
            r = mine["a_wz_mean_m_s2"] / other["a_wz_mean_m_s2"]
            good = r <= 1.05
            why.append(f"mean a_wz / {c} {r:.3f}")
        ok = ok and good
    return ok, "; ".join(why)


def target_check(spec: TargetSpec, command: str | None = None) -> dict[str, Any]:
    """The target check (module docstring) as the JSON document ``target.json`` holds."""
    learned, classical = list(spec.learned), list(spec.classical)
    caps, settings = load_capacities(list(spec.runs))
    comfort = comfort_rows(spec.comfort)
    rows = []
    for cond in PAPER_SCENARIOS:
        have = caps.get(cond, {})
        for name in [*learned, *classical]:
            if name not in have:
                runs = ", ".join(map(str, spec.runs))
                raise TargetInputError(f"{name} has no {FAMILY} capacities on {cond} in {runs}")
        for agent in learned:
            a = have[agent]
            cmps = {}
            for c in classical:
                b = have[c]
                r = compare_paired(
                    *on_common_seeds(
                        (a["capacity"], a["censored"], a["seeds"]),
                        (b["capacity"], b["censored"], b["seeds"]),
                        agent,
                        c,
                    )
                )
                cmps[c] = {k: r[k] for k in ("ratio", "lo", "hi", "p_value", "verdict", "n")}
            above_all = all(v["verdict"] == "A above B" for v in cmps.values())
            c_ok, c_why = comfort_ok(comfort, cond, agent, classical)
            rows.append(
                {
                    "condition": cond,
                    "agent": agent,
                    "vs": cmps,
                    "above_every_classical": above_all,
                    "comfort_no_worse": c_ok,
                    "comfort": c_why,
                    "meets": bool(above_all and c_ok),
                }
            )
    per_agent = {
        a: [r["condition"] for r in rows if r["agent"] == a and r["meets"]] for a in learned
    }
    best = max(learned, key=lambda a: len(per_agent[a]))
    return {
        "command": command or "agents.evaluation.comparisons.target.run(...)",
        "family": FAMILY,
        "settings": settings,
        "learned": learned,
        "classical": classical,
        "rows": rows,
        "conditions_met": per_agent,
        "best_learned": best,
        "target_met": len(per_agent[best]) >= MIN_CONDITIONS,
    }


def target_markdown(doc: dict[str, Any]) -> str:
    """``target.md``: the table of a :func:`target_check` document and its conclusion."""
    rows, classical = doc["rows"], doc["classical"]
    best, met = doc["best_learned"], doc["target_met"]
    best_at = doc["conditions_met"][best]
    md = [
        f"Roughness capacity of each learned agent / each classical controller (paired on "
        f"their common evaluation seeds: {_seed_counts(rows, classical)}; 95 % interval, "
        "verdict), and W_k comfort:",
        "",
        "| condition | agent | "
        + " | ".join(f"/ `{c}`" for c in classical)
        + " | above every classical | W_k no worse |",
        "|---|---|" + "---|" * len(classical) + "---|---|",
    ]
    for r in rows:
        cells = []
        for c in classical:
            v = r["vs"][c]
            verdict = {"A above B": "above", "B above A": "below"}.get(v["verdict"], v["verdict"])
            cells.append(f"{v['ratio']:.3f} [{v['lo']:.3f}, {v['hi']:.3f}] {verdict}")
        cw = {True: "yes", False: "no", None: "n/a"}[r["comfort_no_worse"]]
        md.append(
            f"| {r['condition']} | `{r['agent']}` | "
            + " | ".join(cells)
            + f" | {'yes' if r['above_every_classical'] else 'no'} | {cw} ({r['comfort']}) |"
        )
    md += [
        "",
        f"Target (one learned agent resolved above every classical controller with W_k no "
        f"worse at ≥ {MIN_CONDITIONS} of 4 conditions): **{'met' if met else 'not met'}** — "
        f"best: `{best}` at {len(best_at)} ({', '.join(best_at) or 'none'}).",
    ]
    return "\n".join(md) + "\n"


def _seed_counts(rows: list[dict[str, Any]], classical: list[str]) -> str:
    """ "32" or "32; 16 against mpc": the seeds of the pairs, per classical controller."""
    n = {c: {r["vs"][c]["n"] for r in rows} for c in classical}
    common = max((x for v in n.values() for x in v), default=0)
    fewer = [f"{min(v)} against `{c}`" for c, v in n.items() if min(v) != common]
    return "; ".join([str(common), *fewer])


def run(
    spec: TargetSpec,
    out_dir: str | Path,
    *,
    overwrite: bool = False,
    command: str | None = None,
) -> dict[str, Any]:
    """The target check into ``out_dir`` (``target.json``, ``target.md``; refused with
    ``FileExistsError`` if they exist, unless ``overwrite``); returns the document."""
    out = Path(out_dir)
    files = [out / name for name in FILES]
    if any(f.exists() for f in files) and not overwrite:
        raise FileExistsError(f"{out} holds a target check (pass --overwrite)")
    doc = target_check(spec, command)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(files[0], json.dumps(doc, indent=1) + "\n")
    atomic_write_text(files[1], target_markdown(doc))
    return doc
