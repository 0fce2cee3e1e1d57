"""Each reward term against its documented formula (hyperloop_env/reward.py docstring).

The terms are evaluated one by one on hand-built measurement records and parameter vectors
(positions from ``hyperloop_env.physics.layout``), with the levitation and guidance
clearances, the currents and the weights all different, so that a term reading the wrong
field, the wrong clearance or the wrong weight gives a different number. Then the
environment is run and every term is recomputed from ``info`` (what an agent sees), which
checks the plumbing from ``RewardWeights`` through the compiled kernel to ``info``.

Formulas (reward.py)::

    gap       −w · mean_a min((s_a/Ω)², 4)
    guidance  −w · mean_a min((z_a/Ω_g)², 4)
    current   −w · [mean_a ((I_a − I0)/I0)² + mean_a (ΔI_a/I_g0)²]   (sum capped at 1e12)
    comfort   −w · min((a_heave² + a_lat²)/g², 100)
    survival  +w without contact, 0 at the contact step
    contact   −w at the contact step, else 0
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import hyperloop_env  # noqa: F401  (registration)
from hyperloop_env import kernels
from hyperloop_env.physics.layout import (
    M_ACC_HEAVE,
    M_ACC_LAT,
    M_CONTACT,
    M_GAP,
    M_I,
    M_IG,
    M_LAT,
    NM,
    NP,
    P_CLEAR,
    P_G,
    P_GCLEAR,
    P_I0,
    P_IG0,
)
from hyperloop_env.physics.model import pack_kinds
from hyperloop_env.reward import (
    REWARD_TERMS,
    comfort_term,
    contact_term,
    current_term,
    gap_term,
    guidance_term,
    survival_term,
)

OMEGA = 0.007  # levitation clearance Ω of the hand-built parameter vector [m]
OMEGA_G = 0.009  # guidance clearance Ω_g (deliberately different) [m]
I0 = 40.0  # [A]
IG0 = 16.0  # [A]
GRAV = 9.5  # [m/s²] (not 9.81: a term using another g gives another number)

GAPS = np.array([0.001, -0.0035, 0.0062, -0.0005])  # s_a [m]
LATS = np.array([-0.002, 0.0041, 0.0, 0.0079])  # z_a [m]
CURRENTS = np.array([44.0, 38.0, 40.0, 31.0])  # I_a [A]
DI = np.array([1.5, -2.0, 0.0, 4.0])  # ΔI_a [A]
ACC = (0.7, -0.4)  # a_heave, a_lat [m/s²]


def params() -> np.ndarray:
    p = np.zeros(NP)
    p[P_CLEAR] = OMEGA
    p[P_GCLEAR] = OMEGA_G
    p[P_I0] = I0
    p[P_IG0] = IG0
    p[P_G] = GRAV
    return pack_kinds(p)  # the actuator kinds' blocks (reference I0 / I_g0, record slots)


def record(
    gaps=GAPS, lats=LATS, currents=CURRENTS, di=DI, acc=ACC, contact: bool = False
) -> np.ndarray:
    r = np.zeros(NM)
    r[M_GAP : M_GAP + 4] = gaps
    r[M_LAT : M_LAT + 4] = lats
    r[M_I : M_I + 4] = currents
    r[M_IG : M_IG + 4] = di
    r[M_ACC_HEAVE], r[M_ACC_LAT] = acc
    r[M_CONTACT] = 1.0 if contact else 0.0
    return r


# ---- the documented formulas, written out independently ------------------------------------


def gap_ref(gaps, w, omega=OMEGA):
    return -w * float(np.mean([min((s / omega) ** 2, 4.0) for s in gaps]))


def guidance_ref(lats, w, omega_g=OMEGA_G):
    return -w * float(np.mean([min((z / omega_g) ** 2, 4.0) for z in lats]))


def current_ref(currents, di, w, i0=I0, ig0=IG0):
    return -w * (float(np.mean(((currents - i0) / i0) ** 2)) + float(np.mean((di / ig0) ** 2)))


def comfort_ref(acc, w, g=GRAV):
    return -w * min((acc[0] ** 2 + acc[1] ** 2) / g**2, 100.0)


# ---- single terms on hand-built records ------------------------------------------------------


def test_gap_term_formula() -> None:
    r, p = record(), params()
    # by hand: (1/7)², (3.5/7)², (6.2/7)², (0.5/7)² → mean 0.27219, times −2.5
    by_hand = -2.5 * (1 / 49 + 0.25 + (6.2 / 7) ** 2 + 0.25 / 49) / 4
    assert gap_term(r, p, 2.5) == pytest.approx(by_hand, rel=1e-12)
    assert gap_term(r, p, 2.5) == pytest.approx(gap_ref(GAPS, 2.5), rel=1e-12)
    assert gap_term(record(gaps=np.zeros(4)), p, 2.5) == 0.0
    # −w exactly at |s| = Ω on every unit ("−w at Ω")
    at_omega = record(gaps=np.array([OMEGA, -OMEGA, OMEGA, -OMEGA]))
    assert gap_term(at_omega, p, 3.0) == pytest.approx(-3.0, rel=1e-12)
    # linear in w, independent of the other fields
    assert gap_term(r, p, 1.0) * 2.5 == pytest.approx(gap_term(r, p, 2.5), rel=1e-12)
    other = record(lats=np.zeros(4), currents=np.full(4, I0), di=np.zeros(4), acc=(0.0, 0.0))
    assert gap_term(other, p, 2.5) == gap_term(r, p, 2.5)


def test_gap_term_cap_and_non_finite() -> None:
    p = params()
    # |s| = 3Ω on one unit: capped at 4 for that unit only (|s| = 2Ω)
    g = np.array([3 * OMEGA, 0.5 * OMEGA, 0.0, 0.0])
    assert gap_term(record(gaps=g), p, 1.0) == pytest.approx(-(4.0 + 0.25) / 4, rel=1e-12)
    g2 = np.array([2 * OMEGA, 0.0, 0.0, 0.0])  # exactly at the cap
    assert gap_term(record(gaps=g2), p, 1.0) == pytest.approx(-1.0, rel=1e-12)
    # every unit beyond 2Ω: the term's floor −4w
    assert gap_term(record(gaps=np.full(4, 0.05)), p, 1.5) == pytest.approx(-6.0, rel=1e-12)
    # non-finite input: the cap of that unit (4), never NaN
    for bad in (math.nan, math.inf, -math.inf):
        g3 = np.array([bad, 0.5 * OMEGA, 0.0, 0.0])
        v = gap_term(record(gaps=g3), p, 1.0)
        assert v == pytest.approx(-(4.0 + 0.25) / 4, rel=1e-12), bad
    v = gap_term(record(gaps=np.full(4, math.nan)), p, 2.0)
    assert v == pytest.approx(-8.0, rel=1e-12)


def test_guidance_term_formula_uses_the_guidance_clearance() -> None:
    r, p = record(), params()
    assert guidance_term(r, p, 0.8) == pytest.approx(guidance_ref(LATS, 0.8), rel=1e-12)
    # with Ω (not Ω_g) the value would differ: the test discriminates the clearance
    assert guidance_ref(LATS, 0.8) != pytest.approx(guidance_ref(LATS, 0.8, OMEGA), rel=1e-3)
    lat = np.array([3 * OMEGA_G, math.nan, 0.5 * OMEGA_G, 0.0])
    assert guidance_term(record(lats=lat), p, 1.0) == pytest.approx(-(4 + 4 + 0.25) / 4, rel=1e-12)
    # the guidance term does not read the levitation gaps and vice versa
    assert guidance_term(record(gaps=np.full(4, 0.02)), p, 0.8) == guidance_term(r, p, 0.8)
    assert gap_term(record(lats=np.full(4, 0.02)), p, 0.8) == gap_term(r, p, 0.8)


def test_current_term_formula() -> None:
    r, p = record(), params()
    # by hand: ((4/40)² + (2/40)² + 0 + (9/40)²)/4 + ((1.5/16)² + (2/16)² + 0 + (4/16)²)/4
    lev = (0.01 + 0.0025 + 0.0 + 0.050625) / 4
    gui = ((1.5 / 16) ** 2 + (2 / 16) ** 2 + (4 / 16) ** 2) / 4
    assert current_term(r, p, 0.05) == pytest.approx(-0.05 * (lev + gui), rel=1e-12)
    assert current_term(r, p, 0.05) == pytest.approx(current_ref(CURRENTS, DI, 0.05), rel=1e-12)
    # at the bias currents the term is exactly 0 (the passive suspension costs nothing)
    assert current_term(record(currents=np.full(4, I0), di=np.zeros(4)), p, 0.05) == 0.0
    # the guidance part alone, normalised by I_g0 (not by I0)
    only_g = record(currents=np.full(4, I0))
    assert current_term(only_g, p, 1.0) == pytest.approx(-gui, rel=1e-12)


def test_current_term_cap_and_non_finite() -> None:
    p = params()
    cap = -0.05 * 1e12 / 4  # the sum of squares is capped at 1e12
    for bad in (math.nan, math.inf):
        c = np.array([bad, I0, I0, I0])
        assert current_term(record(currents=c, di=np.zeros(4)), p, 0.05) == pytest.approx(cap)
        assert current_term(record(di=np.array([0.0, bad, 0.0, 0.0])), p, 0.05) == pytest.approx(
            cap
        )
    huge = np.array([I0 * 1e7, I0, I0, I0])  # ((I − I0)/I0)² ≈ 1e14 > 1e12
    assert current_term(record(currents=huge, di=np.zeros(4)), p, 0.05) == pytest.approx(cap)


def test_comfort_term_formula_cap_and_non_finite() -> None:
    r, p = record(), params()
    by_hand = -1.3 * (0.49 + 0.16) / GRAV**2
    assert comfort_term(r, p, 1.3) == pytest.approx(by_hand, rel=1e-12)
    assert comfort_term(r, p, 1.3) == pytest.approx(comfort_ref(ACC, 1.3), rel=1e-12)
    # both components count: lateral alone
    assert comfort_term(record(acc=(0.0, 2.0)), p, 1.0) == pytest.approx(-4.0 / GRAV**2)
    # cap at 100 (10 g)
    assert comfort_term(record(acc=(20 * GRAV, 0.0)), p, 1.3) == pytest.approx(-130.0)
    assert comfort_term(record(acc=(10 * GRAV, 0.0)), p, 1.0) == pytest.approx(-100.0)
    for bad in (math.nan, math.inf, -math.inf):
        assert comfort_term(record(acc=(bad, 0.1)), p, 2.0) == pytest.approx(-200.0), bad
        assert comfort_term(record(acc=(0.1, bad)), p, 2.0) == pytest.approx(-200.0), bad


def test_survival_and_contact_terms() -> None:
    p = params()
    flying, touching = record(contact=False), record(contact=True)
    assert survival_term(flying, p, 1.7) == 1.7
    assert survival_term(touching, p, 1.7) == 0.0
    assert contact_term(flying, p, 100.0) == 0.0
    assert contact_term(touching, p, 100.0) == -100.0
    # they read only the contact flag
    assert survival_term(record(gaps=np.full(4, 0.1), contact=False), p, 1.0) == 1.0


def test_kernel_orders_terms_and_weights_like_reward_terms() -> None:
    """kernels.reward: terms in the order of REWARD_TERMS, each with its own weight, the
    reward their sum; a reset row gets zeros and a skipped row is left alone."""
    p = params()
    weights = np.array([2.0, 3.0, 0.07, 1.1, 0.9, 55.0])
    recs = np.stack([record(), record(contact=True), record(), record()])
    P = np.stack([p] * 4)
    mode = np.array(
        [kernels.MODE_STEP, kernels.MODE_STEP, kernels.MODE_RESET, kernels.MODE_SKIP], dtype=np.int8
    )
    terms = np.full((4, len(REWARD_TERMS)), 7.0)
    out = np.full(4, 7.0)
    kernels.reward(recs, P, mode, weights, terms, out)
    for i, contact in ((0, False), (1, True)):
        expected = {
            "gap": gap_ref(GAPS, 2.0),
            "guidance": guidance_ref(LATS, 3.0),
            "current": current_ref(CURRENTS, DI, 0.07),
            "comfort": comfort_ref(ACC, 1.1),
            "survival": 0.0 if contact else 0.9,
            "contact": -55.0 if contact else 0.0,
        }
        got = dict(zip(REWARD_TERMS, terms[i], strict=True))
        for k in REWARD_TERMS:
            assert got[k] == pytest.approx(expected[k], rel=1e-12, abs=1e-15), (i, k)
        assert out[i] == pytest.approx(sum(expected.values()), rel=1e-12)
    assert np.all(terms[2] == 0.0) and out[2] == 0.0
    assert np.all(terms[3] == 7.0) and out[3] == 7.0


# ---- through the environment -----------------------------------------------------------------

WEIGHTS = {
    "gap_weight": 2.0,
    "guidance_weight": 3.0,
    "current_weight": 0.07,
    "comfort_weight": 1.1,
    "survival_weight": 0.9,
    "contact_weight": 55.0,
}


def _recompute(info, env) -> dict[str, float]:
    u = env.unwrapped
    p = u.params
    omega, omega_g = p.magnet.clearance_m, p.guidance.clearance_m
    g = p.simulation.gravity_m_s2
    i0 = u.nominal_current_A
    from hyperloop_env.physics.model import guidance_bias_A

    ig0 = guidance_bias_A(p)
    contact = bool(info["contact"])
    return {
        "gap": gap_ref(info["gap_excursion_m"], WEIGHTS["gap_weight"], omega),
        "guidance": guidance_ref(info["lateral_offset_m"], WEIGHTS["guidance_weight"], omega_g),
        "current": current_ref(
            info["current_A"], info["guidance_current_A"], WEIGHTS["current_weight"], i0, ig0
        ),
        "comfort": comfort_ref(info["acceleration_m_s2"], WEIGHTS["comfort_weight"], g),
        "survival": 0.0 if contact else WEIGHTS["survival_weight"],
        "contact": -WEIGHTS["contact_weight"] if contact else 0.0,
    }


@pytest.mark.parametrize(
    "kwargs",
    [
        # Ω = 6 mm ≠ Ω_g = 8 mm; the attracting magnet touches within ~0.1 s under random
        # currents, so the contact step is covered too
        {
            "scenario": "paper-1000-curved",
            "clearance_m": 0.006,
            "magnet": "attracting",
            "actuators": "levitation+guidance",
        },
        {"scenario": "paper-2000-straight", "irregularity": "maglev-rough"},
    ],
)
def test_env_reward_terms_recomputed_from_info(kwargs) -> None:
    env = gym.make("HyperloopSuspension-v0", track_length_m=120.0, **WEIGHTS, **kwargs)
    rng = np.random.default_rng(3)
    env.reset(seed=4)
    seen_contact = False
    n = 0
    for _ in range(1000):
        a = rng.uniform(-0.4, 0.4, env.action_space.shape).astype(np.float32)
        _, reward, term, trunc, info = env.step(a)
        n += 1
        expected = _recompute(info, env)
        got = info["reward_terms"]
        assert list(got) == list(REWARD_TERMS)
        for k in REWARD_TERMS:
            assert got[k] == pytest.approx(expected[k], rel=1e-9, abs=1e-15), (n, k)
        assert reward == pytest.approx(sum(expected.values()), rel=1e-9, abs=1e-12)
        seen_contact |= bool(info["contact"])
        if term or trunc:
            break
    assert n > 10
    if kwargs.get("magnet") == "attracting":
        assert seen_contact and info["reward_terms"]["contact"] == -55.0
    env.close()


def test_vector_env_reward_terms_match_the_formula() -> None:
    from hyperloop_env.vector_env import HyperloopSuspensionVectorEnv

    envs = HyperloopSuspensionVectorEnv(
        num_envs=3, scenario="paper-1000-straight", track_length_m=50.0, **WEIGHTS
    )
    envs.reset(seed=1)
    rng = np.random.default_rng(0)
    for _ in range(30):
        _, reward, _, _, info = envs.step(rng.uniform(-0.5, 0.5, (3, 4)).astype(np.float32))
        gaps = info["gap_excursion_m"]
        for i in range(3):
            assert info["reward_terms"]["gap"][i] == pytest.approx(
                gap_ref(gaps[i], WEIGHTS["gap_weight"], 0.008), rel=1e-9
            )
            total = sum(info["reward_terms"][k][i] for k in REWARD_TERMS)
            assert reward[i] == pytest.approx(total, rel=1e-12)
    envs.close()


@pytest.mark.parametrize("actuators", ["levitation", "levitation+guidance"])
def test_step_outcome_equals_observe_and_reward_bit_for_bit(actuators: str) -> None:
    """The vector env's fused step (:func:`kernels.step_outcome`: the reward's gap, guidance
    and current sums taken from the observation's quotients) against the separate
    :func:`kernels.observe` and :func:`kernels.reward` of the single env, bit for bit, on
    records with gaps beyond the cap, NaN and infinite entries, huge currents and reset rows;
    with and without the guidance currents in the observation."""
    from hyperloop_env.vector_env import PREVIEW, HyperloopSuspensionVectorEnv

    n = 12
    envs = HyperloopSuspensionVectorEnv(
        num_envs=n, scenario="paper-2000-curved", actuators=actuators, **WEIGHTS
    )
    envs.reset(seed=5)
    s = envs.sim
    rng = np.random.default_rng(11)
    rec = s.MEAS.copy()
    rec[:, M_GAP : M_GAP + 4] = rng.uniform(-0.02, 0.02, (n, 4))  # beyond 2Ω in places
    rec[:, M_LAT : M_LAT + 4] = rng.uniform(-0.02, 0.02, (n, 4))
    rec[:, M_I : M_I + 4] *= rng.uniform(0.5, 1.5, (n, 4))
    rec[:, M_IG : M_IG + 4] = rng.uniform(-5.0, 5.0, (n, 4))
    rec[1, M_GAP + 2] = np.nan
    rec[2, M_LAT + 3] = np.inf
    rec[3, M_I + 1] = -np.inf
    rec[4, M_IG] = np.nan
    rec[5, M_I] = 1e9  # the current sum's cap
    rec[6, M_CONTACT] = 1.0
    prev_done = np.zeros(n, dtype=np.bool_)
    prev_done[[0, 7]] = True  # reset rows: zero rates and rewards
    prev = rng.uniform(-0.01, 0.01, (n, 8))
    m = envs._obs.shape[1]
    args = (s.P, envs._offsets, PREVIEW)
    obs_f, terms_f, rew_f, prev_f = (
        np.zeros((n, m), np.float32),
        np.zeros((n, 6)),
        np.zeros(n),
        prev.copy(),
    )
    mode = np.zeros(n, dtype=np.int8)
    flags = [np.zeros(n, dtype=np.bool_) for _ in range(3)]
    kernels.step_outcome(
        rec, s.P, prev_f, mode, obs_f, envs._offsets, PREVIEW, envs._weights, terms_f,
        rew_f, prev_done, np.zeros(n, np.int64), np.full(n, 99, np.int64),
        np.zeros(0, np.int64), M_CONTACT, *flags,
    )  # fmt: skip
    obs_s, terms_s, rew_s, prev_s = (
        np.zeros((n, m), np.float32),
        np.zeros((n, 6)),
        np.zeros(n),
        prev.copy(),
    )
    mode_s = np.where(prev_done, kernels.MODE_RESET, kernels.MODE_STEP).astype(np.int8)
    kernels.observe(rec, args[0], prev_s, mode_s, obs_s, args[1], args[2])
    kernels.reward(rec, s.P, mode_s, envs._weights, terms_s, rew_s)
    assert np.array_equal(mode, mode_s)
    assert np.array_equal(obs_f, obs_s) and np.isfinite(obs_f).all()
    assert np.array_equal(prev_f, prev_s, equal_nan=True)
    assert np.array_equal(terms_f, terms_s) and np.array_equal(rew_f, rew_s)
    gaps = rec[1, M_GAP : M_GAP + 4].copy()
    gaps[2] = 1.0  # the NaN gap counts as the cap
    assert terms_f[1, 0] == pytest.approx(gap_ref(gaps, WEIGHTS["gap_weight"], s.P[1, P_CLEAR]))
    assert terms_f[5, 2] == -WEIGHTS["current_weight"] * 1e12 / 4  # the current sum's cap
    assert np.all(terms_f[[0, 7]] == 0.0) and np.all(rew_f[[0, 7]] == 0.0)
    assert flags[0][6] and not flags[0][[0, 1, 2, 3, 4, 5, 7]].any()
    envs.close()
