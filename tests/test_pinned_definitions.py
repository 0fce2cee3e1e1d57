"""The defaults that define the benchmark, pinned to numbers written here with their source.

A benchmark is its definitions: a clearance of 9 mm instead of 8 mm, a 2 % instead of 1 %
guideway damping or a reward weight of 0.5 instead of 0.05 gives other scores for the same
controller. Every number below is typed in from its source (the paper, docs/model.md, the
README's model table, a docstring's design rule), never read from the code under test, and
compared exactly (or to 1e-9 for derived values computed here by hand). Changing one of
them is a change of the benchmark: update the number here *and* say so in the commit.
"""

from __future__ import annotations

import math

import pytest

import hyperloop_env  # noqa: F401  (registers the env)
from hyperloop_env.config import EnvConfig, RewardWeights
from hyperloop_env.observation import (
    CURVATURE_SCALE_M,
    GAP_RATE_SCALE_M_S,
    OBS_SIZE,
    PREVIEW_DISTANCES_M,
    SPEED_SCALE_M_S,
)
from hyperloop_env.physics.layout import P_CLEAR, P_G, P_GCLEAR, P_I0, P_IG0, P_TAU
from hyperloop_env.physics.model import episode_steps, equilibrium_current_A, guidance_bias_A, pack
from hyperloop_env.physics.params import (
    CLEARANCE_M,
    IRREGULARITY_CLASSES,
    GuidanceParams,
    GuidewayParams,
    IrregularityParams,
    MagnetParams,
    ModelParams,
    OperatingCondition,
    SimulationParams,
    VehicleParams,
)
from hyperloop_env.physics.simulator import Simulator
from hyperloop_env.reward import (
    COMFORT_TERM_CAP,
    CURRENT_TERM_CAP,
    GAP_TERM_CAP,
    REWARD_TERMS,
)
from hyperloop_env.scenarios import (
    DEFAULT_COIL_TIME_CONSTANT_S,
    DEFAULT_IRREGULARITY,
    DEFAULT_SCENARIO,
    PAPER_SCENARIOS,
    RANDOM_IRREGULARITY_CLASSES,
    RANDOM_MASS_FACTOR_RANGE,
    RANDOM_RADIUS_RANGE_M,
    RANDOM_SPEED_RANGE_KMH,
    RANDOM_STRAIGHT_PROBABILITY,
    get_scenario,
)
from hyperloop_env.sts import DEFAULT_CLEARANCE_M

MU0 = 4e-7 * math.pi  # vacuum permeability [H/m] (paper eq. 3; SI value before 2019)
G = 9.81  # [m/s²] (paper)
OMEGA_M = 0.008  # Ω, the paper's clearance (§5): "the gap ... must stay below 8 mm"
OMEGA_G_M = 0.008  # Ω_g, the guidance clearance (§5: lateral displacement "does not exceed 8 mm")


# ---- clearances -----------------------------------------------------------------------------


def test_clearances_are_the_papers_8_mm() -> None:
    assert CLEARANCE_M == OMEGA_M
    assert MagnetParams().clearance_m == OMEGA_M
    assert GuidanceParams().clearance_m == OMEGA_G_M
    assert DEFAULT_CLEARANCE_M == OMEGA_M  # the STS default
    # what the environment actually compiles into its parameter vector
    env_p = EnvConfig().resolve().base
    assert env_p.magnet.clearance_m == OMEGA_M
    assert env_p.guidance.clearance_m == OMEGA_G_M
    P = pack(env_p)
    assert P[P_CLEAR] == OMEGA_M
    assert P[P_GCLEAR] == OMEGA_G_M


def test_clearance_override_reaches_the_kernels() -> None:
    P = pack(EnvConfig(clearance_m=0.006).resolve().base)
    assert P[P_CLEAR] == 0.006
    assert P[P_GCLEAR] == OMEGA_G_M  # the override is the levitation clearance only


# ---- magnets ----------------------------------------------------------------------------------


