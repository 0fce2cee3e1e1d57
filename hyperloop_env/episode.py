"""What happens at the start of an episode, shared by the single and the vector env.

From the environment's generator, in a fixed order: the episode's parameters
(:meth:`ResolvedConfig.sample`), the simulator seed (the guideway irregularity) and the
sensor-noise key; then, from generators derived from the simulator seed, the ``random``
scenario's disturbance families (:meth:`ResolvedConfig.episode_disturbances`) and every
disturbance's realisation (:func:`hyperloop_env.disturbances.realise_episode`): parameters,
profile offset and the per-episode sensor hook (``sensor_hook``, installed by the envs
with :meth:`hyperloop_env.sensors.SensorModel.set_episode_hook`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hyperloop_env.config import ResolvedConfig
from hyperloop_env.disturbances import ProfileGrid, SensorHook, realise_episode
from hyperloop_env.physics.model import profile_grid
from hyperloop_env.physics.params import ModelParams

SEED_BOUND = 2**63 - 1


@dataclass(frozen=True)
class EpisodeStart:
    params: ModelParams
    sim_seed: int
    noise_key: np.uint64
    profile_offset: np.ndarray | None
    sensor_hook: SensorHook | None = None


def start_episode(config: ResolvedConfig, rng: np.random.Generator) -> EpisodeStart:
    """Draw one episode (see the module docstring)."""
    params = config.sample(rng)
    sim_seed = int(rng.integers(0, SEED_BOUND))
    key = np.uint64(rng.integers(0, SEED_BOUND))
    disturbances = config.episode_disturbances(np.random.default_rng([sim_seed, 0]))
    if not disturbances:
        return EpisodeStart(params, sim_seed, key, None)
    for d in disturbances:  # deterministic parts of drawn families (random scenario)
        if d not in config.disturbances:
            params = d.configure(params)
    n, step = profile_grid(params)
    r = realise_episode(disturbances, params, ProfileGrid(n, step), sim_seed)
    assert r.params is not None
    return EpisodeStart(r.params, sim_seed, key, r.profile_offset, r.sensor_hook)
