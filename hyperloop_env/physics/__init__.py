"""The vehicle–guideway simulator (no Gymnasium dependency).

>>> from hyperloop_env.physics import Simulator, ModelParams
"""

import os

# The batched kernel runs on numba's OpenMP threading layer. With OpenMP's default
# busy-waiting, one thread spinning while the other core is busy (another process, an RL
# learner) made the 2-thread batch ~3x slower than 1 thread on a 2-core machine; passive
# waiting removes that (measured by benchmarks/bench_physics.py). A user's setting wins.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

from hyperloop_env.physics.model import BatchSimulator, Measurement, Simulator, pack
from hyperloop_env.physics.params import (
    IRREGULARITY_CLASSES,
    UNIT_NAMES,
    GuidewayParams,
    IrregularityParams,
    MagnetParams,
    ModelParams,
    OperatingCondition,
    SimulationParams,
    VehicleParams,
)

__all__ = [
    "IRREGULARITY_CLASSES",
    "UNIT_NAMES",
    "BatchSimulator",
    "GuidewayParams",
    "IrregularityParams",
    "MagnetParams",
    "Measurement",
    "ModelParams",
    "OperatingCondition",
    "SimulationParams",
    "Simulator",
    "VehicleParams",
    "pack",
]