def test_levitation_magnet_defaults() -> None:
    """README model table / docs/model.md: N = 400, δ0 = 10 mm, poles 1.1 m × 0.1 m, I_max = 100 A,
    repelling by default; the simulator's own coil lag is 0 (ideal current source)."""
    m = MagnetParams()
    assert m.orientation == "repelling"
    assert m.turns == 400.0
    assert m.nominal_gap_m == 0.010
    assert (m.pole_length_m, m.pole_width_m) == (1.1, 0.10)
    assert m.max_current_A == 100.0
    assert m.coil_time_constant_s == 0.0


def test_guidance_magnet_defaults() -> None:
    """GuidanceParams docstring: N_g = 400, δg0 = 10 mm, h_g = 50 mm, 40 A per magnet; the
    design condition 2000 km/h on R = 200 km, 37 t, half the clearance."""
    g = GuidanceParams()
    assert g.turns == 400.0
    assert g.nominal_gap_m == 0.010
    assert g.pole_height_m == 0.05
    assert g.max_current_A == 40.0
    assert g.bias_current_A is None  # sized by the design rule
    assert (g.design_speed_kmh, g.design_radius_m) == (2000.0, 200_000.0)
    assert g.design_mass_kg == 37_000.0
    assert g.design_offset_fraction == 0.5


def test_nominal_current_from_equilibrium_is_40_5_A() -> None:
    """I0 = δ0·√(F0/(μ0N²/4·A0)), F0 = (15 t + 22 t)·g/4 (paper eq. 3–5 at the nominal gap).
    By hand: F0 = 90 742.5 N, μ0N²/4 = 0.0502655, A0 = 0.11 m² → I0 = 40.511 A."""
    f0 = (15_000.0 + 22_000.0) * G / 4.0
    assert f0 == pytest.approx(90_742.5, rel=1e-12)
    i0 = 0.010 * math.sqrt(f0 / (MU0 * 400.0**2 / 4.0 * 1.1 * 0.10))
    assert i0 == pytest.approx(40.5111, abs=1e-4)
    p = ModelParams()
    assert equilibrium_current_A(p) == pytest.approx(i0, rel=1e-12)
    assert Simulator(p).nominal_current_A == pytest.approx(i0, rel=1e-12)
    # the environment's I0 (action 0) is the same number
    env_p = EnvConfig().resolve().base
    assert pack(env_p)[P_I0] == pytest.approx(i0, rel=1e-12)


def test_guidance_bias_current_by_the_design_rule_is_16_21_A() -> None:
    """The design rule of GuidanceParams, step by step with the docstring's numbers:

    demand per unit   m·a/4 = 37 000·(555.6²/2e5)/4                      = 14 275 N
    edge force at z_d F0·(δ0/b2)·(2/π)·atan(z_d/δ0), F0 = 37 000·g/4, z_d = 4 mm = 2 198 N
    pair factor       (δg0/(δg0−z_d))² − (δg0/(δg0+z_d))²                = 2.2676
    F_g0 = (14 275 + 2 198)/2.2676 = 7 265 N;  I_g0 = δg0·√(F_g0/(μ0N²/4·a2·h_g)) = 16.21 A
    """
    a = (2000.0 / 3.6) ** 2 / 200_000.0
    demand = 37_000.0 * a / 4.0
    assert demand == pytest.approx(14_275, abs=1.0)
    f0 = 37_000.0 * G / 4.0
    z_d = 0.5 * OMEGA_G_M
    edge = f0 * (0.010 / 0.10) * (2.0 / math.pi) * math.atan(z_d / 0.010)
    assert edge == pytest.approx(2_198, abs=1.0)
    factor = (0.010 / (0.010 - z_d)) ** 2 - (0.010 / (0.010 + z_d)) ** 2
    assert factor == pytest.approx(2.2676, abs=1e-4)
    f_g0 = (demand + edge) / factor
    assert f_g0 == pytest.approx(7_265, abs=1.0)
    ig0 = 0.010 * math.sqrt(f_g0 / (MU0 * 400.0**2 / 4.0 * 1.1 * 0.05))
    assert ig0 == pytest.approx(16.2101, abs=1e-4)
    assert guidance_bias_A(ModelParams()) == pytest.approx(ig0, rel=1e-12)
    assert pack(EnvConfig().resolve().base)[P_IG0] == pytest.approx(ig0, rel=1e-12)
    # an explicit bias overrides the rule
    assert guidance_bias_A(ModelParams(guidance=GuidanceParams(bias_current_A=12.0))) == 12.0


