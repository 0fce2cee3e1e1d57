"""Tests of the stochastic technical stability (STS) metric, on signals with known laws."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import signal as sp_signal
from scipy import stats

from hyperloop_env.sts import (
    UNIT_NAMES,
    EpisodeSignal,
    STSReport,
    analyse_episodes,
    analyse_unit,
    count_contacts,
    effective_sample_size,
    format_probability,
    integrated_autocorrelation_time,
    normal_p_unsteady,
    paper_table_markdown,
    wilson_interval,
)

DT = 1e-3
OMEGA = 0.008


def ar1(phi: float, n: int, sigma: float, seed: int) -> np.ndarray:
    """Stationary Gaussian AR(1) with marginal std ``sigma`` [m]."""
    rng = np.random.default_rng(seed)
    e = rng.standard_normal(n) * sigma * math.sqrt(1.0 - phi * phi)
    x0 = rng.standard_normal() * sigma
    out, _ = sp_signal.lfilter([1.0], [1.0, -phi], e, zi=[phi * x0])
    return out


def closed_form_normal(sigma: float, mean: float = 0.0) -> float:
    z_hi = (OMEGA - mean) / sigma / math.sqrt(2.0)
    z_lo = (OMEGA + mean) / sigma / math.sqrt(2.0)
    return 0.5 * math.erfc(z_hi) + 0.5 * math.erfc(z_lo)


# ------------------------------------------------------------------------------------------
# Known laws
# ------------------------------------------------------------------------------------------


def test_iid_normal_matches_closed_form_and_is_accepted():
    sigma = 3e-3
    x = np.random.default_rng(11).normal(0.0, sigma, 20_000)
    r = analyse_unit(x, DT, name="FL")
    truth = closed_form_normal(sigma)
    assert r.distribution == "norm"
    assert r.normal_accepted and r.ks_accepted and r.thinned_ks_accepted
    assert r.distribution_params == pytest.approx((x.mean(), x.std()))
    assert r.p_unsteady == pytest.approx(truth, rel=0.15)
    assert r.p_unsteady == pytest.approx(normal_p_unsteady(x.mean(), x.std()), rel=1e-12)
    assert r.p_steady == pytest.approx(1.0 - r.p_unsteady)
    lo, hi = r.p_unsteady_ci
    assert lo < truth < hi
    assert lo <= r.p_unsteady <= hi
    # i.i.d.: effective sample size close to n, thinning keeps everything
    assert r.effective_sample_size > 0.8 * x.size
    assert r.thinning_stride == 1
    assert r.empirical_exceedance == pytest.approx(np.mean(np.abs(x) >= OMEGA))
    e_lo, e_hi = r.empirical_exceedance_ci
    assert e_lo < truth < e_hi
    assert r.n_contacts == count_contacts(x, OMEGA)
    assert r.n_contacts > 0 and not r.terminated_in_contact
    assert r.tail_consistent is True


def test_tail_inconsistency_is_flagged():
    """KS is blind to rare large excursions; the tail check must not be."""
    rng = np.random.default_rng(12)
    x = rng.normal(0.0, 1.5e-3, 20_000)
    spikes = rng.choice(x.size, 40, replace=False)
    x[spikes] = 9e-3 * rng.choice([-1.0, 1.0], 40)
    r = analyse_unit(x, DT, n_boot=300)
    assert r.distribution == "norm" and r.normal_accepted  # the KS test is fooled ...
    assert r.p_unsteady_fit < 1e-5
    assert r.empirical_exceedance == pytest.approx(40 / 20_000)
    assert r.tail_consistent is False  # ... the tail check is not
    assert r.empirical_exceedance_ci[0] > r.p_unsteady_fit_ci[1]
    rep = analyse_episodes([np.column_stack([x] * 4)], DT, n_boot=100)
    md = paper_table_markdown(rep)
    assert md.count("\u2020") == 4 + 1  # every row and the footnote
    assert all(row["tail_consistent"] is False for row in rep.to_rows())


@pytest.mark.parametrize(
    ("label", "expected", "truth"),
    [
        ("t2", "t", 2.0 * stats.t.sf(OMEGA / 1e-3, 2)),
        ("laplace", "laplace", 2.0 * stats.laplace.sf(OMEGA / 1.5e-3)),
    ],
)
def test_heavy_tailed_law_rejects_normal_and_chooses_candidate(label, expected, truth):
    rng = np.random.default_rng(6)  # fixed seed; coverage itself is tested below
    x = 1e-3 * rng.standard_t(2, 20_000) if label == "t2" else 1.5e-3 * rng.laplace(size=20_000)
    r = analyse_unit(x, DT, n_boot=300)
    assert not r.normal_accepted
    assert r.normal_ks_pvalue < 1e-6
    assert r.distribution == expected
    assert r.ks_accepted
    assert r.ks_statistic < r.normal_ks_statistic
    assert r.p_unsteady == pytest.approx(truth, rel=0.2)
    lo, hi = r.p_unsteady_ci
    assert lo < truth < hi
    # the normal law would badly misjudge the tail: report differs from the normal answer
    assert abs(r.p_unsteady - normal_p_unsteady(x.mean(), x.std())) > 0.2 * truth
    if expected == "t":
        assert r.distribution_params[0] == pytest.approx(2.0, rel=0.15)  # degrees of freedom


def test_genextreme_fit_does_not_stall():
    x = 1e-3 * stats.genextreme.rvs(-0.2, size=20_000, random_state=np.random.default_rng(2))
    r = analyse_unit(x, DT, n_boot=200)
    assert r.distribution == "genextreme"
    assert r.distribution_params[0] == pytest.approx(-0.2, abs=0.05)
    assert r.ks_accepted


def test_ar1_effective_sample_size():
    phi, n = 0.95, 20_000
    x = ar1(phi, n, 2e-3, seed=3)
    expected = n * (1.0 - phi) / (1.0 + phi)
    ess = effective_sample_size(x)
    assert expected / 1.5 < ess < expected * 1.5
    tau = integrated_autocorrelation_time(x)
    assert tau == pytest.approx(n / ess)
    r = analyse_unit(x, DT)
    assert r.effective_sample_size == pytest.approx(ess)
    assert r.thinning_stride == round(tau)
    assert r.thinned_n_samples == len(range(0, n, r.thinning_stride))
    assert r.block_length >= 2 * tau


def test_iid_effective_sample_size_close_to_n():
    x = np.random.default_rng(4).standard_normal(10_000)
    assert effective_sample_size(x) > 8_000
    assert integrated_autocorrelation_time(x) >= 1.0
    # segments are not joined: two halves of an AR(1) give about the same tau
    y = ar1(0.9, 20_000, 1.0, seed=8)
    split = integrated_autocorrelation_time([y[:10_000], y[10_000:]])
    assert split == pytest.approx(integrated_autocorrelation_time(y), rel=0.2)


def test_ci_wider_for_correlated_signal():
    sigma, n = 3e-3, 20_000
    iid = np.random.default_rng(21).normal(0.0, sigma, n)
    cor = ar1(0.95, n, sigma, seed=23)
    r_iid = analyse_unit(iid, DT)
    r_cor = analyse_unit(cor, DT)
    assert r_iid.distribution == r_cor.distribution == "norm"
    truth = closed_form_normal(sigma)
    assert r_iid.p_unsteady_ci[0] < truth < r_iid.p_unsteady_ci[1]
    assert r_cor.p_unsteady_ci[0] < truth < r_cor.p_unsteady_ci[1]
    assert r_cor.p_unsteady_ci_width > 2.0 * r_iid.p_unsteady_ci_width
    w_iid = r_iid.empirical_exceedance_ci[1] - r_iid.empirical_exceedance_ci[0]
    w_cor = r_cor.empirical_exceedance_ci[1] - r_cor.empirical_exceedance_ci[0]
    assert w_cor > 2.0 * w_iid


@pytest.mark.parametrize(("phi", "n"), [(0.0, 2_000), (0.9, 4_000)])
def test_ci_coverage_over_replications(phi, n):
    """The 95 % CI must cover the true P(unsteady) in most of 20 independent replications
    (P(<= 15 of 20 covered | coverage 0.95) ~ 0.3 %)."""
    sigma = 3e-3
    truth = closed_form_normal(sigma)
    covered = 0
    for seed in range(20):
        x = ar1(phi, n, sigma, seed=1_000 + seed)
        lo, hi = analyse_unit(x, DT, n_boot=200, rng=seed).p_unsteady_ci
        covered += lo <= truth <= hi
    assert covered >= 16


def test_determinism_same_seed_same_ci():
    x = ar1(0.8, 5_000, 3e-3, seed=9)
    a = analyse_unit(x, DT, rng=123)
    b = analyse_unit(x, DT, rng=123)
    c = analyse_unit(x, DT, rng=124)
    assert a.p_unsteady_ci == b.p_unsteady_ci
    assert a.to_dict() == b.to_dict()
    assert c.p_unsteady_ci != a.p_unsteady_ci
    eps = [np.column_stack([ar1(0.8, 3_000, 3e-3, seed=s + k) for k in range(4)]) for s in (0, 10)]
    r1 = analyse_episodes(eps, DT, rng=7)
    r2 = analyse_episodes(eps, DT, rng=7)
    assert r1.to_dict() == r2.to_dict()


# ------------------------------------------------------------------------------------------
# Contacts and failed episodes
# ------------------------------------------------------------------------------------------


def three_contacts_signal() -> np.ndarray:
    x = np.full(200, 1e-3)
    x[20:25] = 9e-3  # entry 1 (5 samples)
    x[60:63] = -9e-3  # entry 2, opposite side
    x[100] = OMEGA  # entry 3: |s| == Omega is already contact
    x[150] = 7.9e-3  # close call, not a contact
    return x


def test_contact_counting_three_crossings():
    x = three_contacts_signal()
    assert count_contacts(x, OMEGA) == 3
    r = analyse_unit(x, DT)
    assert r.n_contacts == 3
    assert r.n_contacts_settling == 0
    assert r.time_to_contact_s == pytest.approx(20 * DT)
    assert r.empirical_exceedance == pytest.approx(9 / 200)
    # contacts inside the settling window are still counted, and flagged as such
    r_settle = analyse_unit(x, DT, settle_s=0.07)
    assert r_settle.n_contacts == 3
    assert r_settle.n_contacts_settling == 2
    assert r_settle.n_samples == 130


def test_terminal_contact_counted_once():
    x = np.array([0.0, 2e-3, 5e-3, 7e-3])
    assert count_contacts(x, OMEGA) == 0
    assert count_contacts(x, OMEGA, terminated_in_contact=True) == 1
    y = np.array([0.0, 2e-3, 5e-3, 8.5e-3])  # contact sample recorded
    assert count_contacts(y, OMEGA, terminated_in_contact=True) == 1
    assert count_contacts(np.zeros(0), OMEGA, terminated_in_contact=True) == 1


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-0.02, 0.02, allow_nan=False), max_size=60), st.booleans())
def test_contact_count_matches_brute_force(values, terminated):
    x = np.array(values, dtype=float)
    expected, inside = 0, False
    for v in x:
        now = abs(v) >= OMEGA
        expected += now and not inside
        inside = now
    if terminated and not inside:
        expected += 1
    assert count_contacts(x, OMEGA, terminated_in_contact=terminated) == expected


def test_episode_ending_in_contact_after_five_samples_is_reported():
    # unstable passive magnet: exponential divergence, contact after 5 samples
    x = 1e-3 * np.array([0.5, 1.0, 2.0, 4.0, 7.5])
    r = analyse_unit(x, DT, settle_s=0.1, name="FL", terminated_in_contact=True)
    assert r.name == "FL"
    assert r.distribution == "none"
    assert r.n_samples == 0
    assert r.p_unsteady == 1.0 and r.p_steady == 0.0
    assert r.p_unsteady_ci == (1.0, 1.0)
    assert math.isnan(r.ks_pvalue) and math.isnan(r.normal_ks_pvalue)
    assert not r.ks_accepted
    assert r.n_contacts == 1 and r.n_contacts_settling == 1
    assert r.terminated_in_contact
    assert r.time_to_contact_s == pytest.approx(5 * DT)
    json.dumps(r.to_dict(), allow_nan=False)
    # same short episode without settling: still too short to fit, still p_unsteady = 1
    r0 = analyse_unit(x, DT, terminated_in_contact=True)
    assert r0.n_samples == 5 and r0.distribution == "none" and r0.p_unsteady == 1.0
    # short and not terminated: undetermined, never a fake 0
    r1 = analyse_unit(x[:3], DT)
    assert math.isnan(r1.p_unsteady) and r1.p_unsteady_ci == (0.0, 1.0)


def test_long_episode_that_terminated_in_contact_has_p_unsteady_one():
    x = np.random.default_rng(1).normal(0.0, 1e-3, 2_000)
    x[-1] = 9e-3
    r = analyse_unit(x, DT, terminated_in_contact=True)
    assert r.distribution == "norm"
    assert r.p_unsteady_fit < 1e-3  # the survival-conditioned fit alone looks fine ...
    assert r.p_unsteady == 1.0 and r.p_unsteady_ci == (1.0, 1.0)  # ... but it touched
    assert r.n_contacts == 1


def test_pooled_episodes_keep_failed_episode():
    rng = np.random.default_rng(31)
    good = [rng.normal(0.0, 1.5e-3, (3_000, 4)) for _ in range(3)]
    failed = np.zeros((5, 4))
    failed[:, 1] = 1e-3 * np.array([0.5, 1.0, 2.0, 4.0, 8.5])  # FR touches
    episodes = [(g, False) for g in good] + [(failed, True)]
    rep = analyse_episodes(episodes, DT, settle_s=0.002, n_boot=200)
    assert isinstance(rep, STSReport)
    assert [u.name for u in rep.units] == list(UNIT_NAMES)
    assert rep.n_episodes == 4 and rep.n_failed_episodes == 1
    assert rep.episode_failure_rate == 0.25
    assert rep.episode_failure_rate_ci[0] < 0.25 < rep.episode_failure_rate_ci[1]
    assert rep.any_contact
    fr = rep.unit("FR")
    assert fr.terminated_in_contact and fr.n_terminal_contacts == 1 and fr.n_contacts == 1
    assert fr.time_to_contact_s == pytest.approx(4 * DT)
    assert fr.n_samples == 3 * (3_000 - 2) + 3  # pre-contact samples enter the pool
    for u in rep.units:
        assert u.n_episodes == 4 and u.n_failed_episodes == 1
        assert u.p_unsteady >= 0.25
        assert u.p_unsteady == pytest.approx(0.25 + 0.75 * u.p_unsteady_fit)
        assert u.p_unsteady_ci[0] >= 0.25
        assert u.p_unsteady_fit < 1e-3
    assert not rep.unit("FL").terminated_in_contact and rep.unit("FL").n_contacts == 0
    assert rep.worst_p_unsteady == max(u.p_unsteady for u in rep.units)
    d = rep.to_dict()
    json.dumps(d, allow_nan=False)
    assert d["worst_unit"] in UNIT_NAMES and len(d["units"]) == 4
    rows = rep.to_rows()
    assert [row["unit"] for row in rows] == list(UNIT_NAMES)
    assert rows[1]["n_contacts"] == 1 and rows[1]["p_unsteady"] >= 0.25


def test_explicit_contact_units_and_bare_arrays():
    rng = np.random.default_rng(2)
    a = rng.normal(0.0, 1e-3, (500, 4))
    ep = EpisodeSignal(a, terminated_in_contact=True, contact_units=("RL",))
    rep = analyse_episodes([ep, a], DT, n_boot=50)
    assert rep.unit("RL").n_terminal_contacts == 1
    assert rep.unit("FL").n_terminal_contacts == 0
    assert rep.episode_failure_rate == 0.5
    with pytest.raises(ValueError, match="contact_units"):
        analyse_episodes([EpisodeSignal(a, contact_units=("RL",))], DT)
    with pytest.raises(ValueError, match="unknown contact unit"):
        analyse_episodes([EpisodeSignal(a, True, ("XX",))], DT)


def test_constant_signal_is_degenerate_not_a_crash():
    r = analyse_unit(np.full(1_000, 2e-3), DT)
    assert r.distribution == "degenerate"
    assert r.p_unsteady == 0.0 and r.p_unsteady_ci == (0.0, 0.0)
    assert r.n_contacts == 0
    r_hit = analyse_unit(np.full(1_000, -8e-3), DT)
    assert r_hit.p_unsteady == 1.0 and r_hit.n_contacts == 1
    rep = analyse_episodes([np.zeros((100, 4))], DT)
    assert rep.worst_p_unsteady == 0.0 and not rep.any_contact


# ------------------------------------------------------------------------------------------
# Input validation
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"dt_s": 0.0}, "dt_s"),
        ({"dt_s": -1e-3}, "dt_s"),
        ({"dt_s": math.nan}, "dt_s"),
        ({"clearance_m": 0.0}, "clearance_m"),
        ({"clearance_m": -0.008}, "clearance_m"),
        ({"alpha": 0.0}, "alpha"),
        ({"alpha": 1.0}, "alpha"),
        ({"alpha": 1.5}, "alpha"),
        ({"settle_s": -0.1}, "settle_s"),
        ({"n_boot": -1}, "n_boot"),
        ({"candidates": ("norm", "not_a_law")}, "candidates"),
        ({"selection_test": "bogus"}, "selection_test"),
    ],
)
def test_bad_arguments_raise_value_error_naming_them(kwargs, match):
    args = {"dt_s": DT} | kwargs
    x = np.zeros(100)
    dt = args.pop("dt_s")
    with pytest.raises(ValueError, match=match):
        analyse_unit(x, dt, **args)
    with pytest.raises(ValueError, match=match):
        analyse_episodes([np.zeros((100, 4))], dt, **args)


@pytest.mark.parametrize(
    ("bad", "word"), [(math.nan, "NaN"), (math.inf, "inf"), (-math.inf, "inf")]
)
def test_non_finite_signal_raises(bad, word):
    x = np.zeros(100)
    x[42] = bad
    with pytest.raises(ValueError, match=rf"signal.*{word}.*42"):
        analyse_unit(x, DT)
    ep = np.zeros((100, 4))
    ep[7, 2] = bad
    with pytest.raises(ValueError, match=rf"episodes\[1\] signal.*{word}"):
        analyse_episodes([np.zeros((10, 4)), ep], DT)


def test_shape_and_misc_validation():
    with pytest.raises(ValueError, match="one-dimensional"):
        analyse_unit(np.zeros((10, 2)), DT)
    with pytest.raises(ValueError, match=r"episodes\[0\].*shape"):
        analyse_episodes([np.zeros((10, 3))], DT)
    with pytest.raises(ValueError, match="episodes"):
        analyse_episodes([], DT)
    with pytest.raises(ValueError, match="std_m"):
        normal_p_unsteady(0.0, -1e-3)
    with pytest.raises(ValueError, match="clearance_m"):
        normal_p_unsteady(0.0, 1e-3, clearance_m=0.0)


# ------------------------------------------------------------------------------------------
# Numerics and the paper
# ------------------------------------------------------------------------------------------


def test_paper_normal_parameters_do_not_give_paper_p_unsteady():
    mean, std = 0.643564e-3, 1.500849e-3
    p = normal_p_unsteady(mean, std, OMEGA)
    assert p == pytest.approx(closed_form_normal(std, mean), rel=1e-9)
    assert 1e-7 < p < 1e-5  # ~4.8e-07 ...
    paper = 0.00356
    assert paper / p > 1_000  # ... three orders of magnitude below the paper's table


def test_normal_p_unsteady_keeps_tiny_tails():
    p = normal_p_unsteady(0.0, 1e-3, OMEGA)  # 8 sigma
    assert p > 0.0
    assert p == pytest.approx(closed_form_normal(1e-3), rel=1e-9)
    assert normal_p_unsteady(0.0, 0.0) == 0.0 and normal_p_unsteady(0.009, 0.0) == 1.0
    assert normal_p_unsteady(1e-3, 2e-3) == pytest.approx(normal_p_unsteady(-1e-3, 2e-3))


def test_wilson_and_format_probability():
    lo, hi = wilson_interval(0.0, 100.0)
    assert lo == 0.0 and 0.03 < hi < 0.04
    assert format_probability(5.1e-7) == "5.1e-07"
    assert format_probability(0.0) == "0"
    assert format_probability(0.99644) == "0.9964"
    assert format_probability(1 - 5.1e-7, complement_of=5.1e-7) == "1 - 5.1e-07"
    assert format_probability(math.nan) == "n/a"


def test_paper_table_markdown():
    rng = np.random.default_rng(17)
    eps = [rng.normal(0.5e-3, 1.5e-3, (5_000, 4)) for _ in range(2)]
    rep = analyse_episodes(eps, DT, n_boot=200)
    md = paper_table_markdown(rep, "Table 2: PD controller")
    assert md.startswith("**Table 2: PD controller**")
    lines = md.splitlines()
    rows = [ln for ln in lines if re.match(r"\| (FL|FR|RL|RR) \|", ln)]
    assert [r.split("|")[1].strip() for r in rows] == ["FL", "FR", "RL", "RR"]
    header = next(ln for ln in lines if ln.startswith("| Unit"))
    for col in ("mean [mm]", "std [mm]", "P(steady)", "P(unsteady)", "95 % CI", "contacts"):
        assert col in header
    for u, row in zip(rep.units, rows, strict=True):
        assert u.p_unsteady < 1e-5  # tiny, so it must be in scientific notation
        assert format_probability(u.p_unsteady) in row
        assert re.search(r"\d\.\de-0\d", row)
        assert "1 - " in row  # P(steady) not rounded to 1.0000
    assert "0.0000" not in md


def test_refit_fallback_when_one_step_is_not_regular(monkeypatch):
    import hyperloop_env.sts.bootstrap as sts_module

    x = 1e-3 * np.random.default_rng(3).standard_t(2, 3_000)
    fast = analyse_unit(x, DT, n_boot=20)
    assert "one-step" in fast.ci_method
    monkeypatch.setattr(sts_module, "_one_step_replicates", lambda *a, **k: None)
    slow = analyse_unit(x, DT, n_boot=20)
    assert slow.distribution == fast.distribution == "t"
    assert "full MLE refit of 20 replicates" in slow.ci_method
    assert slow.n_boot >= 10
    lo, hi = slow.p_unsteady_fit_ci
    assert lo <= slow.p_unsteady_fit <= hi
    assert hi / lo == pytest.approx(fast.p_unsteady_fit_ci[1] / fast.p_unsteady_fit_ci[0], rel=0.5)
