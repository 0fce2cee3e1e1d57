"""Observation layout and action map shared by the environments and the controllers.

The observation (float32, what a real vehicle measures; every entry scaled to O(1)) is a
concatenation of named blocks. Its layout depends on the actuator set only through the
current blocks; for the default ``actuators="levitation"`` it is:

====================  ==========  ===========================================  ===============
slice                 name        meaning                                      scaling
====================  ==========  ===========================================  ===============
``OBS_GAP``  0–3      gap         gap excursion s_a of FL, FR, RL, RR [m]      / clearance Ω
``OBS_GAP_RATE`` 4–7  gap_rate    ds_a/dt (backward difference of the gap      / 1 m/s
                                  sensor over one control interval) [m/s]
``OBS_LAT``  8–11     lateral     guidance gap excursion of each unit          / Ω_g (8 mm)
                                  (lateral offset from the guideway) [m]
``OBS_ACC``  12–13    acc         capsule heave and lateral acceleration       / g
                                  (track frame) [m/s²]
``OBS_CURRENT`` 14–17 current     applied levitation coil current I_a [A]      I_a/I0 − 1
``OBS_SPEED`` 18      speed       v [m/s]                                      / (2000 km/h)
``OBS_CURV``  19–22   curvature   κ at the capsule and 250, 500, 1000 m ahead  × 1e5 m
====================  ==========  ===========================================  ===============

Every actuator kind of the set adds its current block (``ActuatorKind.observation``, 4
entries ``I/reference − neutral``, after ``acc`` in the physics order) and the optional
blocks it asks for (``ActuatorKind.observes``). With ``actuators="levitation+guidance"``
(23 + 8 = 31 entries): ``lateral_rate`` (4, after ``lateral``: backward difference of the
guidance gaps over one control interval [m/s], / 1 m/s) and ``current_guidance`` (4, after
``current``: the applied differential guidance current ΔI_a / I_g0).

The blocks up to the currents are *measured* (sensor noise, delay and dropout act on
them); speed and curvature are map data and stay exact. :class:`ObservationSpec` gives
the layout for any actuator set, with named slices and a typed view in physical units for
controllers (:meth:`ObservationSpec.view`).

Memory options (:class:`MemorySpec`; env keywords ``observation_history`` and
``observation_front_preview``; off by default, the layout above unchanged) append blocks
computed from earlier observations (:mod:`hyperloop_env.observation_memory`), after the
map data:

* ``history`` — the measured blocks (everything before ``speed``) of the previous
  ``k − 1`` observations, the most recent first (``observation_history=k``, 1 ≤ k ≤ 16;
  1: off). Before the episode has run ``k − 1`` steps, the missing ones are the reset
  observation.
* ``front_preview`` — what the rear units (RL, RR) will run over: the front units' (FL, FR)
  gap and guidance gap entries as they were measured ``τ − ℓ`` ago, τ = ``set_spacing_m`` / v
  the time the rear units take to reach where the front units were (16 m: 57.6 ms at
  1000 km/h, 28.8 ms at 2000 km/h; rounded to control steps), for the leads ℓ in
  :data:`FRONT_PREVIEW_LEADS_S` (0, 5, 10, 20 ms): 4 leads × (gap FL, gap FR, lateral FL,
  lateral FR) = 16 entries, scaled as ``gap`` and ``lateral``. ℓ = 0 is the guideway under
  the rear units now; ℓ > 0 is ℓ ahead of them. A delay longer than
  :data:`MAX_FRONT_PREVIEW_DELAY_S` (speeds below 57.6 km/h) is capped at it; entries older
  than the episode are the reset observation's.

Action: ``Box(-1, 1, (n,), float32)``, one entry per channel of the actuator set, mapped
affinely to the commanded current ``I = base·(neutral + action_scale·a)`` [A]
(:func:`action_to_current`; for the levitation coils ``I_a = I0·(1 + action_scale·a)``,
0 … 2·I0 by default), then limited to the physical range [0, I_max] by the simulator.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from hyperloop_env.keywords import kw, validate_fields
from hyperloop_env.physics.actuators import ACTUATOR_KINDS, DEFAULT_ACTUATORS, ActuatorSet
from hyperloop_env.physics.units import N_UNITS

PREVIEW_DISTANCES_M: tuple[float, ...] = (0.0, 250.0, 500.0, 1000.0)
FRONT_PREVIEW_LEADS_S: tuple[float, ...] = (0.0, 0.005, 0.010, 0.020)
"""Leads ℓ [s] of the ``front_preview`` block: the front units' signals τ − ℓ ago."""
MAX_FRONT_PREVIEW_DELAY_S = 1.0
"""Longest delay τ the ``front_preview`` block looks back [s] (16 m at 57.6 km/h)."""
MAX_HISTORY = 16
"""Largest ``observation_history`` (observations stacked, the current one included)."""
FRONT_PREVIEW_SIGNALS: tuple[tuple[str, int], ...] = (
    ("gap", 0),
    ("gap", 1),
    ("lateral", 0),
    ("lateral", 1),
)
"""(block, unit index) of each signal of a ``front_preview`` lead: FL, FR gap, then FL, FR
lateral."""
GAP_RATE_SCALE_M_S = 1.0
SPEED_SCALE_M_S = 2000.0 / 3.6
CURVATURE_SCALE_M = 1e5


