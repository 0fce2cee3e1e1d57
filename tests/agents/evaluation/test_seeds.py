"""Seeds of the evaluation CLIs (agents.evaluation.seeds): the evaluation range by default,
``--seed0`` / ``--seed-list`` honoured, learned agents refused on training seeds unless
``--allow-training-seeds``. The CLIs' plans are checked without running a simulation (the
function each ``main`` hands its seeds to is replaced by one that records them)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from agents.cli import benchmark as benchmark_cli
from agents.cli import evaluate as evaluate_cli
from agents.cli import fragility as fragility_cli
from agents.cli import paper as paper_cli
from agents.evaluation import benchmark as bm
from agents.evaluation import benchmark_report
from agents.evaluation import evaluate as ev
from agents.evaluation import fragility as fr
from agents.evaluation import reproduce_paper as rp
from agents.evaluation import seeds as sd

E0 = sd.EVAL_SEED0


class _Called(Exception):
    """Raised by the stand-in of the function a CLI runs: carries its arguments."""

    def __init__(self, args: tuple[Any, ...], kwargs: dict[str, Any]) -> None:
        super().__init__("called")
        self.args_, self.kwargs = args, kwargs


def _record(*args: Any, **kwargs: Any) -> Any:
    raise _Called(args, kwargs)


def _in_eval_range(seeds: list[int]) -> bool:
    lo, hi = sd.SEED_RANGES["evaluation"]
    return all(lo <= s <= hi for s in seeds)


# ---- the helpers ----------------------------------------------------------------------------


def test_seed_constants_are_shared_with_the_benchmark() -> None:
    assert bm.EVAL_SEED0 == sd.EVAL_SEED0 == 1_000_000
    assert bm.TRAIN_SEED_LIMIT == sd.TRAIN_SEED_LIMIT == 100_000
    assert bm.SEED_RANGES is sd.SEED_RANGES
    assert bm.VALIDATION_SEED0 == 2_000_000 and bm.CALIBRATION_SEED0 == 3_000_000


def test_seed_list_default_seed0_and_explicit() -> None:
    assert sd.seed_list(3) == [E0, E0 + 1, E0 + 2]
    assert sd.seed_list(2, 5) == [5, 6]
    assert sd.seed_list(9, 5, [7, 3]) == [7, 3]  # the explicit list replaces the count
    assert sd.resolve(2) == [E0, E0 + 1] and sd.resolve([4, 0]) == [4, 0]
    assert sd.resolve(range(3), 9) == [0, 1, 2]


@pytest.mark.parametrize(
    ("call", "msg"),
    [
        (lambda: sd.seed_list(0), "--seeds must be an integer >= 1"),
        (lambda: sd.seed_list(1, min_n=2), "--seeds must be an integer >= 2"),
        (lambda: sd.seed_list(2, -1), "--seed0 must be an integer >= 0"),
        (lambda: sd.seed_list(1, 0, []), "--seed-list must not be empty"),
        (lambda: sd.seed_list(1, 0, [3, 4, 3]), "--seed-list must hold distinct seeds"),
        (lambda: sd.seed_list(1, 0, [1, -2]), "--seed-list must hold non-negative"),
        (lambda: sd.seed_list(1, 0, [1], min_n=2), "--seed-list needs at least 2"),
        (lambda: sd.resolve(0), "seeds must be an integer >= 1"),
        (lambda: sd.resolve([]), "seeds must not be empty"),
        (lambda: sd.resolve(2, -5), "seed0 must be an integer >= 0"),
    ],
)
def test_seed_list_validation_names_the_flag(call: Any, msg: str) -> None:
    with pytest.raises(ValueError, match=msg):
        call()


def test_learned_agents_are_refused_on_training_seeds(tmp_path: Path) -> None:
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "model.zip").write_bytes(b"")
    for c in ("ppo", "ppo-guidance", "sac", str(tmp_path / "run"), "runs/x/model_100_steps.zip"):
        assert sd.is_learned(c), c
    for c in ("passive", "pid", "lqr", "pid+g", str(tmp_path)):
        assert not sd.is_learned(c), c
    with pytest.raises(ValueError) as exc:
        sd.check_evaluation_seeds(["pid", "ppo"], [0, 1, 2, 3, E0], False)
    msg = str(exc.value)
    assert "\n" not in msg and "--allow-training-seeds" in msg and "ppo" in msg
    assert "training range (< 100000)" in msg and "pid" not in msg.split("agent(s)")[1]
    sd.check_evaluation_seeds(["ppo"], [0, 1], True)  # allowed
    sd.check_evaluation_seeds(["ppo"], [sd.TRAIN_SEED_LIMIT, E0], False)  # outside
    sd.check_evaluation_seeds(["passive", "pid+g"], [0, 1], False)  # no learned agent
    with pytest.raises(ValueError, match="allow_training_seeds=True"):
        sd.check_evaluation_seeds(["ppo"], [5], False, names=sd.API_NAMES)


# ---- python -m agents.evaluate --------------------------------------------------------------


def _evaluate_main(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, *argv: str
) -> tuple[list[int], dict[str, Any]]:
    monkeypatch.setattr(ev, "evaluate", _record)
    with pytest.raises(_Called) as c:
        evaluate_cli.main(
            [
                "--controllers",
                "passive",
                "--scenarios",
                "paper-1000-straight",
                "--out",
                str(tmp_path / "r"),
                "--no-progress",
                *argv,
            ]
        )
    return c.value.args_[3], c.value.kwargs


def test_evaluate_cli_seeds(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    seeds, kw = _evaluate_main(monkeypatch, tmp_path)
    assert seeds == [E0] and _in_eval_range(seeds) and kw["allow_training_seeds"] is False
    assert _evaluate_main(monkeypatch, tmp_path, "--seeds", "3")[0] == [E0, E0 + 1, E0 + 2]
    assert _evaluate_main(monkeypatch, tmp_path, "--seeds", "2", "--seed0", "7")[0] == [7, 8]
    assert _evaluate_main(monkeypatch, tmp_path, "--seed-list", "9", "4")[0] == [9, 4]
    with pytest.raises(SystemExit) as exc:
        _evaluate_main(monkeypatch, tmp_path, "--seed0", "3", "--seed-list", "4")
    assert exc.value.code == 2 and "not allowed with argument" in capsys.readouterr().err
    # a learned agent on training seeds: refused naming the flag, allowed with it
    with pytest.raises(SystemExit) as exc:
        _evaluate_main(monkeypatch, tmp_path, "--controllers", "ppo", "--seed0", "0")
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "--allow-training-seeds" in err and "training range" in err
    seeds, kw = _evaluate_main(
        monkeypatch, tmp_path, "--controllers", "ppo", "--seed0", "0", "--allow-training-seeds"
    )
    assert seeds == [0] and kw["allow_training_seeds"] is True
    assert _evaluate_main(monkeypatch, tmp_path, "--controllers", "ppo")[0] == [E0]
    with pytest.raises(SystemExit):
        _evaluate_main(monkeypatch, tmp_path, "--seed-list", "1", "1")
    assert "--seed-list must hold distinct seeds" in capsys.readouterr().err


def test_evaluate_api_default_and_refusal() -> None:
    with pytest.raises(ValueError, match="allow_training_seeds=True"):
        ev.evaluate(["ppo"], ["paper-1000-straight"], 0.05, [0], out_dir=None, progress=False)
    with pytest.raises(ValueError, match="seed0 must be"):
        ev.evaluate(["passive"], ["paper-1000-straight"], 0.05, 1, seed0=-1, out_dir=None)


# ---- python -m agents.fragility -------------------------------------------------------------


def _fragility_main(
    monkeypatch: pytest.MonkeyPatch, *argv: str
) -> tuple[list[int], dict[str, Any]]:
    monkeypatch.setattr(fr, "fragility", _record)
    with pytest.raises(_Called) as c:
        fragility_cli.main(
            ["--controllers", "passive", "--levels", "0.1", "0.2", "--no-progress", *argv]
        )
    return c.value.args_[4], c.value.kwargs


def test_fragility_cli_seeds(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    seeds, kw = _fragility_main(monkeypatch)
    assert seeds == list(range(E0, E0 + 10)) and kw["allow_training_seeds"] is False
    assert _fragility_main(monkeypatch, "--seeds", "3", "--seed0", "0")[0] == [0, 1, 2]
    assert _fragility_main(monkeypatch, "--seed-list", "11", "5", "8")[0] == [11, 5, 8]
    with pytest.raises(SystemExit) as exc:
        _fragility_main(monkeypatch, "--controllers", "pid", "ppo", "--seed-list", "0", "1")
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "--allow-training-seeds" in err and "ppo" in err
    seeds, kw = _fragility_main(
        monkeypatch, "--controllers", "ppo", "--seed-list", "0", "1", "--allow-training-seeds"
    )
    assert seeds == [0, 1] and kw["allow_training_seeds"] is True
    with pytest.raises(SystemExit):
        _fragility_main(monkeypatch, "--seed0", "-3")
    assert "--seed0 must be an integer >= 0" in capsys.readouterr().err


def test_fragility_api_default_and_refusal() -> None:
    args = (
        ["passive"],
        ["paper-1000-straight"],
        "roughness",
        [0.1],
        3,
        0.05,
        "repelling",
        0.0,
        16,
        1000,
        "exact",
    )
    assert fr.check_args(*args)[2] == [E0, E0 + 1, E0 + 2]
    assert fr.check_args(*args, seed0=40)[2] == [40, 41, 42]
    with pytest.raises(ValueError, match="training range"):
        fr.fragility(
            ["ppo"],
            ["paper-1000-straight"],
            "roughness",
            [0.1],
            seeds=[3],
            distance_km=0.05,
            progress=False,
        )


# ---- python -m agents.benchmark -------------------------------------------------------------


def _benchmark_main(
    monkeypatch: pytest.MonkeyPatch, *argv: str
) -> tuple[list[int], dict[str, Any]]:
    monkeypatch.setattr(bm, "run_benchmark", _record)
    with pytest.raises(_Called) as c:
        benchmark_cli.main(["--no-progress", *argv])
    return c.value.args_[3], c.value.kwargs


def test_benchmark_cli_seeds(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    seeds, kw = _benchmark_main(monkeypatch)  # default entrants include ppo, ppo-guidance
    assert seeds == list(range(E0, E0 + bm.DEFAULT_SEEDS)) and _in_eval_range(seeds)
    assert kw["allow_training_seeds"] is False
    assert _benchmark_main(monkeypatch, "--seeds", "2", "--seed0", "5000000")[0] == [
        5_000_000,
        5_000_001,
    ]
    assert _benchmark_main(monkeypatch, "--entrants", "passive", "pid+g", "--seed-list", "3", "1")[
        0
    ] == [3, 1]
    with pytest.raises(SystemExit) as e:
        benchmark_cli.main(["--entrants", "passive", "ppo-guidance", "--seed0", "0"])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "--allow-training-seeds" in err and "ppo-guidance" in err and "passive" not in err
    seeds, kw = _benchmark_main(
        monkeypatch, "--entrants", "ppo", "--seed0", "0", "--allow-training-seeds"
    )
    assert seeds[:2] == [0, 1] and kw["allow_training_seeds"] is True
    with pytest.raises(SystemExit) as e:
        benchmark_cli.main(["--seeds", "1"])
    assert e.value.code == 2
    assert "--seeds must be an integer >= 2" in capsys.readouterr().err


def test_benchmark_api_refusal_and_settings_seeds() -> None:
    with pytest.raises(ValueError, match="allow_training_seeds=True"):
        bm.run_benchmark(["ppo"], ["paper-1000-straight"], seeds=[0, 1], distance_km=0.05)
    with pytest.raises(ValueError, match="seeds must be an integer >= 2"):
        bm.run_benchmark(["passive"], ["paper-1000-straight"], seeds=1, distance_km=0.05)
    assert bm.settings_seeds({"seed_range": [E0, E0 + 2]}) == [E0, E0 + 1, E0 + 2]
    assert bm.settings_seeds({"seed_range": [1, 9], "seed_list": [9, 1]}) == [9, 1]
    assert (
        benchmark_report._seed_text({"seed_range": [E0, E0 + 7]})
        == f"evaluation range, {E0}–{E0 + 7}"
    )
    assert (
        benchmark_report._seed_text({"seed_range": [0, 9], "seed_list": [9, 0]})
        == "training range, 9, 0"
    )


# ---- python -m agents.reproduce_paper -------------------------------------------------------


def _reproduce_main(monkeypatch: pytest.MonkeyPatch, tmp_path: Path, *argv: str) -> list[int]:
    monkeypatch.setattr(rp, "_reproduce", _record)
    with pytest.raises(_Called) as c:
        paper_cli.main(["--out", str(tmp_path / "paper"), "--no-progress", *argv])
    return list(c.value.args_[0].seeds)


def test_reproduce_paper_cli_seeds(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert _reproduce_main(monkeypatch, tmp_path) == [E0]
    assert _reproduce_main(monkeypatch, tmp_path, "--seeds", "2", "--seed0", "0") == [0, 1]
    assert _reproduce_main(monkeypatch, tmp_path, "--seed-list", "8", "2") == [8, 2]
    assert set(rp.CONTROLLERS) == {"passive", "pid", "lqr"}  # no learned agent: no refusal
    with pytest.raises(SystemExit) as exc:
        _reproduce_main(monkeypatch, tmp_path, "--seeds", "0")
    assert exc.value.code == 2 and "--seeds must be" in capsys.readouterr().err
