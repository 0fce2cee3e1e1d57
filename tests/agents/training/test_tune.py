"""The Ray Tune search (agents.training.tune, ``train.py --tune``)."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import pytest

from agents.cli.train import main, resolve_config
from agents.training import tune

REWARDS = {
    "gap_weight": 12.5,
    "guidance_weight": 2.0,
    "comfort_weight": 0.7,
    "current_weight": 0.05,
}
RAY_TUNE_MISSING = "needs Ray Tune (optional extra: pip install -e '.[tune]')"


@pytest.mark.parametrize("space", list(tune.SEARCH_SPACES))
def test_sample_configs_are_reproducible_and_inside_the_space(space: str) -> None:
    a = tune.sample_configs(16, seed=3, space=space)
    assert a == tune.sample_configs(16, seed=3, space=space)
    assert a != tune.sample_configs(16, seed=4, space=space)
    for c in a:
        assert set(c) == set(tune.SEARCH_SPACES[space])
        for name, (kind, vals) in tune.SEARCH_SPACES[space].items():
            if kind == "log":
                assert vals[0] <= c[name] <= vals[1], name
            else:
                assert c[name] in vals, name
    if space.endswith("-memory"):  # every configuration has an observation memory
        assert {c["observation"] for c in a} <= set(tune.OBSERVATIONS)
        assert all(
            tune.apply_config({"n_envs": 4, "batch_size": 64}, c)["env_kwargs"].keys()
            & {"observation_history", "observation_front_preview"}
            for c in a
        )


def test_apply_config_sets_the_observation_memory_and_sac_keys() -> None:
    base = {"algo": "sac", "env_kwargs": {"observation_history": 8}, "net_arch": [64, 64]}
    trial = {**REWARDS, "learning_rate": 5e-4, "width": 256, "observation": "fp"}
    cfg = tune.apply_config(base, trial)
    assert cfg["env_kwargs"]["observation_front_preview"] is True
    assert "observation_history" not in cfg["env_kwargs"]  # the trial's choice replaces it
    assert cfg["net_arch"] == [256, 256] and cfg["learning_rate"] == 5e-4
    assert "n_steps" not in cfg and "batch_size" not in cfg


def test_apply_config_sets_reward_weights_and_ppo_hyperparameters() -> None:
    base = {
        "env_kwargs": {"actuators": "levitation+guidance", "gap_weight": 1.0},
        "n_envs": 4,
        "batch_size": 4096,
        "learning_rate": 3e-4,
        "n_steps": 256,
        "ent_coef": 0.0,
        "net_arch": [64, 64],
    }
    trial = {
        **REWARDS,
        "learning_rate": 5e-4,
        "n_steps": 128,
        "ent_coef": 1e-3,
        "width": 128,
    }
    cfg = tune.apply_config(base, trial)
    assert cfg["env_kwargs"] == {
        "actuators": "levitation+guidance",
        "gap_weight": 12.5,
        "guidance_weight": 2.0,
        "comfort_weight": 0.7,
        "current_weight": 0.05,
    }
    assert (cfg["learning_rate"], cfg["n_steps"], cfg["ent_coef"]) == (5e-4, 128, 1e-3)
    assert cfg["net_arch"] == [128, 128]
    assert cfg["batch_size"] == 128 * 4  # never larger than one rollout
    assert base["env_kwargs"]["gap_weight"] == 1.0  # the preset is not modified


def test_validation_seeds_are_disjoint_from_training_and_evaluation() -> None:
    from agents.evaluation.benchmark import EVAL_SEED0, TRAIN_SEED_LIMIT

    lo = tune.VALIDATION_SEED0
    assert lo > EVAL_SEED0 + 100_000 and lo >= TRAIN_SEED_LIMIT


def test_tune_options_are_checked(capsys: pytest.CaptureFixture[str]) -> None:
    for argv, msg in (
        (["--tune", "--resume"], "--tune excludes"),
        (["--tune", "--algo", "sac"], "does not train --algo sac"),
        (["--tune", "--tune-space", "sac-memory"], "does not train --algo ppo"),
        (["--address", "auto"], "--address is a --tune option"),
        (["--tune", "--tune-trials", "0"], "--tune-trials must be >= 1"),
    ):
        with pytest.raises(SystemExit):
            resolve_config(argv)
        assert msg in capsys.readouterr().err


def test_tune_refuses_a_used_search_directory(tmp_path, capsys) -> None:  # noqa: ANN001
    # train.py checks for Ray Tune before it prepares (and with --overwrite empties) the
    # search directory, so the "not empty" refusal is only reachable with the [tune] extra.
    pytest.importorskip("ray.tune", reason=RAY_TUNE_MISSING)
    (tmp_path / "tune_results.json").write_text("{}")
    rc = main(["--preset", "tiny", "--tune", "--tune-out", str(tmp_path)])
    assert rc == 2
    assert "not empty" in capsys.readouterr().err
    assert (tmp_path / "tune_results.json").read_text() == "{}"


def test_tune_without_ray_refuses_before_touching_the_search_directory(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Without Ray Tune, --tune stops with the install hint before the search directory is
    prepared: even with --overwrite a previous search is not deleted."""
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray -> ImportError
    monkeypatch.setitem(sys.modules, "ray.tune", None)
    (tmp_path / "tune_results.json").write_text("{}")
    rc = main(["--preset", "tiny", "--tune", "--tune-out", str(tmp_path), "--overwrite"])
    assert rc == 2
    assert "--tune needs Ray Tune" in capsys.readouterr().err
    assert (tmp_path / "tune_results.json").read_text() == "{}"