# ---- vehicle, guideway, track ---------------------------------------------------------------


def test_vehicle_geometry_defaults() -> None:
    """Paper Table 1 (masses, stiffnesses: tests/physics/test_params.py) and the assumed
    geometry of VehicleParams: d1 = 16 m, d2 = 2 m, b = h = 2.7 m; roll/yaw inertia eq. 9."""
    v = VehicleParams()
    assert (v.set_spacing_m, v.track_gauge_m) == (16.0, 2.0)
    assert (v.capsule_width_m, v.capsule_height_m) == (2.7, 2.7)
    assert v.roll_inertia_kgm2 == pytest.approx(15_000.0 * (2.7**2 + 2.7**2) / 12, rel=1e-12)
    assert v.yaw_inertia_kgm2 == pytest.approx(15_000.0 * (25.0**2 + 2.7**2) / 12, rel=1e-12)


def test_guideway_defaults() -> None:
    """README model table: spans of 30 m, EI = 6.5e10 N·m² in both planes, 1.9 t/m, 6 modes
    per span and plane, ζ = 1 %, flexible; f1 = (π/(2L²))·√(EI/ρA) = 10.2084 Hz."""
    g = GuidewayParams()
    assert g.span_m == 30.0
    assert g.bending_stiffness_Nm2 == 6.5e10
    assert g.lateral_bending_stiffness_Nm2 == 6.5e10
    assert g.mass_per_length_kg_per_m == 1900.0
    assert g.n_modes == 6
    assert g.damping_ratio == 0.01
    assert g.rigid is False
    f1 = math.pi / (2 * 30.0**2) * math.sqrt(6.5e10 / 1900.0)
    assert f1 == pytest.approx(10.2084, abs=1e-4)
    assert g.natural_frequency_hz(1) == pytest.approx(f1, rel=1e-12)
    assert EnvConfig().resolve().base.guideway == g  # the environment uses these


def test_simulation_and_track_defaults() -> None:
    """1 ms control interval, RK4 with 2 substeps (SimulationParams' docstring: stability and
    error at h = 0.5 ms), g = 9.81, a 2000 m section starting at
    x = 10 m; curves start at 100 m after a 500 m clothoid (OperatingCondition)."""
    s = SimulationParams()
    assert s.control_dt_s == 1e-3
    assert s.substeps == 2
    assert s.gravity_m_s2 == G
    assert s.track_length_m == 2_000.0
    assert s.start_position_m == 10.0
    c = OperatingCondition()
    assert c.speed_kmh == 1000.0 and math.isinf(c.curve_radius_m) and c.cant_deg == 0.0
    assert (c.curve_start_m, c.transition_length_m) == (100.0, 500.0)
    base = EnvConfig().resolve().base
    assert base.simulation == s
    assert pack(base)[P_G] == G


def test_episode_lengths() -> None:
    """2000 m at 1000 km/h in 1 ms steps: ceil(2000/(277.78·1e-3)) = 7200 steps; 3600 at
    2000 km/h (the env docstring)."""
    assert EnvConfig(scenario="paper-1000-straight").resolve().episode_steps == 7200
    assert EnvConfig(scenario="paper-2000-straight").resolve().episode_steps == 3600
    assert episode_steps(ModelParams()) == 7200


