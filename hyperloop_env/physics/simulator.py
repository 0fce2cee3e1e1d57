"""The simulators: :class:`Simulator` for one vehicle and :class:`BatchSimulator` for N
independent vehicles advanced in one compiled, multi-threaded call, over the compiled
control step of :mod:`hyperloop_env.physics.model` (the currents' rules, the measurement
record and the contact check are described there).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from hyperloop_env.physics import irregularity as irr_mod
from hyperloop_env.physics.arrays import aligned_zeros
from hyperloop_env.physics.layout import (
    A_I,
    A_SPAN0,
    A_SPAN1,
    A_T,
    M_X,
    N_SLOTS,
    P_I0,
    P_IMAX,
    aux_size,
    record_size,
    state_size,
)
from hyperloop_env.physics.model import (
    TL_ROWS,
    WORK_ROWS,
    Measurement,
    _check_currents,
    _measure,
    _n_kinds,
    command_reference,
    control_step,
    control_step_batch,
    control_step_rows,
    control_step_serial,
    episode_steps,
    initial_state,
    neutral_commands,
    pack,
    profile_grid,
    run_constant,
    track_length_needed_m,
)
from hyperloop_env.physics.params import ModelParams
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES
from hyperloop_env.physics.vehicle import (
    NU,
    stage_loads_size,
)

X_START_M = 10.0
"""Default initial capsule-centre position [m] (``SimulationParams.start_position_m``):
both levitation sets on the first span."""


class Simulator:
    """One hyperloop vehicle over a flexible multi-span guideway.

    >>> sim = Simulator()
    >>> m = sim.reset(seed=0)
    >>> m = sim.step([sim.nominal_current_A] * 4)   # passive: constant I0
    >>> m.gap_excursion_m.shape
    (4,)

    ``step`` takes one command per channel of ``params.actuators`` (the four levitation
    coil currents [A] by default, names in :attr:`command_names`); actuator kinds outside
    the set stay at their neutral command. ``reset(seed, profile_offset=...)`` adds a
    deterministic guideway profile (e.g. a disturbance's realisation) to the irregularity.
    """

    unit_names = UNIT_NAMES

    def __init__(self, params: ModelParams | None = None) -> None:
        self._set_params(params if params is not None else ModelParams())
        self._ready = False

    def _set_params(self, params: ModelParams) -> None:
        if not isinstance(params, ModelParams):
            raise ValueError(f"params must be a ModelParams, got {params!r}")
        self.params = params
        self.P = pack(params)
        nm = params.guideway.n_modes
        self.n_state = state_size(nm)
        n_kinds = _n_kinds(self.P)
        self.n_commands = n_kinds * N_UNITS
        self.y = np.zeros(self.n_state)
        self.aux = np.zeros(aux_size(self.n_commands))
        self.meas = np.zeros(record_size(n_kinds))
        self.work = np.zeros((WORK_ROWS, self.n_state))
        self.wts = np.zeros((N_UNITS, N_SLOTS, nm))  # rhs scratch for callers of rhs
        self.tl = np.zeros((TL_ROWS, stage_loads_size(nm, self.n_commands)))
        self.uo = np.zeros((NU, N_UNITS))
        self.spans = np.zeros(N_SLOTS, dtype=np.int64)
        n, _ = profile_grid(params)
        self.irr = np.zeros((irr_mod.N_ROWS, n))
        acts = params.actuators
        self.command_names: tuple[str, ...] = acts.channel_names
        self._cmd_shape = (acts.size,)
        self._cmd_index = None if acts.is_full else np.array(acts.command_index())
        self._cmd_full = np.zeros(self.n_commands)

    @property
    def track_length_needed_m(self) -> float:
        return track_length_needed_m(self.params)

    @property
    def profile_grid(self) -> tuple[int, float]:
        """(number of points, step [m]) of the guideway profile grid (x = i·step, periodic)."""
        return self.irr.shape[1], float(self.params.irregularity.grid_step_m)

    @property
    def nominal_current_A(self) -> float:
        """I0: the current that carries the vehicle at the nominal gap (equilibrium) [A]."""
        return float(self.P[P_I0])

    @property
    def max_current_A(self) -> float:
        return float(self.P[P_IMAX])

    @property
    def time_s(self) -> float:
        return float(self.aux[A_T])

    @property
    def position_m(self) -> float:
        return float(self.meas[M_X])

    @property
    def episode_steps(self) -> int:
        """Control steps that cover ``SimulationParams.track_length_m``."""
        return episode_steps(self.params)

    def reset(
        self,
        seed: int | None = None,
        params: ModelParams | None = None,
        *,
        profile_offset: np.ndarray | None = None,
    ) -> Measurement:
        """Start a run: draw the irregularity from ``seed``, add ``profile_offset`` (shape
        (3, n) on :attr:`profile_grid`: left vertical, right vertical, lateral [m]) and
        set static equilibrium."""
        if params is not None:
            self._set_params(params)
        rng = np.random.default_rng(seed)
        self.irr[:] = irr_mod.generate(self.params.irregularity, self.track_length_needed_m, rng)[
            :, : self.irr.shape[1]
        ]
        if profile_offset is not None:
            off = np.asarray(profile_offset, dtype=np.float64)
            if off.shape != self.irr.shape:
                raise ValueError(
                    f"profile_offset must have shape {self.irr.shape} (rows left vertical, "
                    f"right vertical, lateral on the profile grid), got {off.shape}"
                )
            if not np.isfinite(off).all():
                raise ValueError("profile_offset must be finite")
            self.irr += off
        y, aux = initial_state(self.P, self.irr)
        self.y[:] = y
        self.aux[:] = aux
        self.spans[:] = aux[A_SPAN0 : A_SPAN1 + 1].astype(np.int64)
        _measure(
            self.P,
            self.y,
            self.aux,
            self.irr,
            self.meas,
            self.work[0],
            self.tl,
            0,
            self.uo,
            self.spans,
            False,
        )
        self._cmd_full[:] = aux[A_I : A_I + self.n_commands]
        self._ready = True
        return Measurement.from_record(self.meas)

    def _full_command(self, currents: Any) -> np.ndarray:
        arr = _check_currents(currents, self._cmd_shape, self.command_names)
        if self._cmd_index is None:
            return arr
        self._cmd_full[self._cmd_index] = arr
        return self._cmd_full

    def step_record(self, currents: Any) -> np.ndarray:
        """Advance one control interval; return the raw measurement record (a view that the
        next step overwrites; named slices in ``physics.layout.RECORD_FIELDS``).
        ``currents`` [A], one per channel of ``params.actuators``."""
        if not self._ready:
            raise RuntimeError("call reset() before step()")
        arr = self._full_command(currents)
        control_step(
            self.P,
            self.y,
            self.aux,
            self.irr,
            arr,
            self.meas,
            self.work,
            self.tl,
            self.uo,
            self.spans,
        )
        return self.meas

    def step_full(self, commands: np.ndarray) -> np.ndarray:
        """Advance with an already validated, finite full command vector (n_commands,) [A]
        (the environments' fast path); returns the record like :meth:`step_record`."""
        control_step(
            self.P,
            self.y,
            self.aux,
            self.irr,
            commands,
            self.meas,
            self.work,
            self.tl,
            self.uo,
            self.spans,
        )
        return self.meas

    @property
    def neutral_command(self) -> np.ndarray:
        """Full command vector with every channel at its neutral command [A] (a copy)."""
        return neutral_commands(self.P)

    @property
    def command_reference_A(self) -> np.ndarray:
        """Reference current of each channel of ``params.actuators`` [A]: the base of the
        environment's action map (I0 for the levitation coils)."""
        return command_reference(self.P, self.params.actuators)

    def step(self, currents: Any) -> Measurement:
        """Advance one control interval with the commanded currents [A] (by default the
        four levitation coil currents FL, FR, RL, RR)."""
        return Measurement.from_record(self.step_record(currents))

    def run(self, currents: Any, n_steps: int) -> np.ndarray:
        """Advance ``n_steps`` with constant currents; return records, shape (n, NM)."""
        if not self._ready:
            raise RuntimeError("call reset() before run()")
        arr = self._full_command(currents).copy()
        if isinstance(n_steps, bool) or not isinstance(n_steps, int | np.integer) or n_steps < 1:
            raise ValueError(f"n_steps must be an int >= 1, got {n_steps!r}")
        out = np.zeros((int(n_steps), self.meas.shape[0]))
        done = run_constant(
            self.P,
            self.y,
            self.aux,
            self.irr,
            arr,
            int(n_steps),
            out,
            self.work,
            self.tl,
            self.uo,
            self.spans,
        )
        if done:
            self.meas[:] = out[done - 1]
        return out[:done]


class BatchSimulator:
    """N independent vehicles advanced together in one compiled, parallel call.

    Every vehicle may have its own :class:`ModelParams` (speed, curve, mass, …) as long as
    they share the number of guideway modes, the irregularity grid size and the actuator
    set. ``step`` takes the commands of every vehicle, shape (N, n_channels).
    """

    unit_names = UNIT_NAMES

    def __init__(self, params: ModelParams | list[ModelParams] | None = None, n: int = 1) -> None:
        if isinstance(params, list | tuple):
            plist = list(params)
        else:
            if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
                raise ValueError(f"n must be a positive int, got {n!r}")
            plist = [params if params is not None else ModelParams()] * int(n)
        if not plist:
            raise ValueError("params must not be an empty list")
        self.n = len(plist)
        self._singles = [Simulator(p) for p in plist]
        self._check_compatible(self._singles)
        s0 = self._singles[0]
        self.command_names = s0.command_names
        self.n_commands = s0.n_commands
        self.P = np.stack([s.P for s in self._singles])
        self.Y = aligned_zeros((self.n, s0.n_state))
        self.AUX = aligned_zeros((self.n, *s0.aux.shape))
        self.IRR = aligned_zeros((self.n, *s0.irr.shape))
        self.MEAS = aligned_zeros((self.n, *s0.meas.shape))
        self.WORK = aligned_zeros((self.n, WORK_ROWS, s0.n_state))
        self.TL = aligned_zeros((self.n, *s0.tl.shape))
        self.UO = aligned_zeros((self.n, NU, N_UNITS))
        self.SPANS = aligned_zeros((self.n, N_SLOTS), np.int64)
        self._cmd_index = s0._cmd_index
        self.CMD = aligned_zeros((self.n, s0.n_commands))
        self._ready = np.zeros(self.n, dtype=bool)

    @staticmethod
    def _check_compatible(sims: list[Simulator]) -> None:
        s0 = sims[0]
        for i, s in enumerate(sims):
            if (
                s.n_state != s0.n_state
                or s.irr.shape != s0.irr.shape
                or s.params.actuators != s0.params.actuators
                or s.P.shape != s0.P.shape
            ):
                raise ValueError(
                    f"params[{i}] is incompatible with params[0]: all vehicles of a batch need "
                    "the same GuidewayParams.n_modes, irregularity grid size and actuators"
                )

    @property
    def nominal_current_A(self) -> np.ndarray:
        return self.P[:, P_I0].copy()

    def reset_one(
        self,
        i: int,
        seed: int | None = None,
        params: ModelParams | None = None,
        *,
        profile_offset: np.ndarray | None = None,
    ) -> None:
        """Reset vehicle i (optionally with new parameters, which must stay compatible)."""
        s = self._singles[i]
        s.reset(seed, params, profile_offset=profile_offset)
        if params is not None:
            self._check_compatible([self._singles[0], s])
            self.P[i] = s.P
        self.Y[i] = s.y
        self.AUX[i] = s.aux
        self.IRR[i] = s.irr
        self.MEAS[i] = s.meas
        self.SPANS[i] = s.spans
        self.CMD[i] = s._cmd_full
        self._ready[i] = True

    def reset(self, seeds: list[int | None] | None = None) -> np.ndarray:
        """Reset all vehicles; ``seeds[i]`` seeds vehicle i. Returns records (N, NM)."""
        if seeds is None:
            seeds = [None] * self.n
        if len(seeds) != self.n:
            raise ValueError(f"seeds must have length {self.n}, got {len(seeds)}")
        for i, sd in enumerate(seeds):
            self.reset_one(i, sd)
        return self.MEAS.copy()

    def full_commands(self, currents: Any) -> np.ndarray:
        """Validated full command array (N, n_commands) for ``currents`` (N, n_channels)."""
        arr = _check_currents(currents, (self.n, len(self.command_names)), self.command_names)
        if self._cmd_index is None:
            return arr
        self.CMD[:, self._cmd_index] = arr
        return self.CMD

    def step(self, currents: Any) -> np.ndarray:
        """Advance all vehicles one control interval; ``currents`` [A] of shape
        (N, n_channels). Returns the records (N, NM) (a view the next step overwrites)."""
        if not self._ready.all():
            raise RuntimeError("call reset() before step()")
        arr = self.full_commands(currents)
        self.step_full(arr)
        return self.MEAS

    def step_full(
        self, commands: np.ndarray, parallel: bool = True, rows: np.ndarray | None = None
    ) -> np.ndarray:
        """Advance with an already validated full command array (N, n_commands) (the
        environments' fast path); ``parallel=False`` runs the same kernel on one thread.
        ``rows`` (int64 indices): advance only these vehicles, on one thread; the others keep
        their state and records (a rollout engine's idle rows)."""
        args = (self.P, self.Y, self.AUX, self.IRR, commands, self.MEAS, self.WORK, self.TL)
        if rows is not None:
            control_step_rows(*args, self.UO, self.SPANS, rows)
        else:
            kernel = control_step_batch if parallel else control_step_serial
            kernel(*args, self.UO, self.SPANS)
        return self.MEAS