@pytest.mark.slow
def test_search_end_to_end_with_a_local_ray(tmp_path) -> None:  # noqa: ANN001
    pytest.importorskip("ray.tune", reason=RAY_TUNE_MISSING)
    from agents.cli.train import resolve_config as rc

    cfg = rc(["--preset", "tiny", "--tune", "--tune-trials", "2", "--tune-timesteps", "1024"])
    base = {k: v for k, v in cfg.items() if k not in ("tune", "out")}
    res = tune.run_search(
        base,
        2,
        1024,
        tmp_path,
        seed=0,
        workers=2,
        validation={
            "seeds": 2,
            "distance_km": 0.7,
            "conditions": ["paper-1000-straight"],
        },
    )
    assert len(res["trials"]) == 2
    assert all(t["error"] is None for t in res["trials"])
    assert all(math.isfinite(t["score"]) for t in res["trials"])
    best = max(res["trials"], key=lambda t: t["score"])
    assert res["best"]["index"] == best["index"]
    saved = json.loads((tmp_path / "tune_results.json").read_text())
    assert saved["chosen_training_config"]["learning_rate"] == best["learning_rate"]
    assert (tmp_path / "trial_000" / "model.zip").exists()


def test_preset_from_search_takes_the_chosen_configuration(tmp_path, monkeypatch) -> None:  # noqa: ANN001
    from agents.training import presets

    monkeypatch.setattr(presets, "PRESET_DIR", tmp_path)
    (tmp_path / "base.json").write_text(
        json.dumps({"algo": "ppo", "n_envs": 4, "seed": 1, "env_kwargs": {"gap_weight": 1.0}})
    )
    monkeypatch.setitem(presets.PRESETS, "base", json.loads((tmp_path / "base.json").read_text()))
    chosen = {
        "env_kwargs": {"gap_weight": 12.0, "comfort_weight": 0.5},
        "learning_rate": 5e-4,
        "n_steps": 128,
        "ent_coef": 1e-3,
        "net_arch": [128, 128],
        "batch_size": 512,
        "seed": 7,
        "timesteps": 400000,
    }
    res = tmp_path / "tune_results.json"
    res.write_text(json.dumps({"chosen_training_config": chosen}))
    path = tune.preset_from_search(res, "base", "mine", timesteps=6_000_000)
    got = json.loads(path.read_text())
    assert got == {
        "algo": "ppo",
        "n_envs": 4,
        "seed": 1,
        "out": "runs/mine",
        "timesteps": 6_000_000,
        "env_kwargs": chosen["env_kwargs"],
        "learning_rate": 5e-4,
        "n_steps": 128,
        "ent_coef": 1e-3,
        "net_arch": [128, 128],
        "batch_size": 512,
    }


