"""The vehicle–guideway simulator (no Gymnasium dependency).

>>> from hyperloop_env.physics import Simulator, ModelParams
"""

import os

# The batched kernel runs on numba's OpenMP threading layer (GNU OpenMP reads these when
# numba first loads it). Threads that busy-wait for long between parallel steps made the
# 2-thread batch ~3x slower than 1 thread whenever the other core was busy; threads that
# sleep at once (passive waiting alone) cost a wake-up per step that ate half the gain
# on an idle machine (speed/bench_threads.py). So: passive waiting after a short spin of
# GOMP_SPINCOUNT=100000 iterations (some tens of microseconds, the gap between two steps
# of the vector env); the vector env measures whether the threads pay off at all
# (hyperloop_env.kernel_choice). Timing only, never a result; a user's setting wins.
if "OMP_WAIT_POLICY" not in os.environ:
    os.environ["OMP_WAIT_POLICY"] = "PASSIVE"
    os.environ.setdefault("GOMP_SPINCOUNT", "100000")

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
