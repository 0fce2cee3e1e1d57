"""The severity curriculum (the preset option ``curriculum``): each episode's severity drawn
below the current level, the level rising only while the agent holds, the same seed the
same draws, bad records refused by field, and a run's checkpoints keeping the level."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from agents.training.curriculum import SeverityCurriculum, check_curriculum, find_curriculum
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

RECORD = {
    "family": "roughness",
    "start": 0.1,
    "stop": 0.3,
    "step": 0.1,
    "hold": 0.9,
    "window": 4,
    "floor": 0.5,
}


def _env(record: dict, seed: int = 7, n: int = 4) -> SeverityCurriculum:
    venv = HyperloopSuspensionVectorEnv(n, scenario="paper-1000-straight", track_length_m=40.0)
    return SeverityCurriculum(venv, record, seed)


def _amplitudes(cur: SeverityCurriculum) -> np.ndarray:
    return np.array([p.irregularity.amplitude for p in cur.env.params])


def _fly(cur: SeverityCurriculum, episodes: int) -> list[np.ndarray]:
    """Passive flights (zero currents' change) until ``episodes`` have ended; each ended row
    reset through the curriculum as the SB3 adapter does. The amplitudes of every reset."""
    cur.reset(seed=[1, 2, 3, 4])
    seen = [_amplitudes(cur)]
    ended = 0
    zero = np.zeros((cur.num_envs, 4), dtype=np.float32)
    while ended < episodes:
        _, _, term, trunc, _ = cur.step(zero)
        done = term | trunc
        if done.any():
            ended += int(done.sum())
            cur.reset(options={"reset_mask": done})
            seen.append(_amplitudes(cur)[done])
    return seen


def test_episodes_fly_below_the_level_and_the_level_rises_while_the_agent_holds() -> None:
    cur = _env(RECORD)
    seen = _fly(cur, 12)
    first = seen[0]
    assert np.all((first >= 0.05 - 1e-12) & (first <= 0.1 + 1e-12))  # [floor·start, start]
    assert np.all(np.round(first, 3) == first)  # rounded to 0.001
    # passive holds 40 m at these amplitudes: +0.1 after each window of 4 episodes, to stop
    assert [lv for _, lv in cur.history] == pytest.approx([0.1, 0.2, 0.3])
    assert max(np.max(s) for s in seen) <= 0.3 + 1e-12
    assert max(np.max(s) for s in seen) > 0.2  # episodes flew at the raised level


def test_the_level_stays_where_the_agent_touches() -> None:
    rough = {**RECORD, "start": 4.0, "stop": 5.0, "floor": 1.0}  # 4 × German "low": contact
    cur = _env(rough)
    _fly(cur, 8)
    assert cur.level == 4.0 and cur.history == [(0, 4.0)]


def test_the_same_seed_gives_the_same_draws() -> None:
    a, b, c = _env(RECORD, 7), _env(RECORD, 7), _env(RECORD, 8)
    for cur in (a, b, c):
        cur.reset(seed=[1, 2, 3, 4])
    np.testing.assert_array_equal(_amplitudes(a), _amplitudes(b))
    assert not np.array_equal(_amplitudes(a), _amplitudes(c))


def test_resets_may_not_bring_their_own_disturbances() -> None:
    cur = _env(RECORD)
    with pytest.raises(ValueError, match="curriculum's to set"):
        cur.reset(options={"disturbances": [None] * 4})


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"family": "wind"}, "'family'"),
        ({"start": 0.0}, "'start'"),
        ({"stop": 0.05}, "'stop'"),
        ({"hold": 1.5}, "'hold'"),
        ({"window": 0}, "'window'"),
        ({"floor": -0.1}, "'floor'"),
        ({"start": 20.0, "stop": 30.0}, "'start'"),  # beyond roughness's own bound (10)
        ({"extra": 1}, "unknown"),
    ],
)
def test_a_bad_record_names_its_field(change: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        check_curriculum({**RECORD, **change})


def test_state_round_trip_and_a_bad_state() -> None:
    cur = _env(RECORD)
    cur.load_state({"level": 0.25, "history": [[0, 0.1], [512, 0.25]]}, seed=3)
    assert cur.level == 0.25 and cur.state() == {"level": 0.25, "history": [[0, 0.1], [512, 0.25]]}
    with pytest.raises(ValueError, match="level"):
        cur.load_state({"level": 0.9}, seed=3)


def test_a_run_logs_and_checkpoints_its_curriculum_and_a_resume_continues_it(
    tmp_path: Path,
) -> None:
    pytest.importorskip("stable_baselines3")
    from agents.cli import train as cli
    from agents.training import experiment

    out = tmp_path / "run"
    args = ["--preset", "tiny", "--out", str(out), "--no-eval", "--no-progress"]
    cfg = cli.resolve_config([*args, "--timesteps", "1024", "--checkpoint-freq", "512"])
    cfg["curriculum"] = {**RECORD, "window": 1000}  # no rise within this run
    log = experiment.train(cfg)
    assert log["curriculum"]["level"] == 0.1 and log["config"]["curriculum"]["window"] == 1000
    manifests = sorted((out / "checkpoints").glob("model_state_*_steps.json"))
    assert manifests
    last = manifests[-1]
    data = json.loads(last.read_text())
    assert data["curriculum"] == {"level": 0.1, "history": [[0, 0.1]]}
    # the resumed segment starts from the checkpoint's level (changed here to tell)
    data["curriculum"] = {"level": 0.2, "history": [[0, 0.1], [700, 0.2]]}
    last.write_text(json.dumps(data) + "\n")
    cfg2 = cli.resolve_config([*args, "--timesteps", "2048", "--resume"])
    cfg2["curriculum"] = cfg["curriculum"]
    log2 = experiment.train(cfg2)
    assert log2["curriculum"]["level"] == 0.2
    assert log2["curriculum"]["history"][:2] == [[0, 0.1], [700, 0.2]]


def test_find_curriculum_sees_through_the_wrappers() -> None:
    from agents.training.privileged import PrivilegedObservationVecEnv

    cur = _env(RECORD)
    assert find_curriculum(PrivilegedObservationVecEnv(cur)) is cur
    assert find_curriculum(cur.env) is None
