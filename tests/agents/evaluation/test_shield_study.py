"""The shield study's tables (:mod:`agents.evaluation.shield_study`): verdicts read from a
capacity run in either order, the pairs bare / shielded, and a small study end to end."""

from __future__ import annotations

import json

import pytest

from agents.evaluation import shield_study as st


def _headline() -> dict:
    caps = [
        {"condition": "c1", "family": "roughness", "entrant": e, "theta": t, "theta_ci": [t, t]}
        for e, t in (
            ("lqr", 0.5),
            ("shielded:lqr", 0.55),
            ("ppo", 0.4),
            ("shielded:ppo", 0.6),
        )
    ]
    v = [
        # stored as (bare, shielded): the study inverts it
        {"a": "lqr", "b": "shielded:lqr", "ratio": 0.5, "lo": 0.4, "hi": 0.8, "verdict": "below"},
        {"a": "shielded:ppo", "b": "ppo", "ratio": 1.5, "lo": 1.2, "hi": 1.9, "verdict": "above"},
        {"a": "ppo", "b": "lqr", "ratio": 0.8, "lo": 0.7, "hi": 0.9, "verdict": "below"},
        {"a": "shielded:ppo", "b": "lqr", "ratio": 1.2, "lo": 1.1, "hi": 1.3, "verdict": "above"},
    ]
    return {
        "settings": {"entrants": ["lqr", "shielded:lqr", "ppo", "shielded:ppo"], "seeds": 4},
        "headline": {"capacities": caps},
        "analysis": {"c1": {"roughness": {"verdicts": v}}},
    }


def test_verdicts_are_read_in_either_order() -> None:
    an = _headline()["analysis"]["c1"]["roughness"]
    inv = st._verdict_lookup(an, "shielded:lqr", "lqr")
    assert inv is not None
    assert inv["ratio"] == pytest.approx(2.0) and inv["verdict"] == "above"
    assert (inv["lo"], inv["hi"]) == (pytest.approx(1.25), pytest.approx(2.5))
    same = st._verdict_lookup(an, "shielded:ppo", "ppo")
    assert same == {"ratio": 1.5, "lo": 1.2, "hi": 1.9, "verdict": "above", "n_used": None}
    assert st._verdict_lookup(an, "lqr", "sac") is None


def test_capacity_effect_pairs_each_entrant_with_its_shielded_self() -> None:
    eff = st.capacity_effect(_headline(), ["lqr", "ppo"])
    pairs = {p["entrant"]: p for p in eff["pairs"]}
    assert pairs["lqr"]["theta"] == 0.5 and pairs["lqr"]["theta_shielded"] == 0.55
    assert pairs["ppo"]["shielded_vs_bare"]["ratio"] == 1.5
    (lv,) = eff["learned_vs_classical"]
    assert (lv["learned"], lv["classical"]) == ("ppo", "lqr")
    assert lv["bare"]["verdict"] == "below" and lv["shielded"]["verdict"] == "above"


def test_a_small_study_end_to_end(tmp_path) -> None:  # noqa: ANN001
    """lqr with and without the filter on 2 seeds × 1.2 km at one condition: the files
    exist, every number in the Markdown comes from the JSON, the filter never acts at the
    scenario's own irregularity and the comfort is then the same."""
    h = _headline()
    h["settings"]["entrants"] = ["lqr", "shielded:lqr"]
    h["analysis"]["c1"]["roughness"]["verdicts"] = h["analysis"]["c1"]["roughness"]["verdicts"][:1]
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
    with pytest.raises(ValueError, match="previous study"):
        st.run(cap, out, conditions=["paper-2000-straight"], seeds=2)
    with pytest.raises(ValueError, match="seeds"):
        st.run(cap, tmp_path / "x", seeds=1)
