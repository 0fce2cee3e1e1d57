"""The shield study's tables (:mod:`agents.evaluation.comparisons.shield`, ``hyperloop
compare shield``): paired verdicts from one or more capacity runs (bare / shielded, learned /
classical), a small study end to end, the command."""

from __future__ import annotations

import json

import numpy as np
import pytest

from agents.evaluation.comparisons import shield as st

SEEDS = list(range(1_000_000, 1_000_008))
PER_SEED = {  # capacities per seed: shielded:ppo 1.5 × ppo on every seed, shielded:lqr = lqr
    "lqr": [0.5, 0.52, 0.48, 0.51, 0.49, 0.5, 0.53, 0.47],
    "ppo": [0.4, 0.42, 0.38, 0.41, 0.39, 0.4, 0.43, 0.37],
}
PER_SEED["shielded:lqr"] = list(PER_SEED["lqr"])
PER_SEED["shielded:ppo"] = [1.5 * c for c in PER_SEED["ppo"]]


def _headline(entrants: list[str]) -> dict:
    caps = [
        {"condition": "c1", "family": "roughness", "entrant": e, "theta": 0.1, "theta_ci": [0, 1]}
        for e in entrants
    ]
    ents = {
        e: {"seeds": SEEDS, "capacity": PER_SEED[e], "censored": [False] * len(SEEDS)}
        for e in entrants
    }
    return {
        "settings": {"entrants": entrants, "seeds": len(SEEDS), "seed_range": [SEEDS[0], 0]},
        "headline": {"capacities": caps},
        "analysis": {"c1": {"roughness": {"entrants": ents}}},
    }


def test_capacity_effect_pairs_each_entrant_with_its_shielded_self(tmp_path) -> None:  # noqa: ANN001
    """Two runs combined: the ratios are the per-seed geometric means (1 and 1.5), and the
    learned agent is compared with the classical one bare and shielded."""
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    a.write_text(json.dumps(_headline(["lqr", "shielded:lqr"])))
    b.write_text(json.dumps(_headline(["ppo", "shielded:ppo"])))
    eff = st.capacity_effect([a, b], ["lqr", "ppo"])
    pairs = {p["entrant"]: p for p in eff["pairs"]}
    assert pairs["lqr"]["shielded_vs_bare"]["ratio"] == pytest.approx(1.0)
    assert pairs["lqr"]["shielded_vs_bare"]["verdict"] == "equivalent"
    assert pairs["ppo"]["shielded_vs_bare"]["ratio"] == pytest.approx(1.5)
    assert pairs["ppo"]["shielded_vs_bare"]["verdict"] == "above"
    (lv,) = eff["learned_vs_classical"]
    assert (lv["learned"], lv["classical"]) == ("ppo", "lqr")
    ratio = np.exp(np.mean(np.log(np.array(PER_SEED["ppo"]) / PER_SEED["lqr"])))
    assert lv["bare"]["ratio"] == pytest.approx(ratio) and lv["bare"]["verdict"] == "below"
    assert lv["shielded"]["ratio"] == pytest.approx(1.5 * ratio)
    assert lv["shielded"]["verdict"] == "above"
    assert st._paired({}, "ppo", "lqr") is None


def test_a_small_study_end_to_end(tmp_path) -> None:  # noqa: ANN001
    """lqr with and without the filter on 2 seeds × 1.2 km at one condition: the files
    exist, every number in the Markdown comes from the JSON, the filter never acts at the
    scenario's own irregularity and the comfort is then the same."""
    h = _headline(["lqr", "shielded:lqr"])
    cap = tmp_path / "headline.json"
    cap.write_text(json.dumps(h))
    out = tmp_path / "out"
    res = st.run(
        cap, out, conditions=["paper-2000-straight"], seeds=2, distance_km=1.2, severities=[0.3]
    )
    assert (out / "shield.json").is_file() and (out / "shield.md").is_file()
    nominal = [r for r in res["interventions"] if r["severity"] is None]
    assert nominal and all(r["counters"]["changed"] == 0 for r in nominal)
    assert all(r["counters"]["steps"] > 0 for r in res["interventions"])
    (c,) = res["comfort"]
    assert c["a_wz_mean_m_s2"] == c["a_wz_mean_shielded_m_s2"]
    assert (
        st.render(json.loads((out / "shield.json").read_text())) == (out / "shield.md").read_text()
    )
    with pytest.raises(FileExistsError, match="holds a shield study"):
        st.run(cap, out, conditions=["paper-2000-straight"], seeds=2)
    with pytest.raises(ValueError, match="seeds"):
        st.run(cap, tmp_path / "x", seeds=1)


def test_the_command_renders_and_refuses_without_capacity(tmp_path, capsys) -> None:  # noqa: ANN001
    """``hyperloop compare shield --render-only`` rewrites shield.md from shield.json (the
    published one); without ``--capacity`` the command stops with one usage line."""
    import shutil
    from pathlib import Path

    from agents.cli import compare

    published = Path(__file__).resolve().parents[3] / "docs" / "benchmark" / "shield"
    out = tmp_path / "shield"
    out.mkdir()
    shutil.copy(published / "shield.json", out / "shield.json")
    assert compare.main(["shield", "--render-only", "--out", str(out)]) == 0
    assert (out / "shield.md").read_text() == (published / "shield.md").read_text()
    with pytest.raises(SystemExit) as exc:
        compare.main(["shield", "--out", str(tmp_path / "new")])
    assert exc.value.code == 2
    assert "--capacity is required" in capsys.readouterr().err


def test_the_study_on_workers_is_the_study_in_one_process(tmp_path) -> None:  # noqa: ANN001
    """The intervention and comfort runs as tasks on two worker processes: the same rows in
    the same order as in this process (two conditions, two severities: the rows differ)."""
    h = _headline(["lqr", "shielded:lqr"])
    cap = tmp_path / "headline.json"
    cap.write_text(json.dumps(h))
    kw = {
        "conditions": ["paper-2000-curved", "paper-1000-straight"],
        "seeds": 2,
        "distance_km": 1.0,
        "severities": [0.3, 0.45],
    }
    here = st.run(cap, tmp_path / "here", **kw)
    there = st.run(cap, tmp_path / "there", **kw, workers=2)
    assert there["interventions"] == here["interventions"]
    assert there["comfort"] == here["comfort"]
    rows = [(r["condition"], r["severity"]) for r in here["interventions"]]
    assert len(set(rows)) == len(rows) == 6
    a = [c["a_wz_mean_m_s2"] for c in here["comfort"]]
    assert a[0] != a[1]  # the conditions ride differently: a swap would show
    seeds = [1_000_000, 1_000_001]
    assert here["comfort"][1] == st.comfort_effect("lqr", "paper-1000-straight", seeds, 1.0)
    assert here["interventions"][5] == st.interventions(
        "lqr", "paper-1000-straight", seeds, 1.0, 0.45
    )
