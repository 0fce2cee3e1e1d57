"""Actuator kinds and sets: which coil currents a controller commands.

The simulator knows every actuator *kind* registered in :data:`ACTUATOR_KINDS` (their order
is the physics order, :func:`physics_kinds`); each kind has one command channel per magnet
unit (FL, FR, RL, RR). The physics always integrates all kinds; an :class:`ActuatorSet`
(``ModelParams.actuators``) says which of them the controller commands, the others stay at
their neutral command. A kind is data (:class:`ActuatorKind`): its reference current, its
neutral command, its clamp, its record slot, its observation block and the name of its
force law; the simulator, the observation, the reward and both environments loop over the
kinds and read that data.

Kinds
-----
``levitation``
    The levitation coil current I_a of each unit [A] (paper eq. 4); reference I0 (the
    equilibrium current), neutral command I0, clamp [0, I_max]. This is the mission's
    action.
``guidance``
    The differential current ΔI_a of each unit's guidance pair [A]: the left magnet carries
    I_g0 + ΔI, the right one I_g0 − ΔI (:class:`~hyperloop_env.physics.params.GuidanceParams`);
    reference I_g0, neutral command 0 (both at bias), clamp ±min(I_g0, I_g,max − I_g0).
    Channel names ``gFL`` … ``gRR``.

Adding a kind (README, "Extending"): :func:`register_actuator_kind` with an
:class:`ActuatorKind` whose ``force_law`` names a law of
:data:`hyperloop_env.physics.layout.FORCE_LAWS` (a new law is one entry there and one
branch of :func:`hyperloop_env.physics.vehicle.kind_force`). Register before building simulators or
environments: each one sizes its arrays for the kinds registered when it is made.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np

from hyperloop_env.physics.layout import (
    FORCE_LAWS,
    M_I,
    M_IG,
    M_KINDS,
    N_BUILTIN_KINDS,
    P_DIGMAX,
    P_I0,
    P_IG0,
    P_IMAX,
    RECORD_FIELDS,
)
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES


@dataclass(frozen=True)
class KindObservation:
    """The observation block of an actuator kind's applied currents (``N_UNITS`` entries,
    value ``I/reference − neutral``: 0 at the neutral command)."""

    name: str  # block name in the observation, e.g. "current"
    meaning: str  # what it holds, with the unit
    scaling: str  # the scaling, written out (for the layout table)


@dataclass(frozen=True)
class ActuatorKind:
    """One kind of actuator, one channel per magnet unit, as data.

    The normalised action ``a ∈ [−1, 1]`` of a channel maps to the physical command
    ``reference·(neutral + scale·a)`` [A], ``scale`` the environment's ``action_scale``;
    ``neutral`` is 1 for an absolute current around its reference, 0 for a differential
    one. ``reference_A`` and ``limits_A`` read the packed parameter vector ``P``
    (:mod:`~hyperloop_env.physics.layout`) of the episode: the reference current [A] and the
    (lower, upper) clamp of the commanded current [A]. The applied currents are recorded in
    the record field ``record_field`` (``info`` key of the same name) and observed in the
    block ``observation``. ``force_law`` names the compiled force law
    (:data:`hyperloop_env.physics.layout.FORCE_LAWS`) that turns the kind's current into
    forces on each unit (and, opposite, on the guideway). ``observes`` names optional
    observation blocks the kind needs (e.g. ``"lateral_rate"``).
    """

    name: str
    description: str
    command: str  # physical meaning and unit of one channel's command
    neutral: float
    reference_A: Callable[[np.ndarray], float]
    limits_A: Callable[[np.ndarray], tuple[float, float]]
    record_field: str
    observation: KindObservation
    force_law: str
    channel_prefix: str = ""  # channel names are prefix + unit name
    observes: tuple[str, ...] = ()


def _levitation_limits(P: np.ndarray) -> tuple[float, float]:
    return 0.0, float(P[P_IMAX])


def _guidance_limits(P: np.ndarray) -> tuple[float, float]:
    return -float(P[P_DIGMAX]), float(P[P_DIGMAX])


ACTUATOR_KINDS: dict[str, ActuatorKind] = {
    "levitation": ActuatorKind(
        name="levitation",
        description="levitation coil current of each unit (paper eq. 4)",
        command="coil current I_a [A]",
        neutral=1.0,
        reference_A=lambda P: float(P[P_I0]),
        limits_A=_levitation_limits,
        record_field="current_A",
        observation=KindObservation(
            "current", "applied levitation coil current I_a [A]", "I_a/I0 − 1"
        ),
        force_law="levitation",
    ),
    "guidance": ActuatorKind(
        name="guidance",
        description="differential current of each unit's guidance pair (I_g0 ± ΔI)",
        command="differential guidance current ΔI_a [A]",
        neutral=0.0,
        reference_A=lambda P: float(P[P_IG0]),
        limits_A=_guidance_limits,
        record_field="guidance_current_A",
        observation=KindObservation(
            "current_guidance", "applied differential guidance current ΔI_a [A]", "ΔI_a/I_g0"
        ),
        force_law="guidance",
        channel_prefix="g",
        observes=("lateral_rate",),
    ),
}
"""Every actuator kind the simulator knows, in the physics order (the order of the full
command vector); extend with :func:`register_actuator_kind`."""

_RECORD_SLOTS: dict[str, int] = {"levitation": M_I, "guidance": M_IG}


def physics_kinds() -> tuple[str, ...]:
    """The registered kinds in the physics order (of the full command vector)."""
    return tuple(ACTUATOR_KINDS)


def n_commands() -> int:
    """Length of the full command vector: one channel per unit and registered kind."""
    return N_UNITS * len(ACTUATOR_KINDS)


def command_slices() -> dict[str, slice]:
    """Slice of each registered kind in the full command vector (``aux`` current blocks)."""
    return {k: slice(i * N_UNITS, (i + 1) * N_UNITS) for i, k in enumerate(ACTUATOR_KINDS)}


def record_slot(kind: str) -> int:
    """First record slot of ``kind``'s applied currents."""
    return _RECORD_SLOTS[kind]


