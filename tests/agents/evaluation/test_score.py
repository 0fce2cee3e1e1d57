"""``hyperloop score``: comparable by construction. The twin test (the LQR under another
name, from a user's package, scores equivalent to the published ``lqr`` and above
``passive``, and rides as ``lqr`` does), the fingerprint refusal for a changed model
parameter, the guard that re-flies a published entrant, and the published data that ships
with the package."""

from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path

import pytest

from agents.evaluation import published as pubmod
from agents.evaluation import score as sc
from agents.evaluation.capacity_benchmark import DEFAULT_ENTRANTS

TWIN = """
from agents.controllers.lqr import LQRController


class Twin(LQRController):
    name = "lqr-twin"


def make(ctx, **kw):
    return Twin(ctx, **kw)
"""


@pytest.fixture(scope="module")
def twin(tmp_path_factory: pytest.TempPathFactory) -> tuple[int, dict, float, str]:
    import os
    import sys

    from agents.cli.score import main

    work = tmp_path_factory.mktemp("user")
    (work / "mine").mkdir()
    (work / "mine" / "__init__.py").write_text("")
    (work / "mine" / "twin.py").write_text(TWIN)
    old = os.getcwd()
    os.chdir(work)
    t0 = time.perf_counter()
    try:
        rc = main(["mine.twin:make", "--quick", "--out", "sc", "--no-progress", "--workers", "2"])
    finally:
        os.chdir(old)
        sys.path[:] = [p for p in sys.path if p != str(work)]
        sys.modules.pop("mine.twin", None)
        sys.modules.pop("mine", None)
    wall = time.perf_counter() - t0
    return (
        rc,
        json.loads((work / "sc" / "score.json").read_text()),
        wall,
        (work / "sc" / "score.md").read_text(),
    )


def test_the_lqr_twin_scores_equivalent_to_lqr_and_above_passive(twin) -> None:  # noqa: ANN001
    rc, res, wall, _ = twin
    assert rc == 0 and res["controller"] == "lqr-twin" and res["quick"]
    assert res["guard"]["entrant"] == "lqr" and res["fingerprint"]["differs_in"] == []
    assert len(res["cells"]) == 4  # the four paper conditions, roughness
    for cell in res["cells"]:
        by = {v["entrant"]: v for v in cell["verdicts"]}
        assert by["lqr"]["verdict"] in ("equivalent", "undecided"), cell["condition"]
        assert by["lqr"]["verdict"] == "equivalent" and by["lqr"]["ratio"] == 1.0
        assert by["passive"]["verdict"] == "A above B", cell["condition"]
        assert sum(cell["contact_at_capacity"].values()) == 8
    assert wall < 90  # the quick score on this 2-core machine


def test_the_score_files_are_written(twin, tmp_path: Path) -> None:  # noqa: ANN001
    _, res, _, _ = twin
    e = res["leaderboard"]
    assert e["controller"] == "lqr-twin" and e["fingerprint"] == res["fingerprint"]["digest"]
    assert e["above"] + e["below"] + e["equivalent"] + e["undecided"] == 4 * len(DEFAULT_ENTRANTS)


def test_the_lqr_twin_rides_as_lqr(twin) -> None:  # noqa: ANN001
    """The twin's a_wz on the quick seeds is the published ``lqr``'s, seed by seed; each
    pair's ratio is the geometric mean of the per-seed ratios to the published values."""
    import math

    _, res, _, md = twin
    ride, pub = res["comfort"], pubmod.load_published_comfort()
    assert ride["n_seeds"] == sc.QUICK_SEEDS and ride["distance_km"] == pub["distance_km"]
    assert ride["seeds"] == [pub["seeds"][0], pub["seeds"][sc.QUICK_SEEDS - 1]]
    assert [c["condition"] for c in ride["cells"]] == pub["conditions"]
    for cell in ride["cells"]:
        theirs = pub["a_wz_m_s2"][cell["condition"]]
        mine = cell["a_wz_m_s2"]
        assert mine == pytest.approx(theirs["lqr"][: sc.QUICK_SEEDS], rel=1e-9)
        by = {v["entrant"]: v for v in cell["verdicts"]}
        assert list(by) == pub["entrants"]
        for lab, v in by.items():
            pairs = [(a, b) for a, b in zip(mine, theirs[lab], strict=False) if a and b]
            ratio = math.exp(sum(math.log(a / b) for a, b in pairs) / len(pairs))
            assert v["n"] == len(pairs) and v["ratio"] == pytest.approx(ratio, rel=1e-12), lab
        assert by["lqr"]["verdict"] == "equivalent" and by["lqr"]["n"] == sc.QUICK_SEEDS
        assert by["passive"]["verdict"] == "rougher", cell["condition"]
    assert sum(ride["summary"].values()) == 4 * len(DEFAULT_ENTRANTS)
    assert ride["wall_s"] < 15  # single runs per seed: a few seconds on top of the score
    assert "## Ride comfort against the published entrants" in md
    assert "| paper-1000-straight | **lqr-twin** |" in md


def test_a_changed_model_parameter_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    from hyperloop_env.physics import params

    real = params.ModelParams

    def heavier() -> params.ModelParams:
        p = real()
        return dataclasses.replace(
            p, vehicle=dataclasses.replace(p.vehicle, capsule_mass_kg=16_000.0)
        )

    pub = pubmod.load_published()
    monkeypatch.setattr(params, "ModelParams", heavier)
    with pytest.raises(sc.ComparabilityError, match=r"differs .* in: model"):
        sc.check_fingerprint(pub, allow_mismatch=False)
    stamped = sc.check_fingerprint(pub, allow_mismatch=True)
    assert stamped["differs_in"] == ["model"]


def test_the_guard_refuses_a_table_that_does_not_re_fly() -> None:
    pub = pubmod.load_published()
    assert sc.guard(pub)["entrant"] == "lqr"  # the shipped table re-flies
    cond, fam = pub["settings"]["conditions"][0], pub["settings"]["families"][0]
    cell = pub["cells"][cond][fam]["lqr"]
    cell["capacity"] = [cell["capacity"][0] * 1.01, *cell["capacity"][1:]]
    with pytest.raises(sc.ComparabilityError, match="re-flown here"):
        sc.guard(pub)


def test_the_published_data_ships_and_is_checked(tmp_path: Path) -> None:
    pub = pubmod.load_published()
    assert pub["benchmark"] == pubmod.BENCHMARK_VERSION
    assert pub["fingerprint"]["digest"] == pubmod.fingerprint(pub["settings"])["digest"]
    headline = json.loads(
        (Path(__file__).resolve().parents[3] / "docs/benchmark/headline.json").read_text()
    )
    assert pubmod.compact(headline)["cells"] == pub["cells"]  # the published headline's
    bad = tmp_path / "bad.json"
    pub["cells"]["paper-1000-straight"]["roughness"]["lqr"]["capacity"][0] = -1
    bad.write_text(json.dumps(pub))
    with pytest.raises(pubmod.PublishedDataError, match="bad.json: the capacities of"):
        pubmod.load_published(bad)
