"""The vehicle–guideway simulator (no Gymnasium dependency).

>>> from hyperloop_env.physics import Simulator, ModelParams
"""

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