def test_irregularity_defaults() -> None:
    """docs/model.md: German "low" spectrum (A_v = 4.032e-7, A_a = 2.119e-7 m²·rad/m) at 10 %
    amplitude (PSD × 0.01) for the scenarios, wavelengths 2–200 m on a 0.1 m grid,
    Ωc = 0.8246, Ωr = 0.0206 rad/m."""
    assert IRREGULARITY_CLASSES["german-low"] == (4.032e-7, 2.119e-7, 1.0)
    assert IRREGULARITY_CLASSES["german-high"] == (1.080e-6, 6.125e-7, 1.0)
    assert IRREGULARITY_CLASSES["maglev"] == (4.032e-7, 2.119e-7, 0.01)
    assert IRREGULARITY_CLASSES["maglev-rough"] == (4.032e-7, 2.119e-7, 0.0625)
    assert IRREGULARITY_CLASSES["none"] == (0.0, 0.0, 0.0)
    i = IrregularityParams()
    assert (i.spectrum, i.amplitude) == ("maglev", 1.0)
    assert (i.min_wavelength_m, i.max_wavelength_m, i.grid_step_m) == (2.0, 200.0, 0.1)
    assert (i.omega_c, i.omega_r) == (0.8246, 0.0206)
    assert DEFAULT_IRREGULARITY == "maglev"
    assert EnvConfig().resolve().base.irregularity.spectrum == "maglev"


# ---- the environment --------------------------------------------------------------------------


def test_coil_lag_and_control_interval_of_the_environment() -> None:
    """The environment's coil lag τ = 2 ms (scenarios docstring; the simulator's own default
    is 0) and its control interval 1 ms."""
    assert DEFAULT_COIL_TIME_CONSTANT_S == 2e-3
    base = EnvConfig().resolve().base
    assert base.magnet.coil_time_constant_s == 2e-3
    assert pack(base)[P_TAU] == 2e-3
    assert EnvConfig().resolve().control_dt_s == 1e-3
    assert pack(EnvConfig(coil_time_constant_s=0.0).resolve().base)[P_TAU] == 0.0


def test_paper_scenarios() -> None:
    """Paper §5: 1000 and 2000 km/h, straight and R = 200 km, no cant, maglev irregularity."""
    assert PAPER_SCENARIOS == (
        "paper-1000-straight",
        "paper-1000-curved",
        "paper-2000-straight",
        "paper-2000-curved",
    )
    assert DEFAULT_SCENARIO == "paper-1000-straight"
    expected = {
        "paper-1000-straight": (1000.0, math.inf),
        "paper-1000-curved": (1000.0, 200_000.0),
        "paper-2000-straight": (2000.0, math.inf),
        "paper-2000-curved": (2000.0, 200_000.0),
    }
    for name, (speed, radius) in expected.items():
        sc = get_scenario(name)
        assert (sc.speed_kmh, sc.curve_radius_m, sc.cant_deg) == (speed, radius, 0.0), name
        assert not sc.randomize
        c = EnvConfig(scenario=name).resolve().base.condition
        assert (c.speed_kmh, c.curve_radius_m, c.cant_deg) == (speed, radius, 0.0), name
        assert EnvConfig(scenario=name).resolve().base.irregularity.spectrum == "maglev"


def test_random_scenario_ranges() -> None:
    """scenarios docstring: 1000–2000 km/h, straight with probability ½ else R log-uniform in
    100–1000 km, classes none/maglev/maglev-rough, capsule mass ×[0.9, 1.1]."""
    assert RANDOM_SPEED_RANGE_KMH == (1000.0, 2000.0)
    assert RANDOM_RADIUS_RANGE_M == (100_000.0, 1_000_000.0)
    assert RANDOM_STRAIGHT_PROBABILITY == 0.5
    assert RANDOM_IRREGULARITY_CLASSES == ("none", "maglev", "maglev-rough")
    assert RANDOM_MASS_FACTOR_RANGE == (0.9, 1.1)


