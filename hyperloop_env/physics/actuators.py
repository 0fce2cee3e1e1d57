"""Actuator sets: which coil currents a controller commands.

The simulator knows every actuator *kind* listed in :data:`ACTUATOR_KINDS`; each kind has
one command channel per magnet unit (FL, FR, RL, RR). The physics always integrates all
kinds; an :class:`ActuatorSet` (``ModelParams.actuators``) says which of them the
controller commands, the others stay at their neutral command (bias current). The order of
the full command vector the compiled kernels read is :data:`PHYSICS_KINDS`.

Kinds
-----
``levitation``
    The levitation coil current I_a of each unit [A] (paper eq. 4); neutral command I0,
    the equilibrium current. This is the mission's action.
``guidance``
    The differential current ΔI_a of each unit's guidance pair [A]: the left magnet carries
    I_g0 + ΔI, the right one I_g0 − ΔI (:class:`~hyperloop_env.physics.params.GuidanceParams`);
    neutral command 0 (both at bias). Channel names ``gFL`` … ``gRR``.

Adding a kind (README, "Extending"): add an :class:`ActuatorKind` here, append its name to
:data:`PHYSICS_KINDS`, give its force law to :mod:`~hyperloop_env.physics.vehicle` (it
reads its command block through :data:`~hyperloop_env.physics.layout.COMMAND_SLICES`), and
the layout, the simulator's command check, the environment's action space, the
observation's current block and the controllers' action view follow from the set.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES


@dataclass(frozen=True)
class ActuatorKind:
    """One kind of actuator, one channel per magnet unit.

    The normalised action ``a ∈ [−1, 1]`` of a channel maps to the physical command
    ``base·(neutral + scale·a)`` [A], ``base`` the kind's reference current of the episode
    (I0 for the levitation coils) and ``scale`` the environment's ``action_scale``.
    ``neutral`` is 1 for an absolute current around its bias, 0 for a differential one.
    """

    name: str
    description: str
    command: str  # physical meaning and unit of one channel's command
    neutral: float
    channel_prefix: str = ""  # channel names are prefix + unit name


ACTUATOR_KINDS: dict[str, ActuatorKind] = {
    "levitation": ActuatorKind(
        name="levitation",
        description="levitation coil current of each unit (paper eq. 4)",
        command="coil current I_a [A]",
        neutral=1.0,
    ),
    "guidance": ActuatorKind(
        name="guidance",
        description="differential current of each unit's guidance pair (I_g0 ± ΔI)",
        command="differential guidance current ΔI_a [A]",
        neutral=0.0,
        channel_prefix="g",
    ),
}

PHYSICS_KINDS: tuple[str, ...] = ("levitation", "guidance")
"""Order of the kinds in the simulator's full command vector."""

N_COMMANDS: int = N_UNITS * len(PHYSICS_KINDS)
"""Length of the full command vector of the compiled kernels."""


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
    return tuple(k for k in PHYSICS_KINDS if k in names)


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
        return self.kinds == PHYSICS_KINDS

    def command_index(self) -> list[int]:
        """Position of each channel of the set in the full command vector."""
        out: list[int] = []
        for k in self.kinds:
            base = PHYSICS_KINDS.index(k) * N_UNITS
            out.extend(range(base, base + N_UNITS))
        return out

    def neutral(self) -> tuple[float, ...]:
        """Per channel ``neutral`` of its kind (see :class:`ActuatorKind`)."""
        return tuple(ACTUATOR_KINDS[k].neutral for k in self.kinds for _ in UNIT_NAMES)

    def __str__(self) -> str:
        return self.name


DEFAULT_ACTUATORS = ActuatorSet(("levitation",))
"""The mission's action: the four levitation coil currents."""