def register_actuator_kind(kind: ActuatorKind) -> ActuatorKind:
    """Add ``kind`` to the simulator's kinds (after the registered ones); returns it.

    Its currents get a record slot after the built-in record (``RECORD_FIELDS[kind.
    record_field]``), a block of the packed parameters, a block of the full command vector
    and of ``aux``; ``ActuatorSet.parse("levitation+<name>")`` then selects it, which grows
    the action space and adds its observation block. Simulators and environments made
    before the call keep the kinds they were made with.
    """
    if not isinstance(kind, ActuatorKind):
        raise ValueError(f"kind must be an ActuatorKind, got {kind!r}")
    if kind.name in ACTUATOR_KINDS or not kind.name.isidentifier():
        raise ValueError(f"actuator kind name {kind.name!r} is taken or not an identifier")
    if kind.force_law not in FORCE_LAWS:
        raise ValueError(f"force_law must be one of {list(FORCE_LAWS)}, got {kind.force_law!r}")
    if kind.record_field in RECORD_FIELDS:
        raise ValueError(f"record field {kind.record_field!r} exists already")
    taken = {k.observation.name for k in ACTUATOR_KINDS.values()}
    if kind.observation.name in taken:
        raise ValueError(f"observation block {kind.observation.name!r} exists already")
    slot = M_KINDS + (len(ACTUATOR_KINDS) - N_BUILTIN_KINDS) * N_UNITS
    ACTUATOR_KINDS[kind.name] = kind
    _RECORD_SLOTS[kind.name] = slot
    RECORD_FIELDS[kind.record_field] = slice(slot, slot + N_UNITS)
    return kind


def _kind_names(spec: str | Iterable[str]) -> tuple[str, ...]:
    if isinstance(spec, str):
        names = tuple(s.strip() for s in spec.split("+"))
    else:
        names = tuple(spec)
    if not names or any(not isinstance(n, str) for n in names):
        raise ValueError(f"actuators must be a '+'-joined string of kinds, got {spec!r}")
    unknown = [n for n in names if n not in ACTUATOR_KINDS]
    if unknown:
        raise ValueError(
            f"actuators: unknown kind(s) {unknown}; valid kinds: {list(ACTUATOR_KINDS)} "
            f"(combine with '+')"
        )
    if len(set(names)) != len(names):
        raise ValueError(f"actuators: a kind is listed twice in {spec!r}")
    if names[0] != "levitation":
        raise ValueError(f"actuators must start with 'levitation', got {spec!r}")
    # canonical order = physics order
    return tuple(k for k in ACTUATOR_KINDS if k in names)


@dataclass(frozen=True)
class ActuatorSet:
    """The actuator kinds a controller commands, in the physics order.

    >>> ActuatorSet.parse("levitation").size
    4
    """

    kinds: tuple[str, ...] = ("levitation",)
    _slices: dict[str, slice] = field(init=False, repr=False, compare=False, hash=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "kinds", _kind_names(self.kinds))
        sl, start = {}, 0
        for k in self.kinds:
            sl[k] = slice(start, start + N_UNITS)
            start += N_UNITS
        object.__setattr__(self, "_slices", sl)

    @classmethod
    def parse(cls, spec: str | Iterable[str] | ActuatorSet) -> ActuatorSet:
        """``"levitation"``, ``"levitation+guidance"``, a sequence of kinds or a set."""
        if isinstance(spec, ActuatorSet):
            return spec
        return cls(_kind_names(spec))

    @property
    def name(self) -> str:
        return "+".join(self.kinds)

    @property
    def size(self) -> int:
        """Number of command channels (the action dimension)."""
        return N_UNITS * len(self.kinds)

    @property
    def slices(self) -> dict[str, slice]:
        """Slice of each kind in the set's command (action) vector."""
        return dict(self._slices)

    def slice(self, kind: str) -> slice:
        if kind not in self._slices:
            raise KeyError(f"actuator kind {kind!r} not in {self.name!r}")
        return self._slices[kind]

    @property
    def channel_names(self) -> tuple[str, ...]:
        """One name per channel, e.g. ``("FL", "FR", "RL", "RR")``."""
        return tuple(ACTUATOR_KINDS[k].channel_prefix + u for k in self.kinds for u in UNIT_NAMES)

    @property
    def is_full(self) -> bool:
        """True if the set commands every kind the physics knows (no expansion needed)."""
        return self.kinds == physics_kinds()

    def command_index(self) -> list[int]:
        """Position of each channel of the set in the full command vector."""
        out: list[int] = []
        order = physics_kinds()
        for k in self.kinds:
            base = order.index(k) * N_UNITS
            out.extend(range(base, base + N_UNITS))
        return out

    def neutral(self) -> tuple[float, ...]:
        """Per channel ``neutral`` of its kind (see :class:`ActuatorKind`)."""
        return tuple(ACTUATOR_KINDS[k].neutral for k in self.kinds for _ in UNIT_NAMES)

    def __str__(self) -> str:
        return self.name


DEFAULT_ACTUATORS = ActuatorSet(("levitation",))
"""The mission's action: the four levitation coil currents."""
