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

The physics and the environments' kernels are compiled by numba on their first use and
cached on disk (next to the sources, or in ``NUMBA_CACHE_DIR``). When a process has to
compile them (the first run, or after the sources changed) it says so once on stderr,
:data:`COMPILE_MESSAGE`; a process that finds them in the cache compiles nothing and
prints nothing.
"""

import sys
from typing import Any

from gymnasium.envs.registration import register, registry
from numba.core import event as numba_event

__version__ = "0.1.0"

ENV_ID = "HyperloopSuspension-v0"

COMPILE_MESSAGE = "hyperloop_env: compiling the physics kernels (first run only, ~20 s)..."
"""Written to stderr once per process, when the first of the package's numba functions is
compiled (not when numba loads it from its disk cache)."""


class CompileNotice(numba_event.Listener):
    """Listener of numba's ``numba:compile`` event (sent only when a function is really
    compiled, never for a disk-cache hit): writes :data:`COMPILE_MESSAGE` to stderr the
    first time a function of this package is compiled, then stays silent."""

    def __init__(self) -> None:
        self.shown = False

    def on_start(self, event: Any) -> None:
        if self.shown:
            return
        func = getattr(event.data.get("dispatcher"), "py_func", None)
        module = getattr(func, "__module__", None) or ""
        if module.startswith(__name__ + "."):
            self.shown = True
            print(COMPILE_MESSAGE, file=sys.stderr, flush=True)

    def on_end(self, event: Any) -> None:
        pass


COMPILE_NOTICE = CompileNotice()
numba_event.register("numba:compile", COMPILE_NOTICE)


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

__all__ = ["COMPILE_MESSAGE", "ENV_ID", "CompileNotice", "__version__", "register_envs"]
