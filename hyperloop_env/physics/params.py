"""Typed, validated parameters of the vehicle–guideway model.

Sign conventions (used everywhere in :mod:`hyperloop_env.physics`)
------------------------------------------------------------------
* ``x`` [m]   along the guideway, direction of travel; the capsule centre is at
  ``x_c = x_start + v·t``.
* ``y`` [m]   normal to the guideway ("vertical", the magnets' gap direction), **up**
  positive; gravity acts along −y. All vertical displacements are measured from the
  static equilibrium configuration on a straight, rigid, level guideway.
* ``z`` [m]   lateral, positive to the **right** of the direction of travel
  (x forward, y up, z right is right-handed).
* pitch  [rad] positive nose-up: a corner at longitudinal offset ``x_a`` moves ``+x_a·pitch``.
* roll   [rad] positive left-side-up: a corner at lateral offset ``z_a`` moves ``−z_a·roll``.
* yaw    [rad] positive nose-right: a corner at ``x_a`` moves laterally ``+x_a·yaw``.
* Gap excursion ``s_a = δ_a − δ0`` [m], positive when the air gap opens.
* Units ``FL, FR, RL, RR`` = front/rear levitation set × left/right; front set at
  ``+d1/2``, left side at ``z = −d2/2``.

All dataclasses are frozen and validate on construction: an invalid value raises
``ValueError`` whose message names the field and the value.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field, fields, replace
from typing import Any, Literal

import numpy as np

from hyperloop_env.physics.actuators import DEFAULT_ACTUATORS, ActuatorSet
from hyperloop_env.physics.units import N_UNITS, UNIT_NAMES  # noqa: F401  (re-exported)

MU0 = 4e-7 * math.pi
"""Vacuum permeability μ0 [H/m] (paper eq. 3)."""

MagnetOrientation = Literal["repelling", "attracting"]

CLEARANCE_M = 0.008
"""The paper's clearance Ω = 8 mm (§5): the levitation gap excursion and the guidance
magnets' lateral displacement must stay below it."""

MIN_EXIT_SPEED_FRACTION = 0.25
"""Slowest speed at the end of a braked track section, as a fraction of the entry speed:
v_end = √(v0² + 2·a·L) >= MIN_EXIT_SPEED_FRACTION·v0 (v0, v_end [m/s], a [m/s²] < 0 brakes,
L = ``track_length_m`` [m]). ``ModelParams`` refuses a section that brakes below it (the
episode's time and step count grow without bound as v_end → 0)."""


