"""``hyperloop score``'s ride comfort: the published entrants' a_wz that ship with the
package (what ``hyperloop headline --comfort`` flies, checked against the independent
``hyperloop compare comfort`` file and re-flown for guided entrants), the pairing of a
scored controller's a_wz with every entrant's on the same seeds (against a hand-computed
expectation: seeds matched by value, touched runs out of both sides), its Markdown, and
the refusals naming the file and the field. The scored flight itself is pinned by the
twin test of ``test_score.py`` (the LQR under another name rides exactly as ``lqr``)."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import pytest

from agents.evaluation import published as pubmod
from agents.evaluation import score as sc
from agents.evaluation.capacity_benchmark import DEFAULT_ENTRANTS
from agents.evaluation.score_report import comfort_markdown

ROOT = Path(__file__).resolve().parents[3]
COMPARE_COMFORT = ROOT / "docs" / "benchmark" / "comfort" / "comfort.json"


@pytest.fixture(scope="module")
def published() -> dict:
    return pubmod.load_published()


@pytest.fixture(scope="module")
def ride(published: dict) -> dict:
    return pubmod.load_published_comfort(published=published)


# --------------------------------------------------------------------------------------
# the published data
# --------------------------------------------------------------------------------------


def test_every_published_entrant_has_its_ride_on_every_seed(published: dict, ride: dict) -> None:
    st = published["settings"]
    assert ride["entrants"] == st["entrants"] == list(DEFAULT_ENTRANTS)  # the headline's
    assert {"pid+g", "lqr+g", "lqr-preview+g", "passive", "pid"} <= set(ride["entrants"])
    assert ride["conditions"] == st["conditions"]
    assert ride["seeds"] == list(range(st["seed_range"][0], st["seed_range"][1] + 1))
    assert len(ride["seeds"]) == 32 and ride["distance_km"] == st["distance_km"] == 3.0
    assert ride["fingerprint"] == published["fingerprint"]["digest"]
    for cond in st["conditions"]:
        for lab in st["entrants"]:
            vals = ride["a_wz_m_s2"][cond][lab]
            assert len(vals) == 32 and all(v is None or 0 < v < 20 for v in vals), (cond, lab)
    # its provenance: the one command, when and where it ran
    assert ride["command"] == "hyperloop headline --comfort"
    assert ride["date"][:4].isdigit() and ride["machine"]["cpus"] >= 1


def test_the_published_ride_is_the_compare_comfort_one(ride: dict) -> None:
    """``hyperloop compare comfort`` flew seven of the entrants on the same seeds
    (docs/benchmark/comfort; mpc-preview is no entrant): the same a_wz, seed by seed."""
    other = json.loads(COMPARE_COMFORT.read_text())
    assert other["seeds"] == [ride["seeds"][0], ride["seeds"][-1]]
    common = 0
    for cond, by in other["a_wz_per_seed"].items():
        for lab, vals in by.items():
            if lab in ride["entrants"]:
                assert ride["a_wz_m_s2"][cond][lab] == pytest.approx(vals, rel=1e-6), lab
                common += 1
    assert common == 4 * 7


def test_guided_entrants_re_fly_their_published_ride(ride: dict) -> None:
    """``name+g`` flies the guidance currents too, a learned agent its own actuator set
    (a levitation-only flight of either would differ or fail)."""
    from agents.evaluation.comparisons.comfort import a_wz

    cond, seeds = "paper-2000-curved", ride["seeds"][:2]
    for lab in ("pid+g", "ppo-guidance"):
        got = a_wz(lab, cond, seeds, ride["distance_km"])
        assert got == pytest.approx(ride["a_wz_m_s2"][cond][lab][:2], rel=1e-9), lab
    assert a_wz("pid", cond, seeds, ride["distance_km"]) != pytest.approx(
        ride["a_wz_m_s2"][cond]["pid+g"][:2], rel=1e-3
    )


def _damaged(ride: dict, tmp_path: Path, edit) -> Path:  # noqa: ANN001
    doc = copy.deepcopy(ride)
    edit(doc)
    path = tmp_path / "comfort.json"
    path.write_text(json.dumps(doc))
    return path


def test_damaged_ride_data_is_refused_naming_the_file_and_field(
    published: dict, ride: dict, tmp_path: Path
) -> None:
    cond = published["settings"]["conditions"][0]

    def negative(d: dict) -> None:
        d["a_wz_m_s2"][cond]["lqr"][3] = -1.0

    def short(d: dict) -> None:
        d["a_wz_m_s2"][cond]["pid+g"].pop()

    def lost(d: dict) -> None:
        del d["a_wz_m_s2"][cond]["passive"]

    def other_seeds(d: dict) -> None:
        d["seeds"] = [s + 1 for s in d["seeds"]]

    def other_fingerprint(d: dict) -> None:
        d["fingerprint"] = "0" * 16

    def no_date(d: dict) -> None:
        del d["date"]

    cases = {
        negative: rf"comfort.json: a_wz_m_s2.{cond}.lqr\[3\] is -1.0",
        short: rf"comfort.json: a_wz_m_s2.{cond}.pid\+g has 31 values for 32 seeds",
        lost: rf"comfort.json: no a_wz_m_s2.{cond}.passive",
        other_seeds: r"comfort.json: seeds is .* the published capacities'",
        other_fingerprint: r"comfort.json: fingerprint is '0+', .*hyperloop headline --comfort",
        no_date: r"comfort.json: no 'date'",
    }
    for edit, message in cases.items():
        with pytest.raises(pubmod.PublishedDataError, match=message):
            pubmod.load_published_comfort(_damaged(ride, tmp_path, edit), published)
    with pytest.raises(pubmod.PublishedDataError, match="none.json: no published ride comfort"):
        pubmod.load_published_comfort(tmp_path / "none.json")


def test_the_headline_command_writes_the_ride_of_a_published_table(
    published: dict, ride: dict, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``hyperloop headline --comfort`` into a checkout whose published table has two
    entrants, one condition and two seeds: their rides, as the shipped file has them."""
    from agents.cli.headline import main

    small = copy.deepcopy(published)
    st = small["settings"]
    cond, labs = "paper-2000-straight", ["lqr", "pid+g"]
    st.update(conditions=[cond], entrants=labs, seed_range=[st["seed_range"][0]] * 2)
    st.update(seeds=2, entrant_seeds={})
    st["seed_range"][1] += 1
    if st.get("seed_list"):  # a run that records its seeds as a list (every run since v1)
        st["seed_list"] = st["seed_list"][:2]
    small["cells"] = {
        cond: {
            fam: {lab: {k: v[:2] if isinstance(v, list) else v for k, v in e.items()}
                  for lab, e in by.items() if lab in labs}
            for fam, by in small["cells"][cond].items()
        }
    }  # fmt: skip
    small["fingerprint"] = pubmod.fingerprint(st)
    rel = pubmod.PUBLISHED_FILE.relative_to(ROOT)
    (tmp_path / rel).parent.mkdir(parents=True)
    (tmp_path / rel).write_text(json.dumps(small))
    (tmp_path / "README.md").write_text("a checkout\n")
    assert main(["--comfort", "--root", str(tmp_path)]) == 0
    written = tmp_path / pubmod.COMFORT_FILE.relative_to(ROOT)
    assert f"{written} written" in capsys.readouterr().out
    doc = pubmod.load_published_comfort(written, pubmod.load_published(tmp_path / rel))
    assert doc["command"] == f"hyperloop headline --comfort --root {tmp_path}"
    assert doc["entrants"] == labs and doc["seeds"] == ride["seeds"][:2]
    for lab in labs:
        assert doc["a_wz_m_s2"][cond][lab] == pytest.approx(
            ride["a_wz_m_s2"][cond][lab][:2], rel=1e-9
        )
    # another fingerprint: refused before any run, naming the components
    small["fingerprint"] = {**small["fingerprint"], "model": "0" * 16}
    (tmp_path / rel).write_text(json.dumps(small))
    assert main(["--comfort", "--root", str(tmp_path)]) == 2
    assert "differs from the published benchmark" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["--comfort", "--from", str(tmp_path), "--root", str(tmp_path)])
    assert "no --from" in capsys.readouterr().err


