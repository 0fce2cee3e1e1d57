"""One vocabulary of output names (issue 19 point 6): every key of every output record of
evaluate, reproduce_paper, fragility, benchmark and capacity is declared in
:mod:`agents.evaluation.vocabulary`, and the old names are read as aliases."""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

import pytest

from agents.evaluation import vocabulary as voc

COND = "paper-2000-straight"


def _undeclared(keys: Any, where: str) -> list[str]:
    return [f"{where}: {k}" for k in keys if not voc.declared(k)]


def _csv_header(text: str) -> list[str]:
    return next(csv.reader(io.StringIO(text)))


def test_the_table_is_well_formed() -> None:
    for name, term in voc.VOCABULARY.items():
        assert name == name.strip() and term.meaning, name
    for old, new in voc.ALIASES.items():
        assert old not in voc.VOCABULARY and new in voc.VOCABULARY, old
    assert voc.declared("theta_pier_settlement_lo") and not voc.declared("worst_unit")


def test_canonical_renames_old_keys_and_keeps_new_ones() -> None:
    old = {"controller": "pid", "scenario": "x", "worst_p_unsteady": 0.1, "worst_unit": "FL"}
    assert voc.canonical(old) == {
        "controller": "pid",
        "condition": "x",
        "p_unsteady": 0.1,
        "unit": "FL",
    }
    both = {"p_unsteady_gap": 1.0, "p_unsteady": 2.0}
    assert voc.canonical(both) == {"p_unsteady": 2.0}


def test_evaluate_outputs_are_declared(tmp_path: Path) -> None:
    from agents.evaluation.evaluate import evaluate

    res = evaluate(
        ["passive"],
        [COND],
        distance_km=0.2,
        seeds=[1_000_000],
        out_dir=tmp_path,
        settle_s=0.1,
        progress=False,
        figures=False,
        n_boot=0,
    )
    m = res["results"][0]["metrics"]
    bad = _undeclared(m, "metrics")
    for name in ("summary.csv", "sts_units.csv"):
        bad += _undeclared(_csv_header((tmp_path / name).read_text()), name)
    assert not bad
    assert {"p_unsteady", "unit", "p_unsteady_guidance", "unit_guidance", "condition"} <= set(m)


def test_reproduce_paper_records_are_declared() -> None:
    from agents.evaluation.reproduce_paper import critical_radius, radius_sweep

    sweep = radius_sweep((150e3,), (1000.0,), 0.2, 0, "repelling", 0.1)
    crit = critical_radius("passive", 1000.0, 0.2, 0, "repelling", rel_bracket=0.9)
    assert not _undeclared(sweep[0], "radius sweep") + _undeclared(crit, "critical radius")
    assert "p_unsteady" in sweep[0]


def test_fragility_outputs_are_declared() -> None:
    from agents.evaluation.fragility import fragility
    from agents.evaluation.fragility_report import (
        FIT_COLUMNS,
        LEVEL_COLUMNS,
        fit_rows,
        level_rows,
        to_json,
    )

    res = fragility(
        controllers=["passive"],
        conditions=[COND],
        family="roughness",
        levels=[0.5],
        seeds=2,
        distance_km=0.2,
        settle_s=0.1,
        n_boot=0,
        n_boot_fragility=5,
        progress=False,
    )
    doc = to_json(res)
    bad = []
    for r in doc["levels"]:
        bad += _undeclared(r, "level row")
    for f in doc["fits"]:
        bad += _undeclared(f, "fit")
    bad += _undeclared(LEVEL_COLUMNS, "LEVEL_COLUMNS") + _undeclared(FIT_COLUMNS, "FIT_COLUMNS")
    for r in level_rows(res) + fit_rows(res):
        bad += _undeclared(r, "CSV row")
    assert not bad
    assert {"unit", "unit_guidance"} <= set(doc["levels"][0])


def test_benchmark_headline_records_are_declared() -> None:
    from agents.evaluation import benchmark as bm

    fit = {"status": "no_contact", "bounds": {"theta_lower": 0.5}, "levels": [0.5]}
    level = {
        "controller": "pid",
        "condition": COND,
        "level": 0.3,
        "p_contact": 0.0,
        "p_contact_ci": [0.0, 0.5],
        "p_unsteady": 1e-9,
        "p_unsteady_ci": [0.0, 1e-8],
        "p_unsteady_guidance": 1e-7,
        "sts_guidance": {},
        "contact_rate_per_100km": 0.0,
        "contact_rate_per_100km_ci": [0.0, 1.0],
        "rms_gap_mm": 1.0,
        "a_wz_m_s2": 0.1,
        "a_wy_m_s2": 0.1,
        "a_v_m_s2": 0.2,
        "comfort": "not uncomfortable",
    }
    sweeps = {
        "roughness": {
            "pid": {
                "fits": [{"controller": "pid", "condition": COND, "fit": fit}],
                "levels": [level],
            }
        }
    }
    suite = {"families": {"roughness": {"levels": [0.3], "grid": [0.3]}}}
    h = bm.headline(sweeps, suite, ["pid"], [COND])
    bad = _undeclared(h, "headline")
    for row in h["rows"]:
        bad += _undeclared(row, "row")
        for c in row["capacity"].values():
            bad += _undeclared(c, "capacity")
        for a in row["at_levels"]:
            bad += _undeclared(a, "at_levels")
    bad += _undeclared(_csv_header(bm.headline_csv(h, ["roughness"])), "headline.csv")
    assert not bad


@pytest.mark.filterwarnings("ignore")
def test_capacity_outputs_are_declared() -> None:
    from agents.evaluation import capacity_benchmark as cb

    res = cb.run(
        ["passive"],
        [COND],
        ["roughness"],
        seeds=[1_000_000, 1_000_001],
        distance_km=0.2,
        n_boot=20,
        progress=False,
        ratio=1.3,
    )
    doc = {"settings": res["settings"], "headline": res["headline"]}
    h = doc["headline"]
    bad = _undeclared(h, "headline")
    for r in h["capacities"]:
        bad += _undeclared(r, "capacity row")
        for st in [r["sts_at_start"], *r["sts_at_levels"]]:
            bad += _undeclared(st or {}, "sts")
        for p in r["p_contact"]:
            bad += _undeclared(p, "p_contact")
    for v in h["verdicts"]:
        bad += _undeclared(v, "verdict")
    for cell in (c for fams in res["analysis"].values() for c in fams.values()):
        bad += _undeclared(cell, "cell")
        for e in cell["entrants"].values():
            bad += _undeclared(e, "entrant")
            for st in e["sts_at_levels"] or []:
                bad += _undeclared(st, "level STS")
                bad += _undeclared(st["gap"], "level STS gap")
    for per_seed in res["capacities"][COND]["roughness"]["passive"]:
        bad += _undeclared(per_seed, "search")
        for run in per_seed["runs"]:
            bad += _undeclared(run, "run")
    bad += _undeclared(_csv_header(cb.csv_text(doc)), "capacities CSV")
    assert not bad
    assert "p_unsteady" in h["capacities"][0]["sts_at_levels"][0]