def is_real(value: Any) -> bool:
    """True for a real number: int, float or a NumPy integer/floating scalar (not bool)."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_)


def _check_finite(obj: object, name: str, value: float) -> None:
    if not is_real(value):
        raise ValueError(f"{type(obj).__name__}.{name} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{type(obj).__name__}.{name} must be finite, got {value!r}")
    if isinstance(value, np.generic):
        # a NumPy scalar is stored as a Python float: float32 arithmetic must not leak
        # into the model
        object.__setattr__(obj, name, float(value))


def _check_int(obj: object, name: str) -> None:
    value = getattr(obj, name)
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{type(obj).__name__}.{name} must be an int, got {value!r}")
    if not isinstance(value, int):
        object.__setattr__(obj, name, int(value))


def _check_positive(obj: object, *names: str) -> None:
    for name in names:
        value = getattr(obj, name)
        _check_finite(obj, name, value)
        if value <= 0:
            raise ValueError(f"{type(obj).__name__}.{name} must be > 0, got {value!r}")


def _check_nonnegative(obj: object, *names: str) -> None:
    for name in names:
        value = getattr(obj, name)
        _check_finite(obj, name, value)
        if value < 0:
            raise ValueError(f"{type(obj).__name__}.{name} must be >= 0, got {value!r}")


@dataclass(frozen=True)
class VehicleParams:
    """Capsule and levitation frames (paper Table 1; eq. 7–10).

    The capsule (carriage body) has heave, lateral, pitch, roll and yaw. The levitation
    frames (total ``frame_mass_kg``) are lumped into four magnet units of a quarter each,
    tied to the capsule corner above them by the primary suspension in y (totals
    ``primary_*``, a quarter per corner) and the secondary suspension in z (totals
    ``secondary_*``). Roll and yaw inertia follow paper eq. 9 with the documented width
    and height (not given by the paper); pitch inertia is Table 1's value.

    Payload (the ``payload`` disturbance): ``payload_kg`` of extra capsule mass the nominal
    design does not know (the nominal currents are sized for the empty vehicle, so the
    passive vehicle sags under it) and the capsule's centre of gravity off the geometric
    centre by ``cg_offset_x_m`` (+ forward) and ``cg_offset_z_m`` (+ right). The corners
    then carry the static loads P_a = (W/4)·(1 + s_x·x_cg/(d1/2) + s_z·z_cg/(d2/2))
    (s_x, s_z = ±1 the corner's side): ΣP_a = W, Σ(x_a − x_cg)P_a = 0, Σ(z_a − z_cg)P_a = 0
    and no twist — the distribution four equal supports under a rigid body take. The
    capsule's rotations are about its centre of gravity. The inertias are not changed by
    the payload (a compact load near the floor; documented simplification).
    """

    capsule_mass_kg: float = 15_000.0  # m_v, Table 1
    capsule_pitch_inertia_kgm2: float = 1.75e6  # I_v, Table 1
    capsule_length_m: float = 25.0  # L, Table 1
    capsule_width_m: float = 2.7  # b, eq. 9 (assumed; Hyperloop Alpha-size capsule)
    capsule_height_m: float = 2.7  # h, eq. 9 (assumed)
    frame_mass_kg: float = 22_000.0  # m_m, Table 1 (all four units together)
    primary_stiffness_N_per_m: float = 1.18e8  # K_h, Table 1 (total)
    primary_damping_Ns_per_m: float = 2.15e6  # C_h, Table 1 (total)
    secondary_stiffness_N_per_m: float = 6.812e5  # K_z, Table 1 (total)
    secondary_damping_Ns_per_m: float = 8.46e4  # c_z, Table 1 (total)
    set_spacing_m: float = 16.0  # d1: front–rear levitation-set distance (assumed)
    track_gauge_m: float = 2.0  # d2: left–right magnet distance (assumed, 3.3 m tube)
    payload_kg: float = 0.0  # extra capsule mass unknown to the nominal design [kg]
    cg_offset_x_m: float = 0.0  # capsule centre of gravity ahead of the centre [m]
    cg_offset_z_m: float = 0.0  # capsule centre of gravity right of the centre [m]

    def __post_init__(self) -> None:
        _check_positive(
            self,
            *(f.name for f in fields(self) if f.name not in _PAYLOAD_FIELDS),
        )
        _check_nonnegative(self, "payload_kg")
        _check_finite(self, "cg_offset_x_m", self.cg_offset_x_m)
        _check_finite(self, "cg_offset_z_m", self.cg_offset_z_m)
        if abs(self.cg_offset_x_m) >= 0.5 * self.set_spacing_m:
            raise ValueError(
                f"VehicleParams.cg_offset_x_m must be within ±set_spacing_m/2 "
                f"({0.5 * self.set_spacing_m!r}), got {self.cg_offset_x_m!r}"
            )
        if abs(self.cg_offset_z_m) >= 0.5 * self.track_gauge_m:
            raise ValueError(
                f"VehicleParams.cg_offset_z_m must be within ±track_gauge_m/2 "
                f"({0.5 * self.track_gauge_m!r}), got {self.cg_offset_z_m!r}"
            )
        if self.set_spacing_m >= self.capsule_length_m:
            raise ValueError(
                f"VehicleParams.set_spacing_m must be < capsule_length_m "
                f"({self.capsule_length_m!r}), got {self.set_spacing_m!r}"
            )

    @property
    def roll_inertia_kgm2(self) -> float:
        """J_r = m_v (h² + b²)/12 [kg·m²] (paper eq. 9)."""
        return self.capsule_mass_kg * (self.capsule_height_m**2 + self.capsule_width_m**2) / 12

    @property
    def yaw_inertia_kgm2(self) -> float:
        """J_y = m_v (L² + b²)/12 [kg·m²] (paper eq. 9)."""
        return self.capsule_mass_kg * (self.capsule_length_m**2 + self.capsule_width_m**2) / 12

    @property
    def total_mass_kg(self) -> float:
        """Nominal mass m_v + m_m [kg] (the design the nominal currents are sized for)."""
        return self.capsule_mass_kg + self.frame_mass_kg

    @property
    def loaded_capsule_mass_kg(self) -> float:
        """Capsule mass with the payload [kg] (what the dynamics carry)."""
        return self.capsule_mass_kg + self.payload_kg


_PAYLOAD_FIELDS = ("payload_kg", "cg_offset_x_m", "cg_offset_z_m")


@dataclass(frozen=True)
class MagnetParams:
    """Levitation magnets (paper eq. 3–6), one per unit.

    Force law (a two-gap magnet; paper eq. 3–5 with the overlap area ``A_a`` in the
    reluctance, ``R_a = 2δ_a/(μ0 A_a)``), all from one energy function
    ``W(δ, z) = μ0 N² I² A_a(z) / (4 δ)`` at constant current::

        F_y = μ0 N² I² A_a / (4 δ²)                    [N]   (eq. 3, 4, 5)
        A_a = a2 (b2 − |z|_s)                           [m²]  (paper, after eq. 3)
        F_z = σ·μ0 N² I² a2 (2/π) arctan(z/δ0) / (4 δ)  [N]   (edge force)

    with ``|z|_s`` the fringing-smoothed overlap loss whose derivative is
    ``(2/π)·arctan(z/δ0)``. The edge force is the lateral gradient of the same energy, so
    its sign follows the orientation (σ below; docs/model.md, revised 2026-11-28): an
    attracting magnet's co-energy grows with the overlap and pulls the unit back over its
    rail (restoring, ``F_z = +∂W/∂z``); a repelling magnet's stored energy shrinks with the
    overlap and pushes it further off (destabilising, ``F_z = −∂W/∂z``). Either way the
    work of (F_y, F_z) around a closed loop in (gap, lateral) is zero. Lateral guidance is
    the job of the guidance magnets (:class:`GuidanceParams`).

    ``orientation``: ``"repelling"`` (default; the high-speed electrodynamic limit: the
    force pushes the magnet away from the guide and falls as the gap opens — statically
    stable, so constant current is a real passive suspension) or ``"attracting"``
    (iron-core EMS, eq. 3–6 verbatim: open-loop unstable at constant current).
    """

    orientation: MagnetOrientation = "repelling"
    turns: float = 400.0  # N
    nominal_gap_m: float = 0.010  # δ0
    pole_length_m: float = 1.1  # a2, along x (also the load length La of eq. 12)
    pole_width_m: float = 0.10  # b2, across z; A0 = a2·b2 = 0.11 m²
    max_current_A: float = 100.0  # physical limit: currents are clipped to [0, max]
    clearance_m: float = CLEARANCE_M  # Ω: contact when |s| >= Ω (paper §5)
    coil_time_constant_s: float = 0.0  # first-order current lag τ (0 = ideal current source)

    def __post_init__(self) -> None:
        if self.orientation not in ("repelling", "attracting"):
            raise ValueError(
                f"MagnetParams.orientation must be 'repelling' or 'attracting', "
                f"got {self.orientation!r}"
            )
        _check_positive(
            self,
            "turns",
            "nominal_gap_m",
            "pole_length_m",
            "pole_width_m",
            "max_current_A",
            "clearance_m",
        )
        _check_nonnegative(self, "coil_time_constant_s")
        if self.clearance_m >= self.nominal_gap_m:
            raise ValueError(
                f"MagnetParams.clearance_m must be < nominal_gap_m ({self.nominal_gap_m!r}), "
                f"got {self.clearance_m!r}"
            )

    @property
    def pole_area_m2(self) -> float:
        """A0 = a2·b2 [m²]."""
        return self.pole_length_m * self.pole_width_m

    @property
    def orientation_sign(self) -> float:
        """σ in s = σ·(y_unit − w − r): +1 repelling (magnet above the guide), −1 attracting."""
        return 1.0 if self.orientation == "repelling" else -1.0

    def inductance_H(self) -> float:
        """Coil inductance at the nominal gap, L0 = μ0 N² A0 / (2 δ0) [H]."""
        return MU0 * self.turns**2 * self.pole_area_m2 / (2.0 * self.nominal_gap_m)


@dataclass(frozen=True)
class GuidanceParams:
    """Guidance magnets (paper §5: the "guidance magnet" whose lateral displacement "does not
    exceed 8 mm"; docs/model.md).

    Each unit carries a pair: one magnet facing the left guide rail, one the right, at the
    nominal gap ``δg0`` each, with the levitation magnets' length ``a2`` along x and a pole
    height ``h_g`` (area ``A_g = a2·h_g``), the same force law (eq. 3–5)::

        δ_L = δg0 + z,  δ_R = δg0 − z            (z: the unit's lateral offset from the
                                                   guideway, + to the right) [m]
        I_L = I_g0 + ΔI,  I_R = I_g0 − ΔI        (ΔI: the pair's differential command) [A]
        F_side = μ0 N_g² I_side² A_g / (4 δ_side²) [N]
        F_z = σ·(F_L − F_R)  on the unit, −F_z on the guideway's lateral modes [N]

    with σ = +1 ``repelling`` (each magnet pushes the unit away from its rail: restoring,
    lateral stiffness 4·F_g0/δg0 per pair at bias) and σ = −1 ``attracting`` (each pulls
    towards its rail: open-loop unstable, −4·F_g0/δg0), following ``MagnetParams.orientation``.
    Contact: |z| ≥ ``clearance_m`` (Ω_g = 8 mm, the paper's figure). The currents are limited
    to [0, ``max_current_A``], so |ΔI| ≤ min(I_g0, I_max − I_g0).

    **Design rule** (sizing the bias current I_g0; :func:`hyperloop_env.physics.magnets.
    guidance_bias_current_A`): the *passive repelling* vehicle at bias current holds the
    largest lateral demand of the paper's conditions — ``design_speed_kmh`` = 2000 km/h on
    ``design_radius_m`` = 200 km without cant, a = v²/R = 555.6²/2e5 = 1.543 m/s² on the
    ``design_mass_kg`` = 37 t vehicle — in quasi-static equilibrium at no more than
    ``design_offset_fraction`` = ½ of the guidance clearance (z_d = 4 mm), against the
    destabilising edge force of the levitation magnets::

        demand per unit   m·a/4                    = 37 000 · 1.543 / 4        = 14 275 N
        edge force at z_d F0·(δ0/b2)·(2/π)·atan(z_d/δ0), F0 = m·g/4 = 90 743 N  =  2 198 N
        pair force at z_d F_g0·[(δg0/(δg0−z_d))² − (δg0/(δg0+z_d))²] = 2.2676·F_g0
        ⇒ F_g0 = (14 275 + 2 198) / 2.2676 = 7 265 N per magnet
        I_g0 = δg0·√(F_g0/(μ0 N_g²/4 · A_g)) = 0.01·√(7265/(0.050265·0.055)) = 16.2 A
              (0.41 T in the gap); lateral stiffness 4·F_g0/δg0 = 2.91 MN/m per unit
              against the edge force's −F0·(2/π)/b2 = −0.58 MN/m.

    ``bias_current_A`` overrides the rule (None: sized by it). The critical radius that
    follows is a result (``python -m agents.reproduce_paper``), not a design input.
    """

    turns: float = 400.0  # N_g
    nominal_gap_m: float = 0.010  # δg0
    pole_height_m: float = 0.05  # h_g (the length along x is MagnetParams.pole_length_m)
    max_current_A: float = 40.0  # per magnet
    clearance_m: float = CLEARANCE_M  # Ω_g: contact when |z| >= Ω_g
    bias_current_A: float | None = None  # I_g0; None = sized by the design rule
    design_speed_kmh: float = 2000.0
    design_radius_m: float = 200_000.0
    design_mass_kg: float = 37_000.0
    design_offset_fraction: float = 0.5

    def __post_init__(self) -> None:
        _check_positive(
            self,
            "turns",
            "nominal_gap_m",
            "pole_height_m",
            "max_current_A",
            "clearance_m",
            "design_speed_kmh",
            "design_radius_m",
            "design_mass_kg",
            "design_offset_fraction",
        )
        if self.clearance_m >= self.nominal_gap_m:
            raise ValueError(
                f"GuidanceParams.clearance_m must be < nominal_gap_m ({self.nominal_gap_m!r}), "
                f"got {self.clearance_m!r}"
            )
        if self.design_offset_fraction >= 1.0:
            raise ValueError(
                "GuidanceParams.design_offset_fraction must be in (0, 1), "
                f"got {self.design_offset_fraction!r}"
            )
        if self.bias_current_A is not None:
            _check_positive(self, "bias_current_A")
            if self.bias_current_A >= self.max_current_A:
                raise ValueError(
                    f"GuidanceParams.bias_current_A must be < max_current_A "
                    f"({self.max_current_A!r}), got {self.bias_current_A!r}"
                )

    @property
    def design_lateral_acceleration_m_s2(self) -> float:
        """v²/R of the design condition [m/s²]."""
        return (self.design_speed_kmh / 3.6) ** 2 / self.design_radius_m


@dataclass(frozen=True)
class FaultParams:
    """An actuator fault (the ``actuator_fault`` disturbance): from ``time_s`` on, the
    levitation coil of unit ``unit`` (index in FL, FR, RL, RR; −1: no fault) keeps only
    ``range_fraction`` of its current range around I0 — its command is limited to
    [I0·(1 − f), I0 + f·(I_max − I0)] — or, with ``freeze``, holds the current it had at
    ``time_s`` whatever the controller commands."""

    unit: int = -1
    time_s: float = 0.0
    range_fraction: float = 1.0
    freeze: bool = False

    def __post_init__(self) -> None:
        _check_int(self, "unit")
        if not -1 <= self.unit < N_UNITS:
            raise ValueError(f"FaultParams.unit must be -1 or in [0, {N_UNITS}), got {self.unit!r}")
        _check_nonnegative(self, "time_s", "range_fraction")
        if self.range_fraction > 1.0:
            raise ValueError(
                f"FaultParams.range_fraction must be in [0, 1], got {self.range_fraction!r}"
            )
        if not isinstance(self.freeze, bool | np.bool_):
            raise ValueError(f"FaultParams.freeze must be a bool, got {self.freeze!r}")
        object.__setattr__(self, "freeze", bool(self.freeze))


@dataclass(frozen=True)
class GuidewayParams:
    """Multi-span simply supported Euler–Bernoulli guideway (paper eq. 11, 12, 15, 16).

    Defaults: a 3.3 m steel tube with a ~24 mm wall on piers every 30 m (Hyperloop Alpha):
    EI ≈ 6.5e10 N·m², ρA ≈ 1.9 t/m, f1 = (π/(2L²))·√(EI/ρA) ≈ 10.2 Hz. The same section
    bends laterally (a round tube): ``lateral_bending_stiffness_Nm2`` defaults to EI.
    ``rigid=True`` removes the beam (w ≡ 0), for verification.
    """

    span_m: float = 30.0
    bending_stiffness_Nm2: float = 6.5e10
    lateral_bending_stiffness_Nm2: float = 6.5e10
    mass_per_length_kg_per_m: float = 1900.0
    damping_ratio: float = 0.01
    n_modes: int = 6
    rigid: bool = False

    def __post_init__(self) -> None:
        _check_positive(
            self,
            "span_m",
            "bending_stiffness_Nm2",
            "lateral_bending_stiffness_Nm2",
            "mass_per_length_kg_per_m",
        )
        _check_nonnegative(self, "damping_ratio")
        if self.damping_ratio >= 1.0:
            raise ValueError(
                f"GuidewayParams.damping_ratio must be < 1, got {self.damping_ratio!r}"
            )
        _check_int(self, "n_modes")
        if not 1 <= self.n_modes <= 40:
            raise ValueError(f"GuidewayParams.n_modes must be in [1, 40], got {self.n_modes!r}")

    def natural_frequency_hz(self, k: int, lateral: bool = False) -> float:
        """f_k = (k²π/(2L²))·√(EI/ρA) [Hz] (simply supported Euler–Bernoulli beam)."""
        ei = self.lateral_bending_stiffness_Nm2 if lateral else self.bending_stiffness_Nm2
        return k**2 * math.pi / (2 * self.span_m**2) * math.sqrt(ei / self.mass_per_length_kg_per_m)


@dataclass(frozen=True)
class OperatingCondition:
    """Speed and horizontal alignment.

    The track is straight up to ``curve_start_m``, then a clothoid transition of
    ``transition_length_m`` in which curvature and cant grow linearly, then a circular curve
    of radius ``curve_radius_m`` (``math.inf`` = straight) with cant ``cant_deg``. The curve
    turns to the left, so the centrifugal load pushes the vehicle to +z (right).

    The vehicle enters the section at ``speed_kmh`` and accelerates uniformly at
    ``acceleration_m_s2`` (braking if negative): x_c(t) = x_0 + v_0·t + a·t²/2,
    v(t) = v_0 + a·t; the speed must stay above a quarter of v_0 over the section
    (:data:`MIN_EXIT_SPEED_FRACTION`, checked with the track length by ``ModelParams``).
    """

    speed_kmh: float = 1000.0
    curve_radius_m: float = math.inf
    cant_deg: float = 0.0
    transition_length_m: float = 500.0
    curve_start_m: float = 100.0
    acceleration_m_s2: float = 0.0  # along the track; < 0 brakes (the speed_profile family)

    def __post_init__(self) -> None:
        _check_positive(self, "speed_kmh", "transition_length_m")
        _check_nonnegative(self, "curve_start_m")
        _check_finite(self, "acceleration_m_s2", self.acceleration_m_s2)
        if abs(self.acceleration_m_s2) > 20.0:
            raise ValueError(
                "OperatingCondition.acceleration_m_s2 must be within ±20 m/s² (≈ 2 g), got "
                f"{self.acceleration_m_s2!r}"
            )
        value = self.curve_radius_m
        if not is_real(value) or math.isnan(value):
            raise ValueError(f"OperatingCondition.curve_radius_m must be a number, got {value!r}")
        if isinstance(value, np.generic):
            object.__setattr__(self, "curve_radius_m", float(value))
            value = self.curve_radius_m
        if value <= 0:
            raise ValueError(
                f"OperatingCondition.curve_radius_m must be > 0 (math.inf for straight), "
                f"got {value!r}"
            )
        _check_finite(self, "cant_deg", self.cant_deg)
        if abs(self.cant_deg) >= 30.0:
            raise ValueError(
                f"OperatingCondition.cant_deg must be in (-30, 30), got {self.cant_deg!r}"
            )

    @property
    def speed_m_s(self) -> float:
        return self.speed_kmh / 3.6

    @property
    def curvature_per_m(self) -> float:
        return 0.0 if math.isinf(self.curve_radius_m) else 1.0 / self.curve_radius_m


IRREGULARITY_CLASSES: dict[str, tuple[float, float, float]] = {
    # name: (A_v [m²·rad/m], A_a [m²·rad/m], PSD scale). German high-speed spectra
    # S(Ω) = A·Ωc²/((Ω²+Ωr²)(Ω²+Ωc²)), Ωc = 0.8246, Ωr = 0.0206 rad/m.
    "none": (0.0, 0.0, 0.0),
    "maglev": (4.032e-7, 2.119e-7, 0.01),  # German "low" at 10 % amplitude (default)
    "maglev-rough": (4.032e-7, 2.119e-7, 0.0625),  # German "low" at 25 % amplitude
    "german-low": (4.032e-7, 2.119e-7, 1.0),
    "german-high": (1.080e-6, 6.125e-7, 1.0),
}


@dataclass(frozen=True)
class IrregularityParams:
    """Stochastic guideway irregularity (vertical per side, lateral alignment shared).

    ``spectrum`` names a class of :data:`IRREGULARITY_CLASSES`, ``amplitude`` scales its
    profile (the PSD by ``amplitude²``: the roughness severity); the one-sided PSD is
    generated over wavelengths ``[min_wavelength_m, max_wavelength_m]``. The magnet
    averages the gap over its ~1.1 m length, so wavelengths under ~2 m are filtered out
    by default. ``grid_step_m`` is the spacing of the precomputed profile (linear
    interpolation between points).
    """

    spectrum: str = "maglev"
    amplitude: float = 1.0  # factor on the class's profile amplitude (PSD × amplitude²)
    min_wavelength_m: float = 2.0
    max_wavelength_m: float = 200.0
    grid_step_m: float = 0.1
    omega_c: float = 0.8246
    omega_r: float = 0.0206

    def __post_init__(self) -> None:
        if self.spectrum not in IRREGULARITY_CLASSES:
            raise ValueError(
                f"IrregularityParams.spectrum must be one of {sorted(IRREGULARITY_CLASSES)}, "
                f"got {self.spectrum!r}"
            )
        _check_positive(
            self, "min_wavelength_m", "max_wavelength_m", "grid_step_m", "omega_c", "omega_r"
        )
        _check_nonnegative(self, "amplitude")
        if self.max_wavelength_m <= self.min_wavelength_m:
            raise ValueError(
                f"IrregularityParams.max_wavelength_m must be > min_wavelength_m "
                f"({self.min_wavelength_m!r}), got {self.max_wavelength_m!r}"
            )
        if self.grid_step_m > self.min_wavelength_m / 8:
            raise ValueError(
                f"IrregularityParams.grid_step_m must be <= min_wavelength_m/8 "
                f"({self.min_wavelength_m / 8!r}), got {self.grid_step_m!r}"
            )


@dataclass(frozen=True)
class SimulationParams:
    """Time stepping. One control step lasts ``control_dt_s``; inside it the state is
    advanced by ``substeps`` classical Runge–Kutta (RK4) steps.

    Two substeps per 1 ms (h = 0.5 ms; 4 until the kernel speed-up of issue "A benchmark
    that decides", point 7): the stiffest part of the model is the highest guideway mode
    (mode 6 of the default 30 m span, 367 Hz, ω ≈ 2309 rad/s), ω·h ≈ 1.15, inside RK4's
    stability limit 2.83 on the imaginary axis (ModelParams keeps ω·h ≤ 2); the vehicle's
    eigenvalues (primary and secondary suspension, magnets) have |λ|·h ≤ 0.07 and the coil
    lag is integrated in closed form. RK4's own damping and phase error per mode at
    h = 0.5 ms: mode 6 +0.012 damping ratio (on its physical 0.01) and −0.85 % frequency,
    mode 5 +0.002 and −0.27 %, modes 1–4 below 2.4e-4 and 0.05 %. Verification case
    ``integrator_vs_radau`` (1 s at 1000 km/h with irregularity, against Radau at rtol 1e-8):
    RMS gap error 6.3e-6 of the RMS gap (4 substeps: 5.8e-7; limit 1e-2). Half the
    right-hand-side evaluations of 4 substeps."""

    control_dt_s: float = 1e-3
    substeps: int = 2
    gravity_m_s2: float = 9.81
    track_length_m: float = 2_000.0  # length of guideway generated for one run
    start_position_m: float = 10.0  # initial capsule-centre position x_c(0) [m]

    def __post_init__(self) -> None:
        _check_positive(self, "control_dt_s", "gravity_m_s2", "track_length_m")
        _check_nonnegative(self, "start_position_m")
        _check_int(self, "substeps")
        if self.substeps < 1:
            raise ValueError(f"SimulationParams.substeps must be >= 1, got {self.substeps!r}")
        if self.control_dt_s > 0.02:
            raise ValueError(
                f"SimulationParams.control_dt_s must be <= 0.02 s, got {self.control_dt_s!r}"
            )


@dataclass(frozen=True)
class ModelParams:
    """All parameters of one vehicle–guideway run."""

    vehicle: VehicleParams = field(default_factory=VehicleParams)
    magnet: MagnetParams = field(default_factory=MagnetParams)
    guideway: GuidewayParams = field(default_factory=GuidewayParams)
    condition: OperatingCondition = field(default_factory=OperatingCondition)
    irregularity: IrregularityParams = field(default_factory=IrregularityParams)
    simulation: SimulationParams = field(default_factory=SimulationParams)
    guidance: GuidanceParams = field(default_factory=GuidanceParams)
    fault: FaultParams = field(default_factory=FaultParams)
    actuators: ActuatorSet = DEFAULT_ACTUATORS
    """The kinds of coil current the controller commands (the others stay at bias);
    a string such as ``"levitation"`` is accepted and parsed."""

    def __post_init__(self) -> None:
        if not isinstance(self.actuators, ActuatorSet):
            object.__setattr__(self, "actuators", ActuatorSet.parse(self.actuators))
        for f, cls in (
            ("vehicle", VehicleParams),
            ("magnet", MagnetParams),
            ("guideway", GuidewayParams),
            ("condition", OperatingCondition),
            ("irregularity", IrregularityParams),
            ("simulation", SimulationParams),
            ("guidance", GuidanceParams),
            ("fault", FaultParams),
        ):
            if not isinstance(getattr(self, f), cls):
                raise ValueError(
                    f"ModelParams.{f} must be a {cls.__name__}, got {getattr(self, f)!r}"
                )
        footprint = self.vehicle.set_spacing_m + self.magnet.pole_length_m
        v0 = self.condition.speed_m_s
        acc = self.condition.acceleration_m_s2
        v_end2 = v0 * v0 + 2.0 * acc * self.simulation.track_length_m
        if v_end2 < (MIN_EXIT_SPEED_FRACTION * v0) ** 2:
            raise ValueError(
                f"OperatingCondition.acceleration_m_s2={acc!r} brakes the vehicle below a "
                f"quarter of its entry speed ({v0:.1f} m/s) within track_length_m="
                f"{self.simulation.track_length_m!r}; brake less or shorten the section"
            )
        v_max = max(v0, math.sqrt(v_end2))
        step = v_max * self.simulation.control_dt_s / self.simulation.substeps
        if footprint + step >= self.guideway.span_m:
            raise ValueError(
                "GuidewayParams.span_m must exceed the magnet footprint set_spacing_m + "
                f"pole_length_m + one substep of travel ({footprint + step!r} m), "
                f"got {self.guideway.span_m!r}"
            )

        if not self.guideway.rigid:
            # RK4 is stable for |λh| < 2.8 on the imaginary axis; keep the highest beam
            # mode well inside (accuracy of the modes that matter is far better).
            n = self.guideway.n_modes
            omega_max = (
                2
                * math.pi
                * max(
                    self.guideway.natural_frequency_hz(n),
                    self.guideway.natural_frequency_hz(n, True),
                )
            )
            h = self.simulation.control_dt_s / self.simulation.substeps
            if omega_max * h > 2.0:
                need = math.ceil(omega_max * self.simulation.control_dt_s / 2.0)
                raise ValueError(
                    f"SimulationParams.substeps={self.simulation.substeps!r} is too few for "
                    f"GuidewayParams.n_modes={n} (highest mode {omega_max / (2 * math.pi):.0f} "
                    f"Hz): RK4 would be unstable; use substeps >= {need}"
                )

    def with_(self, **sections: object) -> ModelParams:
        """Copy with whole sections replaced, e.g. ``p.with_(condition=...)``."""
        return replace(self, **sections)  # type: ignore[arg-type]