# --------------------------------------------------------------------------------------
# the pairing
# --------------------------------------------------------------------------------------

SEEDS = [30, 31, 32, 33, 34, 35, 36, 37, 38, 39]
"""The synthetic published ride's seeds; it lists them shuffled (below)."""
SCORED = [37, 31, 33, 35, 30, 39, 32, 34]
"""The scored seeds: a subset, in another order."""


def _mine(seed: int) -> float | None:
    return None if seed == 33 else 1.0 + 0.1 * (seed - 30)


THEIRS = {
    "same": lambda s: _mine(s),
    "smoother-one": lambda s: None if s == 35 else 1.3 * (1.0 + 0.1 * (s - 30)),
    "rougher-one": lambda s: (1.0 + 0.1 * (s - 30)) / (1.6 + 0.01 * (s % 3)),
    "always-touched": lambda s: None,
}
"""Each entrant's a_wz as a function of the seed (None: touched)."""


def _synthetic() -> dict:
    order = [36, 30, 39, 33, 31, 38, 35, 32, 37, 34]
    assert sorted(order) == SEEDS
    per = {lab: [f(s) for s in order] for lab, f in THEIRS.items()}
    return {"seeds": order, "distance_km": 0.5, "settle_s": 1.0, "command": "x",
            "date": "d", "machine": {}, "a_wz_m_s2": {"c1": per, "c2": per}}  # fmt: skip


