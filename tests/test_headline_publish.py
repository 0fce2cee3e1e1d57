"""``hyperloop headline --from``: a source is validated whole before docs/benchmark/ or
the README is touched; a good one is published whole (files, figures, cost table, the
README's block)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs" / "benchmark"


def _publish(root: Path, src: Path) -> int:
    from agents.cli.headline import main

    return main(["--from", str(src), "--root", str(root)])


def _site(tmp_path: Path) -> Path:
    """A copy of what the script publishes into: the README and docs/benchmark/'s report."""
    root = tmp_path / "site"
    docs = root / "docs" / "benchmark"
    docs.mkdir(parents=True)
    shutil.copy2(ROOT / "README.md", root / "README.md")
    for name in ("headline.md", "headline.json", "headline.csv", "cost.md"):
        shutil.copy2(DOCS / name, docs / name)
    shutil.copytree(DOCS / "figures", docs / "figures")
    return root


def _source(tmp_path: Path) -> Path:
    src = tmp_path / "src"
    src.mkdir()
    for name in ("headline.md", "headline.json", "headline.csv"):
        shutil.copy2(DOCS / name, src / name)
    shutil.copytree(DOCS / "figures", src / "figures")
    return src


def _snapshot(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in root.rglob("*") if p.is_file()}


@pytest.mark.parametrize(
    "damage",
    ["tasks without seeds", "capacities not a list", "no figures", "entrants missing"],
)
def test_a_malformed_source_touches_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], damage: str
) -> None:
    root = _site(tmp_path)
    src = _source(tmp_path)
    doc = json.loads((src / "headline.json").read_text())
    if damage == "tasks without seeds":
        for t in doc["settings"]["tasks"]:
            t.pop("seeds")
    elif damage == "capacities not a list":
        doc["headline"]["capacities"] = {"x": 1}
    elif damage == "entrants missing":
        doc["settings"].pop("entrants")
    else:
        shutil.rmtree(src / "figures")
    (src / "headline.json").write_text(json.dumps(doc))
    before = _snapshot(root)
    assert _publish(root, src) == 2
    err = capsys.readouterr().err
    assert "left as it was" in err or "not a capacity headline" in err
    assert "Traceback" not in err
    assert _snapshot(root) == before


def test_a_good_source_is_published_whole(tmp_path: Path) -> None:
    root = _site(tmp_path)
    docs = root / "docs" / "benchmark"
    (docs / "figures" / "stale.png").write_bytes(b"old")
    (docs / "headline.md").write_text("old\n")
    before_readme = (root / "README.md").read_text()
    assert _publish(root, _source(tmp_path)) == 0
    assert (docs / "headline.md").read_bytes() == (DOCS / "headline.md").read_bytes()
    assert not (docs / "figures" / "stale.png").exists()
    assert sorted(p.name for p in (docs / "figures").iterdir()) == sorted(
        p.name for p in (DOCS / "figures").iterdir()
    )
    assert (docs / "cost.md").read_text() == (DOCS / "cost.md").read_text()
    assert (root / "README.md").read_text() == before_readme  # the same headline, same block
    assert not [p for p in docs.iterdir() if p.name.startswith(".")]
    from agents.evaluation.published import PUBLISHED_FILE, load_published

    data = load_published(root / PUBLISHED_FILE.relative_to(ROOT))
    assert data["cells"] == load_published()["cells"]  # what score pairs with, from the run
