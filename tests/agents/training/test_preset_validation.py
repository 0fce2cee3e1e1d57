"""Presets are checked when they are loaded: an unknown key or a value of the wrong type or
out of bounds is an error naming the key and the preset file, before anything is created
(no run directory, no run_config.json: the corrected command needs no --overwrite)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("stable_baselines3")

from agents.cli import train as cli  # noqa: E402
from agents.training import presets  # noqa: E402

TINY = ["--preset", "tiny", "--no-eval", "--no-progress"]


def _preset(tmp_path: Path, **options: Any) -> Path:
    path = tmp_path / "mine.json"
    path.write_text(json.dumps({**presets.PRESETS["tiny"], **options}))
    return path


BAD_VALUES: list[tuple[str, Any]] = [
    ("activation", "foo"),
    ("n_steps", 0),
    ("batch_size", 0),
    ("learning_rate", "abc"),
    ("learning_rate", 0),
    ("gamma", 5),
    ("gamma", 0),
    ("n_epochs", -1),
    ("n_epochs", 1.5),
    ("clip_range", -1),
    ("sac_buffer_size", -5),
    ("sac_learning_starts", -1),
    ("sac_train_freq", 0),
    ("sac_gradient_steps", 0),
    ("gae_lambda", 1.5),
    ("ent_coef", -0.1),
    ("log_std_init", float("nan")),
    ("norm_reward", "yes"),
    ("eval_episodes", 0),
    ("net_arch", []),
    ("critic_arch", [64, 0]),
    ("timesteps", True),
    ("seed", -1),
    ("env_kwargs", [1, 2]),
    ("ship_name", "../../elsewhere"),
    ("vec", "threads"),
    ("algo", "dqn"),
]


@pytest.mark.parametrize(("key", "value"), BAD_VALUES)
def test_an_invalid_preset_value_is_refused_naming_the_key_and_the_file(
    key: str, value: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _preset(tmp_path, **{key: value})
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as exc:
        cli.main(["--preset", str(path), "--no-eval", "--no-progress", "--out", str(out)])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"option {key!r}" in err and str(path) in err, err
    assert not out.exists()


def test_an_unknown_key_is_refused_naming_it_and_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _preset(tmp_path, learning_rat=0.001)
    with pytest.raises(SystemExit):
        cli.resolve_config(["--preset", str(path), "--no-eval"])
    err = capsys.readouterr().err
    assert "'learning_rat'" in err and str(path) in err


def test_a_named_preset_is_checked_too(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(presets.PRESETS, "broken", {"gamma": 5})
    with pytest.raises(SystemExit):
        cli.resolve_config(["--preset", "broken", "--no-eval"])
    err = capsys.readouterr().err
    assert "'gamma'" in err and str(presets.PRESET_DIR / "broken.json") in err


def test_every_shipped_preset_and_the_defaults_pass_the_checks() -> None:
    assert set(presets.OPTION_CHECKS) == set(presets.DEFAULTS)
    assert presets.defaults() == presets.DEFAULTS
    for name, values in presets.PRESETS.items():
        assert presets.load_preset(name) == values, name


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"batch_size": 1}, "batch_size must be >= 2 for PPO"),
        ({"n_steps": 1, "n_envs": 1}, "n_steps × n_envs (the rollout) must be >= 2"),
    ],
)
def test_ppo_sizes_its_advantage_normalisation_needs(
    options: dict[str, Any], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _preset(tmp_path, **options)
    with pytest.raises(SystemExit):
        cli.resolve_config(["--preset", str(path), "--no-eval"])
    err = capsys.readouterr().err
    assert message in err and str(path) in err
    assert cli.resolve_config(["--preset", str(path), "--no-eval", "--algo", "sac"])


def test_a_configuration_built_in_code_is_checked_as_well() -> None:
    cfg = cli.resolve_config(TINY)
    cfg["clip_range"] = -1
    with pytest.raises(SystemExit):
        cli._validate(cfg, cli.build_parser())


@pytest.mark.parametrize("existing", [False, True])
def test_a_run_refused_at_validation_leaves_the_run_directory_as_it_was(
    existing: bool, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The corrected command then runs without --overwrite."""
    out = tmp_path / "run"
    if existing:
        out.mkdir()
    bad = _preset(tmp_path, activation="foo", timesteps=512, n_envs=2, eval_freq=10**9)
    args = ["--preset", str(bad), "--no-eval", "--no-progress", "--out", str(out)]
    with pytest.raises(SystemExit) as exc:
        cli.main(args)
    assert exc.value.code == 2
    assert "option 'activation'" in capsys.readouterr().err
    assert out.exists() == existing
    assert not existing or not any(out.iterdir())
    bad.write_text(bad.read_text().replace('"foo"', '"relu"'))
    assert cli.main(args) == 0
    assert (out / "model.zip").is_file() and (out / "run_config.json").is_file()