def _expected(lab: str) -> dict:
    """The pair by hand: the seeds where neither side touched, the geometric mean of the
    ratios, the entrant's mean over its runs that did not touch."""
    kept = [s for s in SCORED if _mine(s) is not None and THEIRS[lab](s) is not None]
    logs = [math.log(_mine(s) / THEIRS[lab](s)) for s in kept]
    theirs = [THEIRS[lab](s) for s in SCORED if THEIRS[lab](s) is not None]
    return {
        "n": len(kept),
        "ratio": math.exp(sum(logs) / len(logs)) if logs else None,
        "a_wz_mean_m_s2": sum(theirs) / len(theirs) if theirs else None,
        "contacts": sum(THEIRS[lab](s) is None for s in SCORED),
    }


def test_the_pairing_is_by_seed_and_leaves_touched_runs_out_of_both_sides() -> None:
    mine = {c: [_mine(s) for s in SCORED] for c in ("c1", "c2")}
    cells = sc.comfort_cells(_synthetic(), mine, SCORED, list(THEIRS))
    assert [c["condition"] for c in cells] == ["c1", "c2"]
    for cell in cells:
        assert cell["a_wz_m_s2"] == mine["c1"] and cell["contacts"] == 1
        assert cell["a_wz_mean_m_s2"] == pytest.approx(
            sum(v for v in mine["c1"] if v is not None) / 7
        )
        by = {v["entrant"]: v for v in cell["verdicts"]}
        assert list(by) == list(THEIRS)
        for lab, v in by.items():
            want = _expected(lab)
            assert v["n"] == want["n"] and v["contacts"] == want["contacts"], lab
            for key, rel in (("ratio", 1e-12), ("a_wz_mean_m_s2", 1e-6)):
                if want[key] is None:  # no seed left to pair, or every run touched
                    assert v[key] is None, (lab, key)
                else:
                    assert v[key] == pytest.approx(want[key], rel=rel), (lab, key)
        assert by["same"]["n"] == 7 and by["same"]["ratio"] == pytest.approx(1.0)
        assert by["same"]["verdict"] == "equivalent"
        assert by["smoother-one"]["n"] == 6 and by["smoother-one"]["verdict"] == "smoother"
        assert by["smoother-one"]["hi"] < 1 and by["rougher-one"]["lo"] > 1
        assert by["rougher-one"]["verdict"] == "rougher"
        assert by["always-touched"] == {
            "entrant": "always-touched", "a_wz_mean_m_s2": None, "contacts": 8, "n": 0,
            "ratio": None, "lo": None, "hi": None, "p_value": None, "verdict": "undecided",
        }  # fmt: skip


