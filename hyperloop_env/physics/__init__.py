"""The vehicle–guideway simulator (no Gymnasium dependency).

>>> from hyperloop_env.physics import Simulator, ModelParams
"""

import os

# The batched kernel runs on numba's OpenMP threading layer. With OpenMP's default
# busy-waiting, one thread spinning while the other core is busy (another process, an RL
# learner) made the 2-thread batch ~3x slower than 1 thread on a 2-core machine; passive
# waiting removes that (measured by speed/bench_physics.py). A user's setting wins.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

from hyperloop_env.physics.actuators import (
    ACTUATOR_KINDS,
    DEFAULT_ACTUATORS,
    ActuatorKind,
    ActuatorSet,
    KindObservation,
    register_actuator_kind,
)
from hyperloop_env.physics.layout import RECORD_FIELDS
from hyperloop_env.physics.model import Measurement, episode_steps, pack
from hyperloop_env.physics.params import (
    IRREGULARITY_CLASSES,
    GuidanceParams,
    GuidewayParams,
    IrregularityParams,
    MagnetParams,
    ModelParams,
    OperatingCondition,
    SimulationParams,
    VehicleParams,
)
from hyperloop_env.physics.simulator import BatchSimulator, Simulator
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES

__all__ = [
    "ACTUATOR_KINDS",
    "DEFAULT_ACTUATORS",
    "IRREGULARITY_CLASSES",
    "N_UNITS",
    "RECORD_FIELDS",
    "UNIT_NAMES",
    "ActuatorKind",
    "ActuatorSet",
    "BatchSimulator",
    "GuidanceParams",
    "GuidewayParams",
    "IrregularityParams",
    "KindObservation",
    "MagnetParams",
    "Measurement",
    "ModelParams",
    "OperatingCondition",
    "SimulationParams",
    "Simulator",
    "VehicleParams",
    "episode_steps",
    "pack",
    "register_actuator_kind",
]