@dataclass(frozen=True)
class ObsBlock:
    """One named block of the observation."""

    name: str
    size: int
    meaning: str
    scaling: str
    measured: bool  # True: a sensor signal (noise/delay/dropout apply); False: map data
    # or memory of earlier (already sensed) observations


OPTIONAL_BLOCKS: dict[str, ObsBlock] = {
    "lateral_rate": ObsBlock(
        "lateral_rate",
        N_UNITS,
        "guidance gap rate (backward difference) [m/s]",
        "/ 1 m/s (0 at reset)",
        True,
    ),
}
"""Measured blocks present only when a kind of the set asks for them
(``ActuatorKind.observes``); each comes after ``lateral``."""


def _blocks(actuators: ActuatorSet) -> tuple[ObsBlock, ...]:
    kinds = [ACTUATOR_KINDS[k] for k in actuators.kinds]
    wanted = {name for kind in kinds for name in kind.observes}
    blocks = [
        ObsBlock("gap", N_UNITS, "gap excursion s_a per unit [m], + = gap opens", "/ Ω", True),
        ObsBlock(
            "gap_rate",
            N_UNITS,
            "gap rate ds_a/dt (backward difference) [m/s]",
            "/ 1 m/s (0 at reset)",
            True,
        ),
        ObsBlock(
            "lateral",
            N_UNITS,
            "guidance gap excursion (lateral offset) per unit [m]",
            "/ Ω_g",
            True,
        ),
    ]
    blocks += [b for name, b in OPTIONAL_BLOCKS.items() if name in wanted]
    blocks.append(ObsBlock("acc", 2, "capsule heave and lateral acceleration [m/s²]", "/ g", True))
    for kind in kinds:
        ob = kind.observation
        blocks.append(ObsBlock(ob.name, N_UNITS, ob.meaning, ob.scaling, True))
    blocks += [
        ObsBlock("speed", 1, "speed v [m/s]", "/ (2000 km/h)", False),
        ObsBlock(
            "curvature",
            len(PREVIEW_DISTANCES_M),
            "curvature at the capsule and 250, 500, 1000 m ahead [1/m]",
            "× 1e5 m",
            False,
        ),
    ]
    return tuple(blocks)


def _history(value: Any) -> int:
    ok = not isinstance(value, bool) and isinstance(value, int | np.integer)
    if not ok or not 1 <= int(value) <= MAX_HISTORY:
        raise ValueError(
            f"observation_history must be an integer in 1 … {MAX_HISTORY} (observations "
            f"stacked, 1: the current one only), got {value!r}"
        )
    return int(value)


def _flag(value: Any) -> bool:
    if not isinstance(value, bool | np.bool_):
        raise ValueError(f"observation_front_preview must be True or False, got {value!r}")
    return bool(value)


@dataclass(frozen=True)
class MemorySpec:
    """Observation memory options (module docstring): ``history`` observations stacked
    (1: the current one only) and the ``front_preview`` block on or off."""

    history: int = field(
        default=1,
        metadata=kw(
            f"observations stacked: the current one and the previous k − 1 (1 … {MAX_HISTORY})",
            parse=_history,
            name="observation_history",
            omit=lambda v: v == 1,
        ),
    )
    front_preview: bool = field(
        default=False,
        metadata=kw(
            "append the front units' delayed gap signals (the rear units' preview)",
            parse=_flag,
            name="observation_front_preview",
            omit=lambda v: not v,
        ),
    )

    def __post_init__(self) -> None:
        validate_fields(self)

    @property
    def active(self) -> bool:
        return self.history > 1 or self.front_preview