def test_the_pairing_refuses_seeds_and_entrants_it_does_not_have() -> None:
    mine = {"c1": [1.0] * 3}
    with pytest.raises(pubmod.PublishedDataError, match=r"has no seeds \[99\]"):
        sc.comfort_cells(_synthetic(), mine, [30, 31, 99], ["same"])
    with pytest.raises(pubmod.PublishedDataError, match="has no c1 × nobody"):
        sc.comfort_cells(_synthetic(), mine, [30, 31, 32], ["nobody"])
    with pytest.raises(ValueError, match="c1: 3 a_wz values for 2 seeds"):
        sc.comfort_cells(_synthetic(), mine, [30, 31], ["same"])


def test_the_comfort_section_of_the_markdown() -> None:
    mine = {"c1": [_mine(s) for s in SCORED]}
    ride = sc.comfort_result(_synthetic(), mine, SCORED, list(THEIRS), wall_s=1.0)
    assert ride["summary"] == {"smoother": 1, "equivalent": 1, "rougher": 1, "undecided": 1}
    assert ride["seeds"] == [37, 34] and ride["n_seeds"] == 8 and ride["distance_km"] == 0.5
    lines = "".join(comfort_markdown({"controller": "mine", "quick": True, "comfort": ride}))
    lines = lines.splitlines()
    assert lines[0] == "" and lines[1] == "## Ride comfort against the published entrants"
    assert ride["published_seeds"] == 10
    assert "8 seeds (37–34; --quick: the first 8 of the 10 published) × 0.5 km" in lines[3]
    table = [ln for ln in lines if ln.startswith("| c1 |")]
    assert table[0] == "| c1 | **mine** | 1.4000 (1 touched) | — |  |"
    v = {r["entrant"]: r for r in ride["cells"][0]["verdicts"]}["rougher-one"]
    assert table[3] == (
        f"| c1 | rougher-one | {v['a_wz_mean_m_s2']:.4f} | {v['ratio']:.3f} "
        f"[{v['lo']:.3f}, {v['hi']:.3f}] | rougher |"
    )
    assert table[4] == "| c1 | always-touched | n/a (8 touched) | — | undecided |"
    assert lines[-1] == (
        "`mine` rides smoother than 1, equivalent to 1, rougher than 1 and undecided "
        "against 1 of the 4 entrant × condition pairs."
    )


def test_the_leaderboard_page_shows_the_published_ride(ride: dict) -> None:
    import importlib.util

    spec = importlib.util.spec_from_file_location("docs_ext", ROOT / "docs/_ext/hyperloop_docs.py")
    assert spec is not None and spec.loader is not None
    ext = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ext)
    assert "<!-- generated: published-comfort -->" in (ROOT / "docs/leaderboard.md").read_text()
    block = ext.generated("published-comfort")
    assert "`hyperloop headline --comfort`" in block and "over 32 seeds" in block
    cond = ride["conditions"][0]
    for lab in ride["entrants"]:
        vals = [v for v in ride["a_wz_m_s2"][cond][lab] if v is not None]
        assert f"| `{lab}` | {sum(vals) / len(vals):.3f} |" in block, lab


def test_the_ride_table_on_workers_re_flies_the_published_ride(ride: dict) -> None:
    """The comfort runs of ``hyperloop score``, ``compare comfort`` and ``headline
    --comfort`` as tasks on two worker processes: each entrant and condition gets its own
    published a_wz back (the values differ between them, so a mixed-up order fails), and
    each condition is logged once when done."""
    from agents.evaluation.comparisons.comfort import ride_table

    conds, labs, seeds = (
        ["paper-1000-straight", "paper-2000-curved"],
        ["pid", "lqr+g"],
        ride["seeds"][:2],
    )
    lines: list[str] = []
    per, wall_s = ride_table(conds, labs, seeds, ride["distance_km"], workers=2, log=lines.append)
    assert list(per) == conds and all(list(per[c]) == labs for c in conds)
    for c in conds:
        for lab in labs:
            assert per[c][lab] == pytest.approx(ride["a_wz_m_s2"][c][lab][:2], rel=1e-9), (c, lab)
    assert sorted(line.split(":")[0] for line in lines) == sorted(conds) and wall_s > 0
