"""hyperloop-suspension-gym: simulator and RL benchmark for hyperloop magnetic suspension.

Importing the package registers the Gymnasium environment ``HyperloopSuspension-v0``::

    import gymnasium as gym
    import hyperloop_env  # noqa: F401  (registers the environment)

    env = gym.make("HyperloopSuspension-v0", scenario="paper-1000-curved")
    envs = gym.make_vec("HyperloopSuspension-v0", num_envs=64,
                        vectorization_mode="vector_entry_point", scenario="random")

Episodes end by contact (terminated) or at the end of the track section (truncated, inside
the environment), so the registration has no ``max_episode_steps``.

A process that has not imported the package (a spawned worker, an RLlib runner, a config
file naming the id) uses the module-qualified id, with which Gymnasium imports this
package first::

    env = gym.make("hyperloop_env:HyperloopSuspension-v0")

Gymnasium 1.x loads no ``gymnasium.envs`` entry-point plugins on ``import gymnasium``; the
entry point in ``pyproject.toml`` (:func:`register_envs`) is only read by Gymnasium < 1.0.
"""

from gymnasium.envs.registration import register, registry

__version__ = "0.1.0"

ENV_ID = "HyperloopSuspension-v0"


def register_envs() -> None:
    """Register ``HyperloopSuspension-v0`` with Gymnasium (once; importing the package
    does it)."""
    if ENV_ID not in registry:
        register(
            id=ENV_ID,
            entry_point="hyperloop_env.env:HyperloopSuspensionEnv",
            vector_entry_point="hyperloop_env.vector_env:HyperloopSuspensionVectorEnv",
            max_episode_steps=None,
            disable_env_checker=False,
        )


register_envs()

__all__ = ["ENV_ID", "__version__", "register_envs"]