def test_reward_weights_terms_and_caps() -> None:
    """reward.py docstring: weights gap 1, guidance 1, current 0.05, comfort 1, survival 1,
    contact 100 in that order; caps 4 per unit (|s| = 2Ω), 1e12, 100 (10 g)."""
    assert REWARD_TERMS == ("gap", "guidance", "current", "comfort", "survival", "contact")
    w = RewardWeights()
    assert w.as_tuple() == (1.0, 1.0, 0.05, 1.0, 1.0, 100.0)
    assert EnvConfig().reward == w
    assert (GAP_TERM_CAP, CURRENT_TERM_CAP, COMFORT_TERM_CAP) == (4.0, 1e12, 100.0)
    kw = EnvConfig().to_kwargs()
    assert (kw["gap_weight"], kw["guidance_weight"], kw["current_weight"]) == (1.0, 1.0, 0.05)
    assert (kw["comfort_weight"], kw["survival_weight"], kw["contact_weight"]) == (1.0, 1.0, 100.0)


def test_observation_layout_and_scales() -> None:
    """observation.py: 23 entries for the levitation actuators, preview at 0/250/500/1000 m,
    gap rate per 1 m/s, speed per 2000 km/h, curvature × 1e5 m."""
    assert OBS_SIZE == 23
    assert PREVIEW_DISTANCES_M == (0.0, 250.0, 500.0, 1000.0)
    assert GAP_RATE_SCALE_M_S == 1.0
    assert SPEED_SCALE_M_S == pytest.approx(2000.0 / 3.6, rel=1e-15)
    assert CURVATURE_SCALE_M == 1e5
    assert EnvConfig().resolve().observation.size == 23
    assert EnvConfig(actuators="levitation+guidance").resolve().observation.size == 31
    assert EnvConfig().action_scale == 1.0


def test_benchmark_training_distribution_is_pinned() -> None:
    """scenario 'benchmark-train' (the shipped agents' training distribution; changing it
    means retraining them)."""
    from hyperloop_env.scenarios import BENCHMARK_TRAIN, RANDOM_DISTURBANCES, SCENARIOS

    assert SCENARIOS["benchmark-train"].random is BENCHMARK_TRAIN
    assert BENCHMARK_TRAIN.speed_range_kmh == (1000.0, 2000.0)
    assert BENCHMARK_TRAIN.radius_range_m == (20_000.0, 1_000_000.0)
    assert BENCHMARK_TRAIN.straight_probability == 0.4
    assert BENCHMARK_TRAIN.roughness_range == (0.0, 0.6)
    assert BENCHMARK_TRAIN.disturbances == {
        "thermal_camber": (0.3, (0.0, 0.008), {}),
        "payload": (0.3, (0.0, 0.25), {}),
        "actuator_fault": (0.25, (0.0, 0.9), {}),
        "speed_profile": (0.3, (0.0, 2.0), {"mode": "random"}),
        "pier_settlement": (0.3, (0.0, 0.004), {}),
        "joint_steps": (0.3, (0.0, 0.0012), {}),
        "sensor_dropout": (0.2, (0.0, 0.4), {}),
    }
    # every family is usable in the random scenario (issue: disturbances in `random`)
    from hyperloop_env.disturbances import DISTURBANCES

    assert set(RANDOM_DISTURBANCES) == set(DISTURBANCES) - {"roughness"}


def test_benchmark_train_draws_every_family() -> None:
    """Over many resets every family of the training distribution is drawn, with
    severities inside its range."""
    import numpy as np

    from hyperloop_env.config import build_config
    from hyperloop_env.scenarios import BENCHMARK_TRAIN

    rc = build_config("benchmark-train")
    rng = np.random.default_rng(0)
    seen: dict[str, list[float]] = {}
    for _ in range(200):
        for d in rc.episode_disturbances(rng):
            seen.setdefault(d.name, []).append(d.severity)
    for name, (_, (lo, hi), _) in BENCHMARK_TRAIN.disturbances.items():
        assert name in seen, name
        assert lo <= min(seen[name]) and max(seen[name]) <= hi, name
