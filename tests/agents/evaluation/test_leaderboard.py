"""The leaderboard: a score result round-trips into the board; one scored with another
fingerprint, or under a published entrant's name, is refused naming the file."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from agents.evaluation import leaderboard as lb
from agents.evaluation.published import BENCHMARK_VERSION, load_published


def _result(path: Path, name: str, digest: str, theta: float) -> Path:
    pub = load_published()
    cells = {f"{c}/roughness": theta for c in pub["settings"]["conditions"]}
    entry = {"controller": name, "benchmark": BENCHMARK_VERSION, "fingerprint": digest,
             "quick": True, "theta": cells}  # fmt: skip
    path.write_text(json.dumps({"controller": name, "leaderboard": entry}))
    return path


def test_a_score_round_trips_into_the_board(tmp_path: Path) -> None:
    pub = load_published()
    board = tmp_path / "board"
    res = _result(tmp_path / "s.json", "my-pd", pub["fingerprint"]["digest"], 0.9)
    assert lb.add(res, board).name == "my-pd.json"
    text = lb.table(board)
    first = text.splitlines()[2]  # θ = 0.9 everywhere: above every published entrant
    assert "`my-pd`" in first and "0.9" in first and "score (quick)" in first
    assert text.count("| published |") == len(pub["settings"]["entrants"])
    with pytest.raises(lb.LeaderboardError, match="on the board already"):
        lb.add(res, board)
    assert lb.add(res, board, overwrite=True).exists()


def test_a_foreign_fingerprint_or_a_published_name_is_refused(tmp_path: Path) -> None:
    pub = load_published()
    foreign = _result(tmp_path / "f.json", "mine", "0" * 16, 0.5)
    with pytest.raises(lb.LeaderboardError, match=r"f\.json: fingerprint '0+' is not"):
        lb.add(foreign, tmp_path / "board")
    named = _result(tmp_path / "n.json", "lqr", pub["fingerprint"]["digest"], 0.5)
    with pytest.raises(lb.LeaderboardError, match="published entrant's name"):
        lb.add(named, tmp_path / "board")
    (tmp_path / "junk.json").write_text("[1]")
    with pytest.raises(lb.LeaderboardError, match="junk.json: not a score result"):
        lb.add(tmp_path / "junk.json", tmp_path / "board")
    assert not (tmp_path / "board").exists()


def test_the_command_refuses_in_one_line(tmp_path: Path, capsys) -> None:  # noqa: ANN001
    from agents.cli.leaderboard import main

    foreign = _result(tmp_path / "f.json", "mine", "0" * 16, 0.5)
    with pytest.raises(SystemExit) as e:
        main(["add", str(foreign), "--board", str(tmp_path / "b")])
    err = capsys.readouterr().err
    assert e.value.code == 2 and "fingerprint" in err and "Traceback" not in err
    assert main(["show", "--board", str(tmp_path / "b")]) == 0
    assert "`passive`" in capsys.readouterr().out


def test_adding_refreshes_the_readme_block(tmp_path: Path) -> None:
    from agents.cli.leaderboard import main

    pub = load_published()
    readme = tmp_path / "README.md"
    readme.write_text(f"# x\n\n{lb.START}\nold\n{lb.END}\n\nrest\n")
    res = _result(tmp_path / "s.json", "my-pd", pub["fingerprint"]["digest"], 0.9)
    board = tmp_path / "board"
    assert main(["add", str(res), "--board", str(board), "--readme", str(readme)]) == 0
    text = readme.read_text()
    assert "`my-pd`" in text and "old" not in text and text.endswith("\n\nrest\n")
    assert text.split(lb.START)[1].split(lb.END)[0] == "\n" + lb.readme_block(board)