NO_MEMORY = MemorySpec()


def _memory_blocks(n_measured: int, memory: MemorySpec) -> tuple[ObsBlock, ...]:
    out = []
    if memory.history > 1:
        out.append(
            ObsBlock(
                "history",
                n_measured * (memory.history - 1),
                f"measured entries 0–{n_measured - 1} of the previous {memory.history - 1} "
                "observation(s), most recent first",
                "as those entries",
                False,
            )
        )
    if memory.front_preview:
        leads = ", ".join(f"{1000 * x:g}" for x in FRONT_PREVIEW_LEADS_S)
        out.append(
            ObsBlock(
                "front_preview",
                len(FRONT_PREVIEW_LEADS_S) * len(FRONT_PREVIEW_SIGNALS),
                f"gap FL, FR and lateral FL, FR measured τ − ℓ ago (τ = set spacing / v; "
                f"ℓ = {leads} ms): what the rear units meet ℓ ahead",
                "/ Ω, / Ω_g",
                False,
            )
        )
    return tuple(out)


class ObservationView(NamedTuple):
    """One observation in physical units (SI; per-unit arrays in the order FL, FR, RL, RR)."""

    gap_m: np.ndarray
    gap_rate_m_s: np.ndarray
    lateral_m: np.ndarray
    acc_m_s2: np.ndarray  # heave, lateral
    current_A: np.ndarray  # levitation coil currents
    speed_m_s: float
    curvature_per_m: np.ndarray


@dataclass(frozen=True)
class ObservationScales:
    """The episode constants that scale the observation (from the model parameters)."""

    clearance_m: float
    lateral_clearance_m: float
    gravity_m_s2: float
    nominal_current_A: float


class ObservationSpec:
    """Layout of the observation for one actuator set and memory options: named blocks and
    slices. ``base_size``: the entries computed from the current step (the memory blocks,
    if any, follow them; ``size`` counts all); ``n_measured``: the leading sensor entries."""

    def __init__(
        self, actuators: ActuatorSet = DEFAULT_ACTUATORS, memory: MemorySpec = NO_MEMORY
    ) -> None:
        self.actuators = actuators
        self.memory = memory
        base = _blocks(actuators)
        measured = [b for b in base if b.measured]
        if base[: len(measured)] != tuple(measured):
            raise AssertionError("measured blocks must come first")
        self.n_measured = sum(b.size for b in measured)
        self.base_size = sum(b.size for b in base)
        self.blocks = base + _memory_blocks(self.n_measured, memory)
        self.slices: dict[str, slice] = {}
        start = 0
        for b in self.blocks:
            self.slices[b.name] = slice(start, start + b.size)
            start += b.size
        self.size = start

    @property
    def base(self) -> ObservationSpec:
        """The same layout without memory blocks."""
        return observation_spec(self.actuators)

    def slice(self, name: str) -> slice:
        if name not in self.slices:
            raise KeyError(f"no observation block {name!r}; blocks: {list(self.slices)}")
        return self.slices[name]

    def start(self, name: str) -> int:
        return self.slice(name).start

    def offsets(self) -> np.ndarray:
        """Start of each block of :data:`KERNEL_BLOCKS`, then of each registered actuator
        kind's current block in the physics order (−1 if absent), for the kernel."""
        names = KERNEL_BLOCKS + tuple(k.observation.name for k in ACTUATOR_KINDS.values())
        return np.array(
            [self.slices[n].start if n in self.slices else -1 for n in names],
            dtype=np.int64,
        )

    def view(self, obs: Any, scales: ObservationScales) -> ObservationView:
        """The observation ``obs`` (shape (size,)) in physical units."""
        o = np.asarray(obs, dtype=np.float64)
        if o.shape != (self.size,):
            raise ValueError(f"obs must have shape ({self.size},), got {o.shape}")
        s = self.slices
        return ObservationView(
            gap_m=o[s["gap"]] * scales.clearance_m,
            gap_rate_m_s=o[s["gap_rate"]] * GAP_RATE_SCALE_M_S,
            lateral_m=o[s["lateral"]] * scales.lateral_clearance_m,
            acc_m_s2=o[s["acc"]] * scales.gravity_m_s2,
            current_A=(o[s["current"]] + 1.0) * scales.nominal_current_A,
            speed_m_s=float(o[s["speed"].start]) * SPEED_SCALE_M_S,
            curvature_per_m=o[s["curvature"]] / CURVATURE_SCALE_M,
        )

    def table(self) -> str:
        """Markdown table of the layout (for docs and reports)."""
        rows = ["| entries | name | meaning | scaling |", "|---|---|---|---|"]
        for b in self.blocks:
            sl = self.slices[b.name]
            idx = f"{sl.start}" if b.size == 1 else f"{sl.start}–{sl.stop - 1}"
            rows.append(f"| {idx} | {b.name} | {b.meaning} | {b.scaling} |")
        return "\n".join(rows)

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, ObservationSpec)
            and other.actuators == self.actuators
            and other.memory == self.memory
        )

    def __hash__(self) -> int:
        return hash((self.actuators, self.memory))

    def __repr__(self) -> str:
        mem = f", {self.memory}" if self.memory.active else ""
        return f"ObservationSpec({self.actuators.name!r}{mem}, size={self.size})"


