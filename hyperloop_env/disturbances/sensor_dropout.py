"""Sensor dropout: one unit's gap sensor freezes (holds its last value) for intervals.

Physics and basis. A gap sensor (inductive or capacitive) and its data link can lose their
signal for a while — a connector, an EMC burst, a sensor head passing a defect of the
reference surface. The usual failure mode of a digital link is *stuck at the last value*:
the controller keeps receiving the last delivered reading. This family makes the sensor of
one unit (its gap and gap-rate entries of the observation, ``ObservationSpec`` blocks
``gap`` and ``gap_rate``) hold the last delivered value during dropout intervals; every
other entry stays live. A controller that trusts the frozen reading acts on stale data;
the passive suspension does not read sensors and is unaffected (a useful control).

Model (a two-state Markov chain per control step, i.e. an alternating renewal process with
geometric durations): a dropout ends at each step with probability ``q = dt/mean_duration_s``
(capped at 1: at least one step), a working sensor drops out with probability
``r = q·p/(1 − p)``, so the long-run fraction of time in dropout is exactly
``r/(q + r) = p``, the dropout durations are geometric with mean ``mean_duration_s`` and the
working intervals geometric with mean ``mean_duration_s·(1 − p)/p``. The first observation
of an episode (the reset observation) is always live, so a hold never reaches back into the
previous episode; the chain starts in the working state (memoryless, hence stationary from
there on). Realised per episode from the seed; the unit is fixed (``unit="FL"`` …) or drawn
per episode (``unit="any"``, default).

Units and magnitudes.

* ``severity`` = p [-], in [0, 1): long-run fraction of time the sensor is frozen. 0.001–0.01
  is a flaky link; 0.1–0.5 a failing one.
* ``mean_duration_s`` [s]: mean length of one dropout (default 0.02 s: 20 control steps,
  5.6 m at 1000 km/h — about two vehicle-heave periods' worth of stale data per second at
  p = 0.1 with ~5 dropouts per second).
* ``unit``: ``"any"`` or a unit name of :data:`hyperloop_env.physics.units.UNIT_NAMES`.

Sensor noise is applied before the hold (the held value is the last *delivered*, noisy
reading), the optional one-step delay after it (:mod:`hyperloop_env.sensors`).
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from hyperloop_env.disturbances.base import Disturbance, ProfileGrid, Realisation, check_real
from hyperloop_env.observation import observation_spec
from hyperloop_env.physics.model import episode_steps
from hyperloop_env.physics.params import ModelParams
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES

ANY_UNIT = "any"


class DropoutSchedule:
    """One episode's dropout realisation of one sensor: hold ``columns`` of the observation
    during the steps ``[starts[k], ends[k])``. Called by
    :class:`hyperloop_env.sensors.SensorModel` as ``schedule(step, obs_row, last_row)``;
    stateless (a lookup by step), so repeated or out-of-order calls are safe."""

    __slots__ = ("columns", "ends", "starts", "unit", "_starts", "_ends")

    def __init__(
        self, unit: int, columns: tuple[int, ...], starts: np.ndarray, ends: np.ndarray
    ) -> None:
        self.unit = int(unit)
        self.columns = np.asarray(columns, dtype=np.int64)
        self.starts = np.asarray(starts, dtype=np.int64)
        self.ends = np.asarray(ends, dtype=np.int64)
        self._starts = self.starts.tolist()
        self._ends = self.ends.tolist()

    def active(self, step: int) -> bool:
        """True if the sensor is frozen at ``step``: SensorModel's step counter, the control
        steps completed before the observation's step (0 for the reset observation and the
        first step's; never frozen)."""
        k = bisect.bisect_right(self._starts, step) - 1
        return k >= 0 and step < self._ends[k]

    def held(self, n_steps: int) -> np.ndarray:
        """Boolean mask of the frozen steps 0 … n_steps − 1."""
        m = np.zeros(n_steps, dtype=np.bool_)
        for a, b in zip(self._starts, self._ends, strict=True):
            if a >= n_steps:
                break
            m[a : min(b, n_steps)] = True
        return m

    def __call__(self, step: int, obs_row: np.ndarray, last_row: np.ndarray) -> None:
        if self.active(step):
            obs_row[self.columns] = last_row[self.columns]

    def __repr__(self) -> str:
        return (
            f"DropoutSchedule(unit={UNIT_NAMES[self.unit]}, columns={self.columns.tolist()}, "
            f"intervals={len(self._starts)})"
        )