def test_collect_search_recovers_a_stopped_search(tmp_path) -> None:  # noqa: ANN001
    """A search stopped after some trials (machine restart) still yields tune_results.json:
    finished trials keep their scores, the others are marked, the best is a finished one."""
    configs = tune.sample_configs(4, seed=3)
    base = {"timesteps": 1000, "n_envs": 2, "batch_size": 64, "env_kwargs": {}}
    search = tmp_path / "ray" / "search"
    for i, score in ((0, -1.5), (1, -0.7), (2, None)):
        d = search / f"_trial_{i}"
        d.mkdir(parents=True)
        (d / "params.json").write_text(
            json.dumps({"t": {"index": i, "trial": configs[i], "base": base}})
        )
        if score is not None:
            (d / "result.json").write_text(
                json.dumps({"score": score, "train_s": 1.0, "wall_s": 2.0, "details": "{}"}) + "\n"
            )
        else:
            (d / "result.json").write_text("")
    doc = tune.collect_search(tmp_path, trials=4, seed=3)
    assert [r["score"] for r in doc["trials"]][:2] == [-1.5, -0.7]
    assert doc["trials"][2]["error"] == "not finished: the search stopped (started)"
    assert doc["trials"][3]["error"] == "not finished: the search stopped (never started)"
    assert doc["trials"][3]["gap_weight"] == configs[3]["gap_weight"]
    assert doc["trials_finished"] == 2 and doc["best"]["index"] == 1
    assert doc["chosen_training_config"]["learning_rate"] == configs[1]["learning_rate"]
    assert json.loads((tmp_path / "tune_results.json").read_text())["best"]["index"] == 1
    with pytest.raises(ValueError, match="does not match"):
        tune.collect_search(tmp_path, trials=4, seed=4)


def test_score_checkpoints_lists_checkpoints_and_the_final_model(tmp_path) -> None:  # noqa: ANN001
    """hyperloop checkpoints scores every checkpoint and the final model once each, by step
    count (the final model replaces a checkpoint of the same step count)."""
    from agents.training import checkpoint_scores as mod

    ck = tmp_path / "checkpoints"
    ck.mkdir()
    for n in (2_002_944, 1_003_520, 4_096):
        (ck / f"model_{n}_steps.zip").write_bytes(b"")
    (ck / "model_vecnormalize_4096_steps.pkl").write_bytes(b"")
    (tmp_path / "model.zip").write_bytes(b"")
    (tmp_path / "training_log.json").write_text(json.dumps({"num_timesteps": 2_002_944}))
    got = [(s, p.relative_to(tmp_path).as_posix()) for s, p in mod.models(tmp_path)]
    assert got == [
        (4_096, "checkpoints/model_4096_steps.zip"),
        (1_003_520, "checkpoints/model_1003520_steps.zip"),
        (2_002_944, "model.zip"),
    ]


RESIDUAL = {"base": "lqr-preview", "scale": 0.1, "base_kwargs": {}}


def test_apply_config_of_a_residual_trial_sets_its_bound_critic_and_curriculum() -> None:
    base = {"n_envs": 4, "batch_size": 64, "net_arch": [16, 16], "residual": RESIDUAL}
    seen = set()
    for trial in tune.sample_configs(16, seed=5, space="ppo-residual"):
        cfg = tune.apply_config(base, trial)
        assert cfg["residual"] == {**RESIDUAL, "scale": trial["scale"]}
        assert cfg["net_arch"] == [16, 16]  # the preset's actor: not searched here
        assert cfg["privileged_critic"] is trial["privileged_critic"]
        assert cfg["log_std_init"] == trial["log_std_init"]
        assert cfg["curriculum"] == tune.CURRICULA[trial["curriculum"]]
        seen.add((trial["privileged_critic"], trial["curriculum"]))
        from agents.training.presets import check_options

        check_options({k: cfg[k] for k in ("residual", "curriculum", "privileged_critic")}, "t")
    assert len(seen) == 4  # 16 draws reach every combination of the two options
    assert RESIDUAL["scale"] == 0.1  # the preset's record is not changed in place
    with pytest.raises(ValueError, match="option residual"):
        tune.apply_config({"n_envs": 4, "batch_size": 64}, trial)


def test_a_residual_run_is_scored_against_its_base_law(monkeypatch, tmp_path) -> None:  # noqa: ANN001
    calls = []

    def fake(controller, actuators, *args, controller_kwargs=None, **kw):  # noqa: ANN001, ANN202
        calls.append((controller, actuators, controller_kwargs))
        cap = [0.5, 0.6] if controller == "lqr-preview" else [0.55, 0.66]
        return {"paper-1000-straight": {"seeds": [1, 2], "capacity": cap, "censored": [0, 0]}}

    monkeypatch.setattr(tune, "validation_capacities", fake)
    score, details = tune.validation_score(
        tmp_path, "levitation+guidance", residual=RESIDUAL, conditions=("paper-1000-straight",)
    )
    assert [c[0] for c in calls] == ["lqr-preview", tune.RESIDUAL_ENTRY]
    assert calls[1][2] == {"path": str(tmp_path)} and calls[0][1] == "levitation+guidance"
    assert score == pytest.approx(math.log(1.1))
    assert tune.reference_controller(None) == "lqr"
