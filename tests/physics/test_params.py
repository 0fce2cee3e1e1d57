"""Parameter validation: invalid values raise ValueError naming the field and the value."""

import math

import pytest

from hyperloop_env.physics import (
    GuidanceParams,
    GuidewayParams,
    IrregularityParams,
    MagnetParams,
    ModelParams,
    OperatingCondition,
    SimulationParams,
    VehicleParams,
)


@pytest.mark.parametrize(
    ("cls", "kwargs", "field"),
    [
        (VehicleParams, {"capsule_mass_kg": -1.0}, "capsule_mass_kg"),
        (VehicleParams, {"frame_mass_kg": math.nan}, "frame_mass_kg"),
        (VehicleParams, {"primary_stiffness_N_per_m": math.inf}, "primary_stiffness_N_per_m"),
        (VehicleParams, {"set_spacing_m": 30.0}, "set_spacing_m"),
        (GuidewayParams, {"span_m": 0.0}, "span_m"),
        (GuidewayParams, {"damping_ratio": 1.5}, "damping_ratio"),
        (GuidewayParams, {"n_modes": 0}, "n_modes"),
        (GuidewayParams, {"n_modes": 2.5}, "n_modes"),
        (OperatingCondition, {"speed_kmh": 0.0}, "speed_kmh"),
        (OperatingCondition, {"speed_kmh": -5.0}, "speed_kmh"),
        (OperatingCondition, {"curve_radius_m": 0.0}, "curve_radius_m"),
        (OperatingCondition, {"curve_radius_m": -100.0}, "curve_radius_m"),
        (OperatingCondition, {"curve_radius_m": math.nan}, "curve_radius_m"),
        (OperatingCondition, {"cant_deg": 45.0}, "cant_deg"),
        (MagnetParams, {"clearance_m": 0.010}, "clearance_m"),
        (MagnetParams, {"clearance_m": 0.02}, "clearance_m"),
        (MagnetParams, {"orientation": "sideways"}, "orientation"),
        (MagnetParams, {"turns": -400.0}, "turns"),
        (GuidanceParams, {"clearance_m": 0.02}, "clearance_m"),
        (GuidanceParams, {"bias_current_A": 50.0}, "bias_current_A"),
        (GuidanceParams, {"design_offset_fraction": 1.5}, "design_offset_fraction"),
        (MagnetParams, {"coil_time_constant_s": -1e-3}, "coil_time_constant_s"),
        (IrregularityParams, {"spectrum": "bumpy"}, "spectrum"),
        (IrregularityParams, {"min_wavelength_m": 300.0}, "max_wavelength_m"),
        (SimulationParams, {"control_dt_s": 0.0}, "control_dt_s"),
        (SimulationParams, {"substeps": 0}, "substeps"),
        (SimulationParams, {"track_length_m": math.inf}, "track_length_m"),
    ],
)
def test_invalid_value_names_field(cls, kwargs, field):
    with pytest.raises(ValueError, match=field):
        cls(**kwargs)


def test_error_message_contains_value():
    with pytest.raises(ValueError, match=r"-1500\.0"):
        VehicleParams(capsule_mass_kg=-1500.0)


def test_defaults_are_paper_table_1():
    v = VehicleParams()
    assert (v.capsule_mass_kg, v.frame_mass_kg) == (15_000.0, 22_000.0)
    assert v.capsule_pitch_inertia_kgm2 == 1.75e6
    assert (v.primary_stiffness_N_per_m, v.primary_damping_Ns_per_m) == (1.18e8, 2.15e6)
    assert (v.secondary_stiffness_N_per_m, v.secondary_damping_Ns_per_m) == (6.812e5, 8.46e4)
    assert v.capsule_length_m == 25.0


def test_footprint_must_fit_on_a_span():
    with pytest.raises(ValueError, match="span_m"):
        ModelParams(guideway=GuidewayParams(span_m=15.0))


def test_params_are_frozen():
    p = ModelParams()
    with pytest.raises(AttributeError):
        p.vehicle.capsule_mass_kg = 1.0  # type: ignore[misc]


def test_current_limit_below_equilibrium_current_is_rejected():
    from hyperloop_env.physics import Simulator

    with pytest.raises(ValueError, match="max_current_A"):
        Simulator(ModelParams(magnet=MagnetParams(max_current_A=10.0)))


def test_straight_is_infinite_radius():
    assert OperatingCondition().curvature_per_m == 0.0
    assert OperatingCondition(curve_radius_m=200_000).curvature_per_m == pytest.approx(5e-6)


def test_too_few_substeps_for_the_modes_is_rejected():
    with pytest.raises(ValueError, match="substeps"):
        ModelParams(guideway=GuidewayParams(n_modes=12), simulation=SimulationParams(substeps=1))
    ModelParams(guideway=GuidewayParams(n_modes=12), simulation=SimulationParams(substeps=8))
