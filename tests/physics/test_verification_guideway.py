"""Guideway verification cases through the production path (hyperloop_env.verification.guideway)
and checks of the independent references they use (hyperloop_env.verification.reference)."""

import json
import math

import numpy as np
import pytest

from hyperloop_env.physics import GuidewayParams
from hyperloop_env.verification import guideway as vg
from hyperloop_env.verification import reference as ref


def _check(r) -> None:
    assert r.passed, r.to_dict()
    json.dumps(r.to_dict())


@pytest.mark.parametrize("alpha", vg.SIM_DAF_ALPHAS)
def test_moving_force_daf_sim(alpha):
    r = vg.moving_force_daf_sim(alpha)
    assert r.name == f"moving_force_daf_sim_alpha_{alpha}"
    _check(r)
    # the configuration really is a constant force shared by the two sets
    assert r.info["total_force_rel_variation"] < 1e-3
    assert r.info["set_force_shares"]["front"] == pytest.approx(0.5, abs=1e-6)
    # the sampled reference is within the sampling error of the continuous maximum
    assert r.reference == pytest.approx(r.info["fryba_daf_continuous_max"], rel=2e-3)


def test_static_midspan_slow_crossing():
    r = vg.static_midspan_slow_crossing()
    _check(r)
    assert r.computed >= 1.0  # the dynamic excess is positive, ~alpha


def test_static_deflection_initial_state():
    r = vg.static_deflection_initial_state()
    _check(r)
    assert r.info["crawl_is_equilibrium"]
    assert max(r.info["unit_footprint_rel_error_front_rear"]) < 1e-2  # 6-mode truncation


def test_guideway_load_coupling():
    r = vg.guideway_load_coupling()
    _check(r)
    assert r.info["unit_force_vs_rhs_output_rel"] < 1e-12
    lo, hi = r.info["front_footprint_m"]
    assert lo < 30.0 < hi  # the case really straddles a support
    fy = np.asarray(r.info["unit_force_y_N"])
    assert np.ptp(fy) > 0.1 * fy.mean()  # and the units carry different forces


# ---- the references themselves --------------------------------------------------------


def test_fe_beam_converges_to_closed_form():
    g = GuidewayParams()
    args = (g.bending_stiffness_Nm2, g.mass_per_length_kg_per_m, g.span_m)
    exact = [ref.beam_frequency_closed_form_hz(k, *args) for k in (1, 2, 3)]
    coarse = ref.fe_beam_frequencies_hz(*args, 3, n_elements=10)
    fine = ref.fe_beam_frequencies_hz(*args, 3, n_elements=60)
    assert np.all(coarse > fine)  # consistent-mass FE converges from above
    np.testing.assert_allclose(fine, exact, rtol=1e-6)


def test_influence_function_midspan_and_symmetry():
    span, ei, p = 30.0, 6.5e10, 1e5
    mid = p * ref.simply_supported_deflection(15.0, 15.0, span, ei)
    assert mid == pytest.approx(p * span**3 / (48 * ei), rel=1e-14)
    # Maxwell reciprocity
    a = ref.simply_supported_deflection(7.0, 21.0, span, ei)
    assert a == pytest.approx(ref.simply_supported_deflection(21.0, 7.0, span, ei), rel=1e-14)
    # a short distributed load tends to the point load
    d = ref.distributed_load_deflection(15.0, [(p, 15.0, 1e-3)], span, ei)
    assert d == pytest.approx(mid, rel=1e-6)


def test_fryba_history_matches_daf_and_starts_at_rest():
    for alpha in (0.25, 1.0):
        tau_exit = math.pi / alpha
        tau = np.linspace(-1.0, tau_exit + 6 * math.pi, 20001)
        hist = ref.fryba_midspan_history(alpha, tau)
        assert np.all(hist[tau < 0] == 0.0)
        assert hist.max() == pytest.approx(ref.fryba_daf(alpha, periods_after=3.0), rel=1e-5)
