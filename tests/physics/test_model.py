"""Simulator behaviour: determinism, batching, bad input, physics sanity."""

import math

import numpy as np
import pytest

from hyperloop_env.physics import (
    BatchSimulator,
    GuidewayParams,
    IrregularityParams,
    MagnetParams,
    ModelParams,
    OperatingCondition,
    SimulationParams,
    Simulator,
)
from hyperloop_env.physics.layout import M_CONTACT, M_GAP, M_I, M_LAT, M_T, M_X
from hyperloop_env.physics.magnets import nominal_current_A


def test_nominal_current_from_equilibrium():
    p = ModelParams()
    sim = Simulator(p)
    f0 = p.vehicle.total_mass_kg * p.simulation.gravity_m_s2 / 4
    assert sim.nominal_current_A == pytest.approx(nominal_current_A(p.magnet, f0))
    heavier = ModelParams(vehicle=p.vehicle.__class__(capsule_mass_kg=18_000.0))
    assert Simulator(heavier).nominal_current_A > sim.nominal_current_A
    # ≈ 1 T at 10 mm with N = 400: I0 ≈ 40 A (docs/model.md order of magnitude)
    assert 30.0 < sim.nominal_current_A < 50.0


def test_same_seed_bit_identical_and_different_seed_differs():
    def traj(seed):
        sim = Simulator()
        sim.reset(seed=seed)
        return sim.run([sim.nominal_current_A] * 4, 300)

    a, b, c = traj(7), traj(7), traj(8)
    assert np.array_equal(a, b)
    assert not np.array_equal(a[:, M_GAP], c[:, M_GAP])


def test_reset_restarts_the_run():
    sim = Simulator()
    sim.reset(seed=3)
    a = sim.run([sim.nominal_current_A] * 4, 50)
    sim.reset(seed=3)
    b = sim.run([sim.nominal_current_A] * 4, 50)
    assert np.array_equal(a, b)


def test_step_and_run_agree_and_time_advances():
    sim = Simulator()
    sim.reset(seed=1)
    i0 = sim.nominal_current_A
    recs = np.array([sim.step_record([i0] * 4).copy() for _ in range(20)])
    sim.reset(seed=1)
    run = sim.run([i0] * 4, 20)
    assert np.array_equal(recs, run)
    assert run[-1, M_T] == pytest.approx(20 * 1e-3)
    assert run[-1, M_X] == pytest.approx(10.0 + 1000 / 3.6 * 0.02)


@pytest.mark.parametrize("bad", [[np.nan, 40, 40, 40], [40, np.inf, 40, 40], [40, 40, 40, -np.inf]])
def test_non_finite_currents_raise(bad):
    sim = Simulator()
    sim.reset(seed=0)
    with pytest.raises(ValueError, match="finite"):
        sim.step(bad)


def test_wrong_shape_raises():
    sim = Simulator()
    sim.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        sim.step([40.0, 40.0, 40.0])


def test_step_before_reset_raises():
    with pytest.raises(RuntimeError, match="reset"):
        Simulator().step([40.0] * 4)


def test_currents_clipped_to_physical_range():
    sim = Simulator()
    sim.reset(seed=0)
    m = sim.step([-50.0, 1e6, 40.0, 0.0])
    assert m.current_A[0] == 0.0
    assert m.current_A[1] == sim.max_current_A
    assert m.current_A[2] == 40.0


def test_coil_lag_is_first_order():
    tau = 5e-3
    p = ModelParams(magnet=MagnetParams(coil_time_constant_s=tau))
    sim = Simulator(p)
    sim.reset(seed=0)
    i0 = sim.nominal_current_A
    rec = sim.run([i0 + 10.0] * 4, 5)
    expected = i0 + 10.0 * (1 - math.exp(-5e-3 / tau))
    assert rec[-1, M_I] == pytest.approx(expected, rel=1e-12)


def test_batch_matches_single_step_for_step():
    seeds = [11, 12, 13]
    params = [
        ModelParams(),
        ModelParams(condition=OperatingCondition(speed_kmh=2000.0, curve_radius_m=300_000.0)),
        ModelParams(magnet=MagnetParams(coil_time_constant_s=2e-3)),
    ]
    batch = BatchSimulator(params)
    batch.reset(seeds)
    singles = [Simulator(p) for p in params]
    for s, sd in zip(singles, seeds, strict=True):
        s.reset(seed=sd)
    rng = np.random.default_rng(0)
    for _ in range(40):
        cur = 40.0 + rng.normal(0, 5, size=(3, 4))
        recs = batch.step(cur)
        for i, s in enumerate(singles):
            assert np.array_equal(recs[i], s.step_record(cur[i]))


def test_batch_rejects_incompatible_params():
    with pytest.raises(ValueError, match="n_modes"):
        BatchSimulator([ModelParams(), ModelParams(guideway=GuidewayParams(n_modes=4))])


def test_passive_repelling_stays_bounded_on_straight_track():
    p = ModelParams(simulation=SimulationParams(track_length_m=2000.0))
    sim = Simulator(p)
    sim.reset(seed=0)
    rec = sim.run([sim.nominal_current_A] * 4, 3000)
    assert not rec[:, M_CONTACT].any()
    gaps = rec[500:, M_GAP : M_GAP + 4]
    # beam + irregularity produce excursions of the paper's order (~1 mm), far below 8 mm
    assert 1e-4 < gaps.std() < 4e-3


def test_passive_attracting_fails_quickly():
    sim = Simulator(ModelParams(magnet=MagnetParams(orientation="attracting")))
    sim.reset(seed=0)
    rec = sim.run([sim.nominal_current_A] * 4, 1000)
    first = np.flatnonzero(rec[:, M_CONTACT])
    assert first.size and first[0] < 300  # open-loop pole ≈ 45 rad/s


def test_small_radius_at_2000_kmh_ends_in_lateral_contact():
    p = ModelParams(condition=OperatingCondition(speed_kmh=2000.0, curve_radius_m=5_000.0))
    sim = Simulator(p)
    sim.reset(seed=0)
    rec = sim.run([sim.nominal_current_A] * 4, 3000)
    first = np.flatnonzero(rec[:, M_CONTACT])
    assert first.size
    assert np.abs(rec[first[0], M_LAT : M_LAT + 4]).max() >= p.guidance.clearance_m


def test_curve_pushes_units_outward():
    p = ModelParams(
        condition=OperatingCondition(speed_kmh=1000.0, curve_radius_m=200_000.0),
        irregularity=IrregularityParams(spectrum="none"),
        simulation=SimulationParams(track_length_m=1500.0),
    )
    sim = Simulator(p)
    sim.reset(seed=0)
    rec = sim.run([sim.nominal_current_A] * 4, 4000)
    lat = rec[-500:, M_LAT : M_LAT + 4].mean()
    assert lat > 1e-3  # outward (+z) for the left-hand curve
    assert not rec[:, M_CONTACT].any()


def test_rigid_smooth_guideway_stays_at_equilibrium():
    p = ModelParams(
        guideway=GuidewayParams(rigid=True), irregularity=IrregularityParams(spectrum="none")
    )
    sim = Simulator(p)
    sim.reset(seed=0)
    rec = sim.run([sim.nominal_current_A] * 4, 200)
    assert np.abs(rec[:, M_GAP : M_GAP + 4]).max() < 1e-12


def test_spans_are_entered_and_left():
    sim = Simulator()
    sim.reset(seed=0)
    rec = sim.run([sim.nominal_current_A] * 4, 1000)  # 278 m: ~9 spans
    assert np.isfinite(rec).all()
    assert set(np.unique(sim.spans)) <= set(range(8, 12))