KERNEL_BLOCKS: tuple[str, ...] = (
    "gap",
    "gap_rate",
    "lateral",
    "lateral_rate",
    "acc",
    "speed",
    "curvature",
)
"""Blocks the compiled observation kernel knows by name, in the order of ``offsets()``
(the actuator kinds' current blocks follow them)."""

_SPECS: dict[tuple[ActuatorSet, MemorySpec], ObservationSpec] = {}


def observation_spec(
    actuators: ActuatorSet | str = DEFAULT_ACTUATORS, memory: MemorySpec = NO_MEMORY
) -> ObservationSpec:
    """The (cached) observation layout of an actuator set and memory options."""
    acts = ActuatorSet.parse(actuators)
    key = (acts, memory)
    if key not in _SPECS:
        _SPECS[key] = ObservationSpec(acts, memory)
    return _SPECS[key]


# ---- the default layout as constants (levitation only) -------------------------------------
_DEFAULT = observation_spec(DEFAULT_ACTUATORS)
OBS_GAP = _DEFAULT.slice("gap")
OBS_GAP_RATE = _DEFAULT.slice("gap_rate")
OBS_LAT = _DEFAULT.slice("lateral")
OBS_ACC = _DEFAULT.slice("acc")
OBS_CURRENT = _DEFAULT.slice("current")
OBS_SPEED = _DEFAULT.start("speed")
OBS_CURV = _DEFAULT.slice("curvature")
OBS_SIZE = _DEFAULT.size


def command_current(base: Any, neutral: Any, scale: Any, action: Any) -> Any:
    """The action -> current map, ``base·(neutral + scale·action)`` [A], element-wise: the
    one definition of it. ``base`` is the channel's reference current [A] (I0 for the
    levitation coils), ``neutral`` its neutral command (1 for the levitation coils) and
    ``scale`` the env's ``action_scale``. Works on floats and NumPy arrays; compiled into
    :func:`hyperloop_env.kernels.commanded_currents` (whose numba cache is keyed on
    ``kernels.py``: after changing this formula, delete the ``__pycache__`` ``*.nbi`` /
    ``*.nbc`` files)."""
    return base * (neutral + scale * action)


def action_to_current(
    action: np.ndarray, i0: float | np.ndarray, action_scale: float = 1.0
) -> np.ndarray:
    """Commanded levitation currents [A] for normalised actions in [-1, 1]: I0·(1 + scale·a)
    (:func:`command_current` with neutral command 1).

    ``i0`` is a scalar, or shape (N,) for a batch of actions of shape (N, n)."""
    i0 = np.asarray(i0, dtype=np.float64)
    if i0.ndim:
        i0 = i0[..., None]
    return command_current(i0, 1.0, action_scale, np.asarray(action, dtype=np.float64))


def current_to_action(current: np.ndarray, i0: float, action_scale: float = 1.0) -> np.ndarray:
    """Inverse of :func:`action_to_current` (not clipped)."""
    return (np.asarray(current) / i0 - 1.0) / action_scale
