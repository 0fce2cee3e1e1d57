"""The environments keep the conventions Gymnasium's tools rely on: ``render_fps`` is the
rate of the steps (videos play in real time), headless ``"human"`` rendering behaves as
documented, and ``info["speed_kmh"]`` is the speed the observation shows."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest

import hyperloop_env  # noqa: F401  (registration)
from hyperloop_env.env import HyperloopSuspensionEnv
from hyperloop_env.observation import SPEED_SCALE_M_S
from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

ENV_ID = "HyperloopSuspension-v0"


@pytest.mark.parametrize("control_dt_s", [None, 0.0005, 0.0015])
def test_render_fps_is_the_step_rate_so_videos_play_in_real_time(control_dt_s):
    """A video recorder (Gymnasium's ``RecordVideo``) writes one frame per step and plays
    them at ``metadata["render_fps"]``: the video lasts as long as the simulated time."""
    kw = {} if control_dt_s is None else {"control_dt_s": control_dt_s}
    env = gym.make(ENV_ID, render_mode="rgb_array", scenario="paper-1000-straight", **kw)
    dt = env.unwrapped.config.control_dt_s
    assert env.metadata["render_fps"] == 1.0 / dt
    env.reset(seed=0)
    frames = [env.render()]
    for _ in range(30):
        *_, info = env.step(np.zeros(4, np.float32))
        frames.append(env.render())
    video_s = (len(frames) - 1) / env.metadata["render_fps"]
    assert video_s == pytest.approx(info["time_s"], rel=1e-9)
    vec = HyperloopSuspensionVectorEnv(2, "paper-1000-straight", render_mode="rgb_array", **kw)
    assert vec.metadata["render_fps"] == 1.0 / dt
    assert HyperloopSuspensionEnv.metadata["render_fps"] == 1000.0  # the default 1 ms
    env.close()


def _headless(monkeypatch):
    for var in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setattr("sys.platform", "linux")


def test_headless_human_mode_warns_once_and_runs_as_documented(monkeypatch):
    """Without a display, ``render_mode="human"`` warns once (saying to use rgb_array),
    ``render()`` returns None and the episode runs on, as the docstring says."""
    _headless(monkeypatch)
    doc = " ".join(HyperloopSuspensionEnv.__doc__.split())
    assert "Without a display it warns once" in doc
    assert "raises ``RuntimeError`` at the first frame" not in doc
    env = gym.make(ENV_ID, render_mode="human", track_length_m=60.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env.reset(seed=0)
        for _ in range(45):  # the window's refreshes: steps 20 and 40
            env.step(np.zeros(4, np.float32))
        assert env.render() is None
    shown = [w for w in caught if "needs a display" in str(w.message)]
    assert len(shown) == 1 and "rgb_array" in str(shown[0].message)
    env.close()


@pytest.mark.parametrize("mode", ["brake", "accelerate"])
def test_info_speed_is_the_current_speed_under_a_speed_profile(mode):
    """Under ``speed_profile`` the speed changes along the section: ``info["speed_kmh"]``
    follows it as the observation's speed entry does, in the single and the vector env
    (bit for bit alike); at constant speed it is the entry speed exactly."""
    kw = {
        "scenario": "paper-1000-straight",
        "track_length_m": 200.0,
        "disturbances": {"speed_profile": {"severity": 5.0, "mode": mode}},
    }
    env = gym.make(ENV_ID, **kw)
    vec = HyperloopSuspensionVectorEnv(1, **kw)
    at = env.unwrapped.observation_spec.start("speed")
    obs, info = env.reset(seed=0)
    vec.reset(seed=0)
    assert info["speed_kmh"] == 1000.0
    a = np.zeros(4, np.float32)
    for _ in range(300):
        obs, _, _, _, info = env.step(a)
        *_, vinfo = vec.step(a[None])
        seen_kmh = float(obs[at]) * SPEED_SCALE_M_S * 3.6
        assert info["speed_kmh"] == pytest.approx(seen_kmh, rel=1e-6)
        assert vinfo["speed_kmh"][0] == info["speed_kmh"]
    change = info["speed_kmh"] - 1000.0
    expected = 3.6 * 5.0 * info["time_s"] * (1 if mode == "accelerate" else -1)
    assert change == pytest.approx(expected, rel=1e-9)
    steady = gym.make(ENV_ID, scenario="paper-2000-straight")
    steady.reset(seed=0)
    for _ in range(5):
        *_, info = steady.step(a)
        assert info["speed_kmh"] == 2000.0
