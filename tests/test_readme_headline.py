"""The README's headline block is the one docs/benchmark/headline.json gives
(``hyperloop headline`` writes both; a hand edit of either fails here), and the
JSON's numbers are the ones its per-seed capacities give."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from agents.evaluation import capacity_stats as cs

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "benchmark" / "headline.json"


def test_readme_headline_matches_the_json() -> None:
    from agents.evaluation import headline_publish as hp

    doc = json.loads(DOC.read_text())
    text = (ROOT / "README.md").read_text()
    block = text.split(hp.START, 1)[1].split(hp.END, 1)[0]
    assert block.strip() == hp.readme_block(doc).strip()


def test_headline_json_is_complete_and_recomputes() -> None:
    """Every paper condition × family × entrant has its per-seed capacities on the same
    seeds from the evaluation range (an entrant of ``settings.entrant_seeds`` on the first N
    of them); θ and the verdicts (paired on the common seeds) recompute from them."""
    doc = json.loads(DOC.read_text())
    s, h, an = doc["settings"], doc["headline"], doc["analysis"]
    assert len(s["conditions"]) == 4 and len(s["families"]) == 3
    assert s["seeds"] >= 32 and s["seed_range"][0] == 1_000_000
    reduced = s.get("entrant_seeds") or {}
    seeds = list(range(s["seed_range"][0], s["seed_range"][1] + 1))
    assert len(seeds) == s["seeds"]
    n_ent = len(s["entrants"])
    assert len(h["capacities"]) == 4 * 3 * n_ent
    assert h["pairs"] == 4 * 3 * n_ent * (n_ent - 1) // 2
    for cond in s["conditions"]:
        for fam in s["families"]:
            cell = an[cond][fam]
            for lab in s["entrants"]:
                e = cell["entrants"][lab]
                assert e["seeds"] == seeds[: reduced.get(lab)]  # common random numbers
                fit = cs.fit_capacity_lognormal(e["capacity"], e["censored"], n_boot=0)
                if fit["theta"] is not None:
                    assert fit["theta"] == pytest.approx(e["fit"]["theta"], rel=1e-9)
            # the first pair, and the first with an entrant on fewer seeds
            checks = [cell["verdicts"][0]]
            checks += [v for v in cell["verdicts"] if {v["a"], v["b"]} & set(reduced)][:1]
            for v in checks:
                a, b = cell["entrants"][v["a"]], cell["entrants"][v["b"]]
                r = cs.compare_paired(
                    *cs.on_common_seeds(
                        (a["capacity"], a["censored"], a["seeds"]),
                        (b["capacity"], b["censored"], b["seeds"]),
                        v["a"],
                        v["b"],
                    ),
                    n_boot=v["n_boot"],
                    seed=0,
                )
                assert r["verdict"] == v["verdict"] and r["n"] == v["n"]
                if r["ratio"] is not None:
                    assert r["ratio"] == pytest.approx(v["ratio"], rel=1e-12)
    fracs = [v["verdict"] != "undecided" for v in h["verdicts"]]
    assert h["decided"] == int(np.sum(fracs))


def _docs_generators():  # noqa: ANN202
    spec = importlib.util.spec_from_file_location(
        "hyperloop_docs", ROOT / "docs" / "_ext" / "hyperloop_docs.py"
    )
    mod = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(mod)  # type: ignore[union-attr]
    return mod


def test_site_suite_table_is_the_suite_file() -> None:
    """The method page shows the suite table generated from the suite file; the results
    page the leaderboard generated from headline.json (the README's block)."""
    from agents.evaluation.benchmark import load_suite, suite_markdown
    from agents.evaluation.capacity_report import readme_block

    gen = _docs_generators()
    method = (ROOT / "docs" / "method.md").read_text()
    assert method.count("<!-- generated: suite -->") == 1
    assert gen.generated("suite").strip() == suite_markdown(load_suite()).strip()
    results = (ROOT / "docs" / "results.md").read_text()
    assert results.count("<!-- generated: headline -->") == 1
    doc = json.loads(DOC.read_text())
    assert gen.generated("headline").strip() == readme_block(doc).strip()


def test_publishing_validates_the_source_before_touching_docs(tmp_path, capsys) -> None:  # noqa: ANN001
    """A source without headline.csv, or a run that does not cover the four paper
    conditions, or a damaged JSON, is refused before docs/benchmark or the README change."""
    from agents.cli.headline import main

    docs = ROOT / "docs" / "benchmark"
    before = {p: p.stat().st_mtime_ns for p in docs.rglob("*") if p.is_file()}
    readme = (ROOT / "README.md").read_bytes()
    doc = json.loads(DOC.read_text())
    (tmp_path / "headline.md").write_text("x")
    (tmp_path / "headline.json").write_text(json.dumps(doc))
    args = ["--from", str(tmp_path), "--root", str(ROOT)]
    assert main(args) == 2
    assert "headline.csv: missing" in capsys.readouterr().err
    (tmp_path / "headline.csv").write_text("x")
    doc["settings"]["conditions"] = doc["settings"]["conditions"][:1]
    (tmp_path / "headline.json").write_text(json.dumps(doc))
    assert main(args) == 2
    assert "not the four paper conditions" in capsys.readouterr().err
    (tmp_path / "headline.json").write_text("{")
    assert main(args) == 2
    assert "not a capacity headline" in capsys.readouterr().err
    assert {p: p.stat().st_mtime_ns for p in docs.rglob("*") if p.is_file()} == before
    assert (ROOT / "README.md").read_bytes() == readme


def test_cost_table_is_the_commands_output(capsys: pytest.CaptureFixture[str]) -> None:
    """The per-entrant cost table of the performance page (docs/performance.md includes
    docs/benchmark/cost.md) is ``hyperloop compare cost`` of headline.json (every task's
    wall time kept)."""
    from agents.cli.compare import main

    doc = json.loads(DOC.read_text())
    tasks = doc["settings"]["tasks"]
    assert len(tasks) == 4 * len(doc["settings"]["entrants"])
    assert main(["cost", str(DOC)]) == 0
    assert (ROOT / "docs" / "benchmark" / "cost.md").read_text() == capsys.readouterr().out
    page = (ROOT / "docs" / "performance.md").read_text()
    assert "```{include} benchmark/cost.md\n```" in page
