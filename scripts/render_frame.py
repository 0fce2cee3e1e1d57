#!/usr/bin/env python
"""Render one frame of the passive vehicle and save it as PNG (``docs/render_frame.png``).

python scripts/render_frame.py docs/render_frame.png
"""

from __future__ import annotations

import sys

import numpy as np

import hyperloop_env  # noqa: F401
from hyperloop_env.env import HyperloopSuspensionEnv
from hyperloop_env.rendering import save_png


def save_frame(path: str, steps: int = 600, **env_kwargs: object) -> np.ndarray:
    """Run the passive vehicle (action 0) for ``steps`` control steps, save the frame."""
    env = HyperloopSuspensionEnv(render_mode="rgb_array", **env_kwargs)
    env.reset(seed=0)
    action = np.zeros(env.action_space.shape, dtype=np.float32)
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            break
    frame = env.render()
    env.close()
    assert frame is not None
    save_png(frame, path)
    return frame


if __name__ == "__main__":
    save_frame(
        sys.argv[1] if len(sys.argv) > 1 else "render_frame.png",
        scenario="paper-2000-curved",
        irregularity="maglev-rough",
    )
