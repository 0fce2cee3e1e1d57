"""Vehicle and magnet verification cases through the production path
(hyperloop_env.verification.vehicle) and checks of their independent references."""

import json
import math

import numpy as np
import pytest

from hyperloop_env import verification as v
from hyperloop_env.physics import GuidanceParams, MagnetParams, VehicleParams
from hyperloop_env.physics.layout import P_AG, P_DELTAG0, P_IG0, P_KMAG, P_KMAGG
from hyperloop_env.physics.magnets import guidance_force, magnet_forces
from hyperloop_env.physics.model import pack
from hyperloop_env.physics.params import ModelParams
from hyperloop_env.verification import reference as ref
from hyperloop_env.verification import vehicle as vv


def _check(r) -> None:
    assert r.passed, r.to_dict()
    json.dumps(r.to_dict())


@pytest.mark.parametrize("quantity", ["hz", "zeta"])
@pytest.mark.parametrize("name", vv.VEHICLE_MODE_NAMES)
def test_vehicle_mode(name, quantity):
    r = vv.vehicle_mode(name, quantity)
    assert r.name == f"vehicle_mode_{name}_{quantity}"
    _check(r)


def test_named_modes_are_the_expected_ones():
    _, named = vv.reference_eigen("repelling")
    f = {k: abs(z) / (2 * math.pi) for k, z in named.items()}
    # vertical modes on the magnet springs (5-7 Hz), lateral ones on the edge force (~1 Hz)
    assert 5.0 < f["pitch"] < f["roll"] < f["heave"] < 7.5
    assert 0.5 < f["lateral"] < f["yaw"] < 1.5
    # the least damped mode quoted in the README (passive_stability_repelling) is heave
    r = v.passive_stability("repelling")
    assert r.info["least_damped_mode_hz"] == pytest.approx(f["heave"], rel=1e-6)


@pytest.mark.parametrize("orientation", ["repelling", "attracting"])
def test_vehicle_eigenvalues(orientation):
    _check(vv.vehicle_eigenvalues(orientation))


def test_vehicle_unstable_pole_attracting():
    r = vv.vehicle_unstable_pole_attracting()
    _check(r)
    assert 0.9 < r.info["ratio_to_estimate"] < 1.1


def test_weight_check():
    r = vv.weight_check()
    _check(r)
    assert r.reference == pytest.approx(362_970.0)
    assert r.info["nominal_current_A"] == pytest.approx(40.5, abs=0.05)


@pytest.mark.parametrize("name", list(vv.CURVE_CASES))
def test_curve_lateral_offset(name):
    r = vv.curve_lateral_offset(name)
    _check(r)
    assert r.info["lateral_load_record_m_s2"] == pytest.approx(
        r.info["lateral_load_reference_m_s2"], rel=1e-12
    )
    assert r.info["gap_excursion_mean_m"] == pytest.approx(
        r.info["gap_excursion_reference_m"], rel=1e-3
    )


def test_curve_closed_form_with_guidance():
    """1000 km/h, R = 200 km: 3.57 kN per unit against the pair's ≈ 2.9 MN/m minus the
    edge force's ≈ 0.58 MN/m gives ≈ 1.53 mm linearly, 1.45 mm with the pair's stiffening
    1/δ² law (the design point, 2000 km/h, sits at 4 mm: half the guidance clearance, by
    the design rule)."""
    eq = ref.quasi_static_lateral_offset(VehicleParams(), MagnetParams(), 1000 / 3.6, 200e3)
    assert 1.40e-3 < eq.offset_m < 3567.0 / 2.33e6
    design = ref.quasi_static_lateral_offset(VehicleParams(), MagnetParams(), 2000 / 3.6, 200e3)
    assert design.offset_m == pytest.approx(4.0e-3, rel=1e-3)
    # another lateral term enters as one callable (here an extra 1 MN/m spring)
    stiff = ref.quasi_static_lateral_offset(
        VehicleParams(),
        MagnetParams(),
        1000 / 3.6,
        200e3,
        extra_terms=[
            lambda z, d: ref.guidance_force_N(GuidanceParams(), MagnetParams(), 16.2101, 0.0, z),
            lambda z, d: -1e6 * z,
        ],
    )
    assert 0 < stiff.offset_m < eq.offset_m


@pytest.mark.parametrize("orientation", ["repelling", "attracting"])
def test_magnet_work_loop(orientation):
    r = vv.magnet_work_loop(orientation)
    assert r.name == f"magnet_work_loop_{orientation}"
    _check(r)


@pytest.mark.parametrize("orientation", ["repelling", "attracting"])
def test_guidance_stiffness(orientation):
    r = vv.guidance_stiffness(orientation)
    _check(r)
    # repelling pairs restore (about 2.9 MN/m per unit at the design-rule bias), attracting
    # ones destabilise by the same amount
    assert (r.computed > 2.5e6) if orientation == "repelling" else (r.computed < -2.5e6)


def test_guidance_pole_attracting():
    r = vv.guidance_pole_attracting()
    _check(r)
    assert 15.0 < r.computed < 25.0  # ≈ 19.8 rad/s


def test_reference_force_law_matches_the_compiled_one():
    """The independent rewrite of eq. 3-5 agrees with magnets.magnet_forces (a check of the
    rewrite, not a reference)."""
    for orientation, sigma in (("repelling", 1.0), ("attracting", -1.0)):
        mp = MagnetParams(orientation=orientation)
        P = pack(ModelParams(magnet=mp))
        i0 = ref.nominal_current_paper_A(mp, (15_000 + 22_000) * 9.81 / 4)
        for s, z in [(0.0, 0.0), (1e-3, 4e-3), (-2e-3, -7e-3)]:
            fy, fz = magnet_forces(
                i0, s, z, P[P_KMAG], mp.pole_length_m, mp.pole_width_m, mp.nominal_gap_m, sigma
            )
            gap = mp.nominal_gap_m + s
            assert fy == pytest.approx(ref.lift_force_N(mp, i0, gap, z), rel=1e-12)
            assert fz == pytest.approx(ref.edge_force_N(mp, i0, gap, z), rel=1e-12, abs=1e-9)
            # repelling: the edge force pushes the unit further off its rail
            assert fz * z * sigma >= 0.0
        gp = GuidanceParams()
        ig0 = ref.guidance_bias_reference_A(gp, mp, 9.81)
        assert ig0 == pytest.approx(float(P[P_IG0]), rel=1e-12)
        for d_i, z in [(0.0, 0.0), (2.0, 3e-3), (-5.0, -6e-3)]:
            got = guidance_force(ig0, d_i, z, P[P_KMAGG], P[P_AG], P[P_DELTAG0], sigma)
            assert got == pytest.approx(
                ref.guidance_force_N(gp, mp, ig0, d_i, z), rel=1e-12, abs=1e-9
            )


def test_reference_matrices_are_symmetric_and_definite():
    mats = ref.vehicle_matrices(VehicleParams(), MagnetParams())
    np.testing.assert_allclose(mats.K, mats.K.T, rtol=0, atol=1e-6)
    np.testing.assert_allclose(mats.C, mats.C.T, rtol=0, atol=1e-9)
    assert np.all(np.linalg.eigvalsh(mats.K) > 0)  # repelling: statically stable
    att = ref.vehicle_matrices(VehicleParams(), MagnetParams(orientation="attracting"))
    assert np.linalg.eigvalsh(att.K).min() < 0
