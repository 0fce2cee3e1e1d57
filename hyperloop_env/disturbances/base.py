"""The disturbance interface: a small frozen dataclass with physical units, a continuous
severity and a seeded realisation.

A disturbance acts on one or more of

* the **parameters** of the run (:meth:`Disturbance.configure`, deterministic, applied once
  to the scenario's base parameters; :meth:`Disturbance.realise` may also return per-episode
  parameters),
* the **guideway profile** (:meth:`Disturbance.realise` returns an additive offset on the
  simulator's profile grid: rows left vertical, right vertical, lateral [m]),
* the **sensors** (:meth:`Disturbance.realise` may return ``sensor_hook``: a callable
  ``(step, obs_row, last_row) -> None`` that the environments install for the episode in
  :class:`hyperloop_env.sensors.SensorModel`, see :mod:`.sensor_dropout`),
* (later kinds) the actuators, through the same ``realise`` hook.

Realisations are drawn from a generator seeded by the episode's simulator seed and the
disturbance's position in the scenario (:func:`hyperloop_env.disturbances.realise_all`), so
adding a disturbance never changes the draws of the others and the same seed gives the
same episode.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from hyperloop_env.physics.irregularity import N_ROWS, ROW_LATERAL, ROW_LEFT, ROW_RIGHT
from hyperloop_env.physics.params import ModelParams, is_real

SensorHook = Callable[[int, np.ndarray, np.ndarray], None]
"""A per-episode sensor hook: ``hook(step, obs_row, last_row)``."""


@dataclass(frozen=True)
class ProfileGrid:
    """The simulator's guideway profile grid: ``n`` points ``x_i = i·step`` [m] (periodic)."""

    n: int
    step_m: float

    @property
    def x_m(self) -> np.ndarray:
        return np.arange(self.n) * self.step_m


@dataclass(frozen=True)
class Realisation:
    """What one episode's draw of a disturbance changes (None: nothing)."""

    params: ModelParams | None = None
    profile_offset: np.ndarray | None = None  # (3, n) [m] on the profile grid
    sensor_hook: SensorHook | None = None
    """Per-episode sensor hook ``hook(step, obs_row, last_row)`` (may overwrite entries of
    ``obs_row`` in place, e.g. hold ``last_row``'s values); installed per environment row."""


def profile_realisation(
    grid: ProfileGrid, vertical: np.ndarray, lateral: np.ndarray | None = None
) -> Realisation:
    """The realisation of a guideway-geometry family: ``vertical`` [m] (shape ``(grid.n,)``,
    positive raises the rail) under both rails alike (the left and right vertical rows: no
    roll of the cross-section) and ``lateral`` [m] (positive to +z; zero if None) as the
    ``profile_offset`` on the grid."""
    off = np.zeros((N_ROWS, grid.n))
    off[ROW_LEFT] = vertical
    off[ROW_RIGHT] = vertical
    if lateral is not None:
        off[ROW_LATERAL] = lateral
    return Realisation(profile_offset=off)


@dataclass(frozen=True)
class Disturbance:
    """Base class. Subclasses are frozen dataclasses with a ``severity`` field (a real
    number, its unit in :attr:`severity_unit`; 0 = no disturbance) and set ``name``,
    :attr:`scales_with_severity` and :attr:`scaling_note`."""

    name: ClassVar[str] = "disturbance"
    severity_unit: ClassVar[str] = ""
    description: ClassVar[str] = ""
    scales_with_severity: ClassVar[bool] = False
    """Whether one seed's realisation scales linearly with the severity: the same seed at
    severity 2s gives exactly twice the disturbance it gives at s (same draws, only their
    amplitude grows). This is the premise of a per-seed capacity search (incremental
    dynamic analysis: one realisation scaled until the run touches); a family that does not
    scale (its severity changes what is drawn, or the model itself) is studied on a grid of
    severities instead. The default, False, is the safe answer for a new family."""
    scaling_note: ClassVar[str] = ""
    """Why :attr:`scales_with_severity` holds or not, in one line (quoted by the tools that
    refuse a family that does not scale)."""

    severity: float = 0.0

    def __post_init__(self) -> None:
        check_real(self, "severity", lower=0.0)

    # ---- hooks ---------------------------------------------------------------------------
    def configure(self, params: ModelParams) -> ModelParams:
        """Deterministic change of the scenario's base parameters (default: none)."""
        return params

    def realise(
        self, params: ModelParams, grid: ProfileGrid, rng: np.random.Generator
    ) -> Realisation:
        """One episode's random draw (default: nothing)."""
        return Realisation()

    def validate(self, params: ModelParams) -> None:
        """Refuse (``ValueError`` naming the field) a *configured* disturbance that some
        episode of ``params`` could not realise, so that the configuration fails at
        construction rather than at a reset (default: nothing to check). Called by
        :class:`hyperloop_env.config.EnvConfig` with the base parameters at the slowest
        entry speed an episode can draw; not called for the families a randomising
        scenario draws per episode."""

    # ---- helpers -------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        from dataclasses import asdict

        return {"name": self.name, **asdict(self)}


def check_real(
    obj: object,
    name: str,
    lower: float | None = None,
    upper: float | None = None,
    strict_lower: bool = False,
) -> float:
    """Validate ``obj.name`` as a finite real in the given bounds; store it as a float."""
    value = getattr(obj, name)
    cls = type(obj).__name__
    if not is_real(value) or not math.isfinite(value):
        raise ValueError(f"{cls}.{name} must be a finite number, got {value!r}")
    if lower is not None and (value <= lower if strict_lower else value < lower):
        op = ">" if strict_lower else ">="
        raise ValueError(f"{cls}.{name} must be {op} {lower}, got {value!r}")
    if upper is not None and value > upper:
        raise ValueError(f"{cls}.{name} must be <= {upper}, got {value!r}")
    if not isinstance(value, float):
        object.__setattr__(obj, name, float(value))
    return float(value)
