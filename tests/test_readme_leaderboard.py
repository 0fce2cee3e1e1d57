"""The README's leaderboard summary, between ``<!-- leaderboard:start -->`` and
``<!-- leaderboard:end -->``, is exactly what
:func:`agents.evaluation.leaderboard.readme_block` gives for ``docs/leaderboard/``: a hand
edit of the block, or a score admitted to the board without refreshing it, fails here.

``hyperloop leaderboard add`` rewrites the block in a checkout; so does
``python tests/test_readme_leaderboard.py``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
BOARD = ROOT / "docs" / "leaderboard"
START, END = "<!-- leaderboard:start -->", "<!-- leaderboard:end -->"


def _block(text: str) -> str:
    assert text.count(START) == 1 and text.count(END) == 1, "one leaderboard block"
    return text.split(START, 1)[1].split(END, 1)[0]


def _generated(board: Path = BOARD) -> str:
    from agents.evaluation.leaderboard import readme_block

    return "\n" + readme_block(board)


def _is_generated(text: str, board: Path = BOARD) -> bool:
    return _block(text) == _generated(board)


def rewrite(readme: Path = README, board: Path = BOARD) -> None:
    """Replace the README's block by the one the board gives (as ``hyperloop leaderboard
    add`` does in a checkout)."""
    from agents.evaluation.leaderboard import update_readme

    assert update_readme(readme, board)


def test_the_readme_block_is_the_generated_one() -> None:
    assert _is_generated(README.read_text()), (
        "the README's leaderboard block is not readme_block(docs/leaderboard): "
        "run python tests/test_readme_leaderboard.py"
    )


def test_a_hand_edited_block_fails(tmp_path: Path) -> None:
    text = README.read_text()
    block = _block(text)
    rows = [line for line in block.splitlines() if line.startswith("| 1 |")]
    assert len(rows) == 1
    first = rows[0]
    edits = {
        "the rank": block.replace(first, first.replace("| 1 |", "| 2 |", 1), 1),
        "the source": block.replace(first, first.replace("| published |", "| score |"), 1),
        "a row dropped": block.replace(first + "\n", "", 1),
        "the caption": block.replace("Median", "The median", 1),
        "a blank line": block.replace("\n\n", "\n", 1),
    }
    for what, edited in edits.items():
        assert edited != block, what
        copy = text.replace(block, edited)
        assert not _is_generated(copy), what
        # rewriting the copy restores the generated block
        (tmp_path / "README.md").write_text(copy)
        rewrite(tmp_path / "README.md")
        assert (tmp_path / "README.md").read_text() == text, what


def test_an_admitted_score_makes_the_block_stale(tmp_path: Path) -> None:
    from agents.evaluation import leaderboard as lb
    from agents.evaluation.published import BENCHMARK_VERSION, load_published

    pub = load_published()
    board = tmp_path / "board"
    board.mkdir()
    for f in BOARD.glob("*.json"):  # the admitted scores, if any
        (board / f.name).write_text(f.read_text())
    theta = {f"{c}/roughness": 0.5 for c in pub["settings"]["conditions"]}
    entry = {"controller": "my-pd", "benchmark": BENCHMARK_VERSION, "quick": True,
             "fingerprint": pub["fingerprint"]["digest"], "theta": theta}  # fmt: skip
    result = tmp_path / "score.json"
    result.write_text(json.dumps({"controller": "my-pd", "leaderboard": entry}))
    lb.add(result, board)
    text = README.read_text()
    assert not _is_generated(text, board)
    block = lb.readme_block(board)
    assert "`my-pd`" in block and "and 1 scored controller (" in block.splitlines()[0]
    (tmp_path / "README.md").write_text(text)
    rewrite(tmp_path / "README.md", board)
    assert _is_generated((tmp_path / "README.md").read_text(), board)


def test_the_section_says_how_to_join() -> None:
    text = README.read_text()
    section = text.split("## Join the leaderboard", 1)[1].split(START, 1)[0]
    assert "hyperloop score mypkg.mod:make --quick" in section
    assert "hyperloop leaderboard add reports/score/score.json" in section
    assert "(docs/leaderboard.md)" in section
    assert len(text.splitlines()) <= 250


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    rewrite()
    print(f"rewrote the leaderboard block of {README}")