def dropout_intervals(
    n_steps: int, p: float, q: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Start and end steps of the dropouts over steps 0 … n_steps − 1 (see the module
    docstring): alternating working runs ~ Geometric(r) and dropouts ~ Geometric(q),
    starting with a working run at step 0. Drawn in pairs (working, dropout) in batches."""
    if p <= 0.0 or n_steps <= 1:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    r = q * p / (1.0 - p)
    starts: list[np.ndarray] = []
    ends: list[np.ndarray] = []
    t = 0
    batch = max(16, int(n_steps * r * 1.2) + 16)
    while t < n_steps:
        up = rng.geometric(r, batch)
        down = rng.geometric(q, batch)
        s = t + np.cumsum(up + down) - down
        e = s + down
        starts.append(s)
        ends.append(e)
        t = int(e[-1])
    st = np.concatenate(starts)
    en = np.concatenate(ends)
    keep = st < n_steps
    return st[keep], en[keep]


@dataclass(frozen=True)
class SensorDropout(Disturbance):
    """One unit's gap sensor holds its last value a fraction ``severity`` of the time."""

    name: ClassVar[str] = "sensor_dropout"
    severity_unit: ClassVar[str] = "long-run fraction of time the gap sensor is frozen [-]"
    description: ClassVar[str] = "one unit's gap sensor holds its last value for intervals"
    scales_with_severity: ClassVar[bool] = False
    scaling_note: ClassVar[str] = "the dropout schedule is a Markov chain of the severity"

    severity: float = 0.1
    mean_duration_s: float = 0.02
    unit: str = ANY_UNIT

    def __post_init__(self) -> None:
        check_real(self, "severity", lower=0.0)
        if not self.severity < 1.0:
            raise ValueError(
                f"SensorDropout.severity must be < 1 (a fraction of time), got {self.severity!r}"
            )
        check_real(self, "mean_duration_s", lower=0.0, upper=3600.0, strict_lower=True)
        if self.unit != ANY_UNIT and self.unit not in UNIT_NAMES:
            raise ValueError(
                f"SensorDropout.unit must be {ANY_UNIT!r} or one of {list(UNIT_NAMES)}, "
                f"got {self.unit!r}"
            )

    def step_probabilities(self, dt_s: float) -> tuple[float, float]:
        """(q, r): per-step probabilities that a dropout ends / a working sensor drops out."""
        q = min(1.0, dt_s / self.mean_duration_s)
        p = self.severity
        r = q * p / (1.0 - p)
        if r > 1.0:
            raise ValueError(
                f"SensorDropout: severity {p!r} with mean_duration_s {self.mean_duration_s!r} "
                f"needs working intervals shorter than one control step; raise mean_duration_s"
            )
        return q, r

    def realise(
        self, params: ModelParams, grid: ProfileGrid, rng: np.random.Generator
    ) -> Realisation:
        if self.severity == 0.0:
            return Realisation()
        dt = params.simulation.control_dt_s
        q, _ = self.step_probabilities(dt)
        unit = int(rng.integers(N_UNITS)) if self.unit == ANY_UNIT else UNIT_NAMES.index(self.unit)
        spec = observation_spec(params.actuators)
        cols = (spec.start("gap") + unit, spec.start("gap_rate") + unit)
        starts, ends = dropout_intervals(episode_steps(params) + 1, self.severity, q, rng)
        return Realisation(sensor_hook=DropoutSchedule(unit, cols, starts, ends))
