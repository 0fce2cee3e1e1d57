"""Disturbances: parts a scenario is made of, each with a continuous severity.

>>> from hyperloop_env.disturbances import make_disturbance
>>> make_disturbance("thermal_camber", 0.004)
ThermalCamber(severity=0.004, spread=0.5)

================  ==================================  =========================================
name              severity                            acts on
================  ==================================  =========================================
roughness         amplitude factor of the German      parameters (the irregularity the
                  "low" spectrum [-]                  simulator draws from the seed)
thermal_camber    mean midspan camber [m]             guideway profile (parabolic per span)
payload           payload mass / capsule mass [-]     parameters (mass, off-centre CG), drawn
actuator_fault    fraction of one coil's range lost   parameters (fault unit, onset), drawn
speed_profile     |acceleration| [m/s²]               parameters (braking/accelerating)
pier_settlement   σ of each pier's vertical offset    guideway profile (piecewise linear,
                  [m]                                 kinks at the piers)
joint_steps       σ of each span's rail offset [m]    guideway profile (steps at the joints,
                                                      ramped over the magnet length)
sensor_dropout    fraction of time one unit's gap     sensors (hold the last value; installed
                  sensor is frozen [-], in [0, 1)     per episode by the environments)
================  ==================================  =========================================

Adding a disturbance (README, "Extending"): one module with a frozen dataclass deriving
from :class:`~hyperloop_env.disturbances.base.Disturbance`, one entry in
:data:`DISTURBANCES`, and its tests. Environments take them as
``disturbances={"thermal_camber": 0.004}`` (name → severity, or name → dict of fields) or
as a tuple of instances.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from hyperloop_env.disturbances.actuator_fault import ActuatorFault
from hyperloop_env.disturbances.base import Disturbance, ProfileGrid, Realisation, SensorHook
from hyperloop_env.disturbances.joint_steps import JointSteps
from hyperloop_env.disturbances.payload import Payload
from hyperloop_env.disturbances.pier_settlement import PierSettlement
from hyperloop_env.disturbances.roughness import Roughness
from hyperloop_env.disturbances.sensor_dropout import DropoutSchedule, SensorDropout
from hyperloop_env.disturbances.speed_profile import SpeedProfile
from hyperloop_env.disturbances.thermal_camber import ThermalCamber
from hyperloop_env.physics.params import ModelParams, is_real

DISTURBANCES: dict[str, type[Disturbance]] = {
    Roughness.name: Roughness,
    ThermalCamber.name: ThermalCamber,
    Payload.name: Payload,
    ActuatorFault.name: ActuatorFault,
    SpeedProfile.name: SpeedProfile,
    PierSettlement.name: PierSettlement,
    JointSteps.name: JointSteps,
    SensorDropout.name: SensorDropout,
}
"""Registry: disturbance name → class."""


def make_disturbance(name: str, severity: Any = None, **fields: Any) -> Disturbance:
    """The disturbance called ``name`` with ``severity`` (its own unit) and other fields."""
    if not isinstance(name, str) or name not in DISTURBANCES:
        raise ValueError(f"unknown disturbance {name!r}; valid disturbances: {list(DISTURBANCES)}")
    cls = DISTURBANCES[name]
    if severity is not None:
        fields["severity"] = severity
    try:
        return cls(**fields)
    except TypeError as exc:
        raise TypeError(f"disturbance {name!r}: {exc}") from None


def parse_disturbances(spec: Any) -> tuple[Disturbance, ...]:
    """Normalise ``spec`` (None, a Disturbance, an iterable of them, or a mapping
    name → severity | dict of fields) to a tuple of disturbances, one per name."""
    if spec is None:
        return ()
    if isinstance(spec, Disturbance):
        items: list[Disturbance] = [spec]
    elif isinstance(spec, Mapping):
        items = []
        for name, value in spec.items():
            if isinstance(value, Disturbance):
                items.append(value)
            elif isinstance(value, Mapping):
                items.append(make_disturbance(name, **dict(value)))
            elif is_real(value):
                items.append(make_disturbance(name, value))
            else:
                raise ValueError(
                    f"disturbances[{name!r}] must be a severity (number) or a dict of fields, "
                    f"got {value!r}"
                )
    elif isinstance(spec, Iterable) and not isinstance(spec, str | bytes):
        items = list(spec)
        for d in items:
            if not isinstance(d, Disturbance):
                raise ValueError(
                    f"disturbances must be Disturbance instances or a mapping name -> severity, "
                    f"got {d!r}"
                )
    else:
        raise ValueError(
            "disturbances must be None, a Disturbance, a tuple of them or a mapping "
            f"name -> severity, got {spec!r}"
        )
    names = [d.name for d in items]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ValueError(f"disturbances: {dup} given more than once")
    return tuple(items)


def merge(base: tuple[Disturbance, ...], extra: tuple[Disturbance, ...]) -> tuple[Disturbance, ...]:
    """``base`` with every disturbance of the same name replaced by ``extra``'s, the rest
    of ``extra`` appended (order: base order, then new names in ``extra`` order)."""
    by_name = {d.name: d for d in extra}
    out = [by_name.pop(d.name, d) for d in base]
    out += [d for d in extra if d.name in by_name]
    return tuple(out)


def configure_all(disturbances: tuple[Disturbance, ...], params: ModelParams) -> ModelParams:
    for d in disturbances:
        params = d.configure(params)
    return params


def realise_episode(
    disturbances: tuple[Disturbance, ...], params: ModelParams, grid: ProfileGrid, seed: int
) -> Realisation:
    """One episode's realisation of every disturbance: the episode parameters, the sum of
    the profile offsets (None if no disturbance touches the profile) and the sensor hook
    (None if no disturbance touches the sensors; several are applied in order).
    Disturbance k draws from ``default_rng([seed, k + 1])``: independent of the
    irregularity (which the simulator draws from ``default_rng(seed)``) and of the other
    disturbances."""
    offset = None
    hooks: list[SensorHook] = []
    for k, d in enumerate(disturbances):
        r = d.realise(params, grid, np.random.default_rng([seed, k + 1]))
        if r.params is not None:
            params = r.params
        if r.profile_offset is not None:
            offset = r.profile_offset if offset is None else offset + r.profile_offset
        if r.sensor_hook is not None:
            hooks.append(r.sensor_hook)
    hook: SensorHook | None = None
    if len(hooks) == 1:
        hook = hooks[0]
    elif hooks:
        hook = _Chain(tuple(hooks))
    return Realisation(params=params, profile_offset=offset, sensor_hook=hook)


class _Chain:
    """Several sensor hooks applied in order."""

    def __init__(self, hooks: tuple[SensorHook, ...]) -> None:
        self.hooks = hooks

    def __call__(self, step: int, obs_row: np.ndarray, last_row: np.ndarray) -> None:
        for h in self.hooks:
            h(step, obs_row, last_row)


def realise_all(
    disturbances: tuple[Disturbance, ...], params: ModelParams, grid: ProfileGrid, seed: int
) -> tuple[ModelParams, np.ndarray | None]:
    """(episode parameters, summed profile offset) of :func:`realise_episode`."""
    r = realise_episode(disturbances, params, grid, seed)
    assert r.params is not None
    return r.params, r.profile_offset


__all__ = [
    "DISTURBANCES",
    "ActuatorFault",
    "Payload",
    "SpeedProfile",
    "Disturbance",
    "DropoutSchedule",
    "JointSteps",
    "PierSettlement",
    "ProfileGrid",
    "Realisation",
    "Roughness",
    "SensorDropout",
    "SensorHook",
    "ThermalCamber",
    "configure_all",
    "make_disturbance",
    "merge",
    "parse_disturbances",
    "realise_all",
    "realise_episode",
]
