"""Controllers checked by value, not by shape: the passive baseline commands exactly the bias
currents, the PID gains are the documented pole placement and its first actions follow the
documented control law, and the LQG's first actions follow its documented
predictor–corrector equations from its own design matrices."""

from __future__ import annotations

import json
import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import hyperloop_env  # noqa: F401  (registration)
from agents import make_controller
from agents.controllers.base import control_context
from agents.controllers.lqr import LQRController, design_lqg
from agents.controllers.passive import PassiveController
from agents.controllers.pid import (
    PIDController,
    closed_loop_spectral_radius,
    design_guidance_pid,
    design_pid,
    guidance_unit_model,
)
from hyperloop_env.config import EnvConfig
from hyperloop_env.physics.model import guidance_bias_A

ROOT = Path(__file__).resolve().parents[3]
GAINS_JSON = ROOT / "agents" / "controllers" / "pid_gains.json"
F0 = (15_000.0 + 22_000.0) * 9.81 / 4.0  # nominal force per unit [N]


def _env(**kw):
    return gym.make("HyperloopSuspension-v0", disable_env_checker=True, **kw)


# ---- passive -----------------------------------------------------------------------------------


@pytest.mark.parametrize("actuators", ["levitation", "levitation+guidance"])
def test_passive_commands_exactly_the_bias_currents(actuators: str) -> None:
    """Action exactly 0 on every channel, whatever the observation, and the applied currents
    are the bias currents: I_a = I0, ΔI_a = 0, so the current term of the reward is 0."""
    env = _env(scenario="paper-1000-curved", actuators=actuators, track_length_m=60.0)
    obs, info = env.reset(seed=2)
    ctrl = make_controller("passive", env)
    ctrl.reset(seed=2)
    u = env.unwrapped
    i0 = u.nominal_current_A
    n = env.action_space.shape[0]
    rng = np.random.default_rng(0)
    for k in range(60):
        a = ctrl.act(obs if k % 2 else rng.normal(0, 5, obs.shape).astype(np.float32))
        assert a.dtype == np.float32 and a.shape == (n,)
        assert np.array_equal(a, np.zeros(n, np.float32))
        obs, _, term, trunc, info = env.step(a)
        assert np.array_equal(info["current_A"], np.full(4, i0))
        assert np.array_equal(info["guidance_current_A"], np.zeros(4))
        assert info["reward_terms"]["current"] == 0.0
        assert not term
        if trunc:
            break
    batch = ctrl.act_batch(rng.normal(0, 1, (5, obs.shape[0])).astype(np.float32))
    assert np.array_equal(batch, np.zeros((5, n), np.float32))
    env.close()


def test_passive_returns_to_the_bias_through_the_coil_lag() -> None:
    """After an active phase the passive commands bring the applied currents back to I0 by
    the first-order lag of τ = 2 ms: I_k = I0 + (I_start − I0)·exp(−k·dt/τ)."""
    env = _env(scenario="paper-1000-straight", track_length_m=60.0)
    env.reset(seed=0)
    i0 = env.unwrapped.nominal_current_A
    tau, dt = 2e-3, 1e-3
    for _ in range(10):  # +30 % for 10 ms: the current approaches 1.3·I0
        obs, *_, info = env.step(np.full(4, 0.3, np.float32))
    i_start = info["current_A"].copy()
    a03 = float(np.float32(0.3))  # the action as the env receives it
    np.testing.assert_allclose(i_start, i0 + a03 * i0 * (1 - math.exp(-10 * dt / tau)), rtol=1e-9)
    passive = PassiveController(env)
    for k in range(1, 41):
        obs, *_, info = env.step(passive.act(obs))
        expected = i0 + (i_start - i0) * math.exp(-k * dt / tau)
        np.testing.assert_allclose(info["current_A"], expected, rtol=1e-9)
    np.testing.assert_allclose(info["current_A"], i0, rtol=0, atol=1e-6)  # settled: 20 τ
    env.close()


# ---- PID ----------------------------------------------------------------------------------------


def _design() -> dict[str, float]:
    return json.loads(GAINS_JSON.read_text())["design"]


@pytest.mark.parametrize(("magnet", "sigma"), [("repelling", 1.0), ("attracting", -1.0)])
def test_pid_gains_are_the_documented_pole_placement(magnet: str, sigma: float) -> None:
    """pid.py: m = (m_c + m_m)/4, k_i = 2F0/I0, k_m = 2F0/δ0, b = k_i/m, ω_m² = k_m/m;
    Kd = (2ζ + ρ)ω/b, Kp = (ω²(1 + 2ζρ) − σω_m²)/b, Ki = ρω³/b, with ω, ζ, ρ from
    agents/pid_gains.json; the closed loop λ³ + bKd λ² + (bKp + σω_m²)λ + bKi has its roots
    at −ρω and −ζω ± jω√(1 − ζ²)."""
    d = _design()
    assert (d["omega_rad_s"], d["zeta"], d["integral_ratio"]) == (60.0, 0.7, 0.2)
    w, z, r = d["omega_rad_s"], d["zeta"], d["integral_ratio"]
    p = EnvConfig(magnet=magnet).resolve().base
    ctx = control_context(p)
    i0 = ctx.nominal_current_A
    m = (15_000.0 + 22_000.0) / 4.0
    ki_, km = 2 * F0 / i0, 2 * F0 / 0.010
    b, wm2 = ki_ / m, km / m
    g = design_pid(ctx)
    assert g.sigma == sigma
    assert g.mass_kg == pytest.approx(m, rel=1e-12)
    assert g.k_current_N_per_A == pytest.approx(ki_, rel=1e-12)
    assert g.k_magnet_N_per_m == pytest.approx(km, rel=1e-12)
    assert g.kd_A_s_per_m == pytest.approx((2 * z + r) * w / b, rel=1e-12)
    assert g.kp_A_per_m == pytest.approx((w * w * (1 + 2 * z * r) - sigma * wm2) / b, rel=1e-12)
    assert g.ki_A_per_m_s == pytest.approx(r * w**3 / b, rel=1e-12)
    assert g.deriv_filter_rad_s == pytest.approx(d["deriv_filter_ratio"] * w, rel=1e-12)
    roots = np.sort_complex(
        np.roots([1.0, b * g.kd_A_s_per_m, b * g.kp_A_per_m + sigma * wm2, b * g.ki_A_per_m_s])
    )
    want = np.sort_complex(
        np.array(
            [
                -r * w,
                complex(-z * w, w * math.sqrt(1 - z * z)),
                complex(-z * w, -w * math.sqrt(1 - z * z)),
            ]
        )
    )
    np.testing.assert_allclose(roots, want, rtol=1e-9)
    # the gains stored with the design (agents/pid_gains.json) are these
    stored = json.loads(GAINS_JSON.read_text())["gains_paper_defaults"][magnet]
    for k in ("kp_A_per_m", "ki_A_per_m_s", "kd_A_s_per_m", "k_current_N_per_A"):
        assert getattr(g, k) == pytest.approx(stored[k], rel=1e-9), k
    assert closed_loop_spectral_radius(ctx, g) < 1.0


def test_guidance_pid_gains_are_the_documented_pole_placement() -> None:
    """GuidanceDesign (ω = 60 rad/s, ζ = 0.7, ρ = 0.2): m_u = m_m/4, b_g = 4F_g0/I_g0,
    k_l = 4F_g0/δg0 − (2/π)F0/b2 + K_z/4 (repelling), F_g0 = μ0N²/4·I_g0²·a2·h_g/δg0²."""
    p = EnvConfig(actuators="levitation+guidance").resolve().base
    ctx = control_context(p)
    ig0 = guidance_bias_A(p)
    f_g0 = 4e-7 * math.pi * 400.0**2 / 4.0 * ig0**2 * 1.1 * 0.05 / 0.010**2
    m_u = 22_000.0 / 4.0
    bg = 4.0 * f_g0 / ig0
    kl = 4.0 * f_g0 / 0.010 - 2.0 / math.pi * F0 / 0.10 + 6.812e5 / 4.0
    um = guidance_unit_model(ctx)
    assert um["b_N_per_A"] == pytest.approx(bg, rel=1e-12)
    assert um["k_N_per_m"] == pytest.approx(kl, rel=1e-12)
    assert um["max_current_dev_A"] == pytest.approx(min(ig0, 40.0 - ig0), rel=1e-12)
    g = design_guidance_pid(ctx)
    w, z, r = 60.0, 0.7, 0.2
    b = bg / m_u
    assert g.kd_A_s_per_m == pytest.approx((2 * z + r) * w / b, rel=1e-12)
    assert g.kp_A_per_m == pytest.approx((w * w * (1 + 2 * z * r) - kl / m_u) / b, rel=1e-12)
    assert g.ki_A_per_m_s == pytest.approx(r * w**3 / b, rel=1e-12)
    assert g.sigma == 1.0


def _obs(spec, gap=None, rate=None, lat=None, lat_rate=None) -> np.ndarray:
    o = np.zeros(spec.size)
    for name, v in (("gap", gap), ("gap_rate", rate), ("lateral", lat), ("lateral_rate", lat_rate)):
        if v is not None:
            o[spec.slice(name)] = v
    return o.astype(np.float32)


@pytest.mark.parametrize("magnet", ["repelling", "attracting"])
def test_pid_actions_follow_the_documented_control_law(magnet: str) -> None:
    """ΔI = −σ·(Kp·s + Kd·ṡ_f + Ki·∫s), a = ΔI/(I0·scale), ṡ_f the first-order low-pass of the
    measured rate (α = dt/(1/ω_f + dt)), ∫s by the forward sum s·dt, recomputed over four
    steps from hand-built observations (gap entries s/Ω, rate entries ṡ/(1 m/s))."""
    p = EnvConfig(magnet=magnet, action_scale=0.8).resolve().base
    ctrl = PIDController(p, action_scale=0.8)
    g = ctrl.gains
    ctx = ctrl.ctx
    spec = ctx.observation
    omega, dt, i0, scale = 0.008, 1e-3, ctx.nominal_current_A, 0.8
    alpha = dt / (1.0 / g.deriv_filter_rad_s + dt)
    gaps = [
        np.array([1e-4, -2e-4, 5e-5, 0.0]),
        np.array([2e-4, -1e-4, 0.0, 3e-5]),
        np.array([-1e-4, 0.0, 1e-4, 2e-4]),
        np.array([0.0, 3e-4, -3e-4, 1e-4]),
    ]
    rates = [
        np.array([0.01, -0.02, 0.0, 0.005]),
        np.array([0.1, 0.1, -0.1, 0.0]),
        np.array([-0.3, 0.0, 0.2, 0.05]),
        np.array([0.0, 0.05, -0.05, 0.0]),
    ]
    ctrl.reset(seed=0)
    filt = np.zeros(4)
    integ = np.zeros(4)
    for s, rdot in zip(gaps, rates, strict=True):
        a = ctrl.act(_obs(spec, gap=s / omega, rate=rdot))
        s32 = (s / omega).astype(np.float32).astype(np.float64) * omega  # what the obs holds
        r32 = rdot.astype(np.float32).astype(np.float64)
        filt = filt + alpha * (r32 - filt)
        integ = integ + s32 * dt
        d_i = -g.sigma * (g.kp_A_per_m * s32 + g.kd_A_s_per_m * filt + g.ki_A_per_m_s * integ)
        np.testing.assert_allclose(a, d_i / (i0 * scale), rtol=1e-5, atol=1e-7)
        assert np.all(np.abs(a) < 1.0)  # unsaturated: the law applies as written
    # sign: a gap opening on a repelling magnet asks for less current, on an attracting one
    # for more
    ctrl.reset()
    a = ctrl.act(_obs(spec, gap=np.full(4, 0.05)))
    assert np.all(np.sign(a) == (-1.0 if magnet == "repelling" else 1.0))


def test_pid_saturation_and_anti_windup() -> None:
    """Output limited to ctx.action_limits(); while saturated in the direction the error
    pushes, the integrator is frozen (conditional integration)."""
    p = EnvConfig().resolve().base
    ctrl = PIDController(p)
    g, ctx = ctrl.gains, ctrl.ctx
    spec = ctx.observation
    lo, hi = ctx.action_limits()
    assert (lo, hi) == (-1.0, 1.0)
    ctrl.reset()
    big = _obs(spec, gap=np.full(4, 2.0))  # 16 mm: Kp·s ≈ 87 A > I0, saturates at lo
    for _ in range(50):
        assert np.array_equal(ctrl.act(big), np.full(4, lo, np.float32))
    # the integrator did not wind up: one small step gives the unsaturated law with ∫s = s·dt
    alpha = 1e-3 / (1.0 / g.deriv_filter_rad_s + 1e-3)
    s = np.float32(0.01) * 0.008
    a = ctrl.act(_obs(spec, gap=np.full(4, 0.01)))
    d_i = -(g.kp_A_per_m * s + g.ki_A_per_m_s * s * 1e-3)
    assert alpha > 0 and np.allclose(a, d_i / ctx.nominal_current_A, rtol=1e-5)


def test_pid_guidance_loop_actions() -> None:
    """With the guidance pairs actuated the second loop acts on the guidance gaps (entries
    z/Ω_g) with a = ΔI/I_g0: first step −sgn(b)·(Kp·z + Kd·α·ż + Ki·z·dt)/I_g0."""
    p = EnvConfig(actuators="levitation+guidance").resolve().base
    ctrl = PIDController(p)
    gg = ctrl.guidance_gains
    spec = ctrl.ctx.observation
    ig0 = guidance_bias_A(p)
    z = np.array([1e-4, -2e-4, 3e-4, 0.0])
    zd = np.array([0.01, 0.0, -0.02, 0.03])
    a = ctrl.act(_obs(spec, lat=z / 0.008, lat_rate=zd))
    z32 = (z / 0.008).astype(np.float32).astype(np.float64) * 0.008
    zd32 = zd.astype(np.float32).astype(np.float64)
    alpha = 1e-3 / (1.0 / gg.deriv_filter_rad_s + 1e-3)
    d_i = -gg.sigma * (
        gg.kp_A_per_m * z32 + gg.kd_A_s_per_m * alpha * zd32 + gg.ki_A_per_m_s * z32 * 1e-3
    )
    lev = ctrl.ctx.actuators.slice("levitation")
    gui = ctrl.ctx.actuators.slice("guidance")
    np.testing.assert_allclose(a[gui], d_i / ig0, rtol=1e-5, atol=1e-7)
    assert np.array_equal(a[lev], np.zeros(4, np.float32))  # no gap error: no levitation action


# ---- LQR -----------------------------------------------------------------------------------------


def _lqg_reference(m, obs_list, spec, i0, scale, lo, hi, dt=1e-3, omega=0.008, g=9.81):
    """The documented LQG step, written out: y = [s (m), ΔI (A), a_heave (m/s²), 0, 0, 0];
    x = x⁻ + M(y − C x⁻); u = clip(−(Kx x + Kq q)/(I0·scale)); q ← q + dt·s;
    x⁻ ← Φx + Γ·u·I0·scale."""
    n = m.Phi.shape[0]
    kx, kq = m.K[:, :n], m.K[:, n:]
    x_pred = np.zeros(n)
    q = np.zeros(4)
    out = []
    for o in obs_list:
        o = np.asarray(o, dtype=np.float64)
        y = np.zeros(m.C.shape[0])
        y[0:4] = o[spec.slice("gap")] * omega
        y[4:8] = o[spec.slice("current")] * i0
        y[8] = o[spec.start("acc")] * g
        x = x_pred + m.M @ (y - m.C @ x_pred)
        u = np.clip(-(kx @ x + kq @ q) / (i0 * scale), lo, hi)
        q = q + dt * y[0:4]
        x_pred = m.Phi @ x + m.Gam @ (u * i0 * scale)
        out.append(u)
    return out


@pytest.mark.parametrize("magnet", ["repelling", "attracting"])
def test_lqr_actions_follow_the_documented_lqg_equations(magnet: str) -> None:
    p = EnvConfig(magnet=magnet).resolve().base
    ctrl = LQRController(p)
    m = design_lqg(p)
    assert m.has_coil_states and m.C.shape[0] == 4 + 4 + 1 + 3  # τ = 2 ms: currents measured
    assert m.closed_loop_radius < 1.0
    ctx = ctrl.ctx
    spec = ctx.observation
    rng = np.random.default_rng(5)
    obs_list = []
    for _ in range(6):
        o = np.zeros(spec.size, dtype=np.float32)
        o[spec.slice("gap")] = rng.normal(0, 0.02, 4)  # ≈ 0.16 mm
        o[spec.slice("current")] = rng.normal(0, 0.01, 4)  # ≈ 0.4 A
        o[spec.start("acc")] = rng.normal(0, 0.02)  # ≈ 0.2 m/s²
        o[spec.slice("gap_rate")] = 7.0  # not a measurement of the LQG: must be ignored
        obs_list.append(o)
    lo, hi = ctx.action_limits()
    want = _lqg_reference(m, obs_list, spec, ctx.nominal_current_A, 1.0, lo, hi)
    ctrl.reset(seed=0)
    for k, (o, w) in enumerate(zip(obs_list, want, strict=True)):
        got = ctrl.act(o)
        np.testing.assert_allclose(got, w, rtol=1e-5, atol=1e-6, err_msg=f"step {k}")
    assert np.any(np.abs(np.concatenate(want)) > 1e-3)  # the steps are not trivially zero
    # sign of the response to a gap opening on all four units (first step from reset)
    ctrl.reset()
    a = ctrl.act(_obs(spec, gap=np.full(4, 0.05)))
    assert np.all(np.sign(a) == (-1.0 if magnet == "repelling" else 1.0))


@pytest.mark.parametrize("magnet", ["repelling", "attracting"])
def test_lqr_gain_is_optimal_for_the_documented_weights(magnet: str) -> None:
    """lqr.py: per-step cost Σ (s/s_ref)² + (q/q_ref)² + (a_heave/a_ref)² + (ΔI/I_ref)² on the
    design model augmented with q_{k+1} = q_k + dt·s_k. The LQR gain K is optimal for it iff
    it is a fixed point of policy iteration: with S the cost of K (discrete Lyapunov equation
    S = A_clᵀ S A_cl + Q + KᵀRK), (R + GᵀSG)⁻¹GᵀSA gives K back. Q and R are rebuilt here
    from the documented weights (LQRDesign) and the design's own model matrices."""
    from scipy.linalg import solve_discrete_lyapunov

    from agents.controllers.lqr import LQRDesign

    d = LQRDesign()
    assert (d.s_ref_m, d.q_ref_m_s, d.a_ref_m_s2, d.i_ref_A) == (0.5e-3, 0.5e-3, 1.0, 15.0)
    p = EnvConfig(magnet=magnet).resolve().base
    m = design_lqg(p)
    n, nu, dt = m.Phi.shape[0], 4, 1e-3
    c_acc = m.C[8]  # measurement rows: 4 gaps, 4 currents, heave acceleration, 3 anchors
    A = np.zeros((n + nu, n + nu))
    A[:n, :n], A[n:, :n], A[n:, n:] = m.Phi, dt * m.C_s, np.eye(nu)
    G = np.vstack([m.Gam, np.zeros((nu, nu))])
    Q = np.zeros((n + nu, n + nu))
    Q[:n, :n] = m.C_s.T @ m.C_s / d.s_ref_m**2 + np.outer(c_acc, c_acc) / d.a_ref_m_s2**2
    Q[n:, n:] = np.eye(nu) / d.q_ref_m_s**2
    Q += 1e-9 * np.eye(n + nu) * np.trace(Q) / (n + nu)  # the documented regularisation
    R = np.eye(nu) / d.i_ref_A**2
    K = m.K
    acl = A - G @ K
    assert np.max(np.abs(np.linalg.eigvals(acl))) < 1.0
    # policy evaluation in coordinates scaled by 1/√diag(Q) (the raw problem spans ~12 decades)
    D = np.diag(1.0 / np.sqrt(np.diag(Q)))
    s_t = solve_discrete_lyapunov(np.linalg.solve(D, acl @ D).T, D @ (Q + K.T @ R @ K) @ D)
    S = np.linalg.solve(D, np.linalg.solve(D, s_t).T).T
    k_improved = np.linalg.solve(R + G.T @ S @ G, G.T @ S @ A)
    assert np.abs(k_improved - K).max() / np.abs(K).max() < 1e-5


@pytest.mark.parametrize("actuators", ["levitation", "levitation+guidance"])
def test_lqr_act_batch_is_the_batched_lqg_law(actuators: str) -> None:
    """act_batch (compiled, in the estimator's Schur coordinates) runs, per plane, the law
    Xu = X + (Y − X Cᵀ) Mᵀ, U = clip(−a·(Xu Kxᵀ + Q Kqᵀ)), Q = clip(Q + dt·Y_gaps),
    X = Xu Φᵀ + (U/a) Γᵀ, with Y the measured gaps [m], currents [A] and acceleration
    [m/s²] (non-finite → 0) and zero pseudo-measurements: here in NumPy for a few steps,
    equal up to rounding (also after a reset of some rows and with a NaN measurement)."""
    env = _env(scenario="paper-1000-curved", actuators=actuators, track_length_m=60.0)
    env.reset(seed=0)
    ctrl = make_controller("lqr", env)
    ctx = control_context(env)
    spec = ctx.observation
    planes = [
        (ctrl.vertical, ctrl._lev, "gap", "current", 0, ctx.clearance_m, ctx.nominal_current_A)
    ]
    if ctrl.lateral is not None:
        planes.append(
            (
                ctrl.lateral,
                ctrl._guid,
                "lateral",
                "current_guidance",
                1,
                ctx.params.guidance.clearance_m,
                ctx.guidance_bias_A,
            )
        )
    n = 5
    rng = np.random.default_rng(4)
    ctrl.reset_batch(np.ones(n, dtype=bool))
    ref = {id(p): (np.zeros((n, p.n)), np.zeros((n, 4))) for p, *_ in planes}
    for k in range(40):
        obs = rng.normal(0.0, 0.3, (n, spec.size)).astype(np.float32)
        if k == 20:
            obs[2, spec.start("gap")] = np.nan
            ctrl.reset_batch(np.array([False, True, False, False, True]))
            for X, Q in ref.values():
                X[[1, 4]] = 0.0
                Q[[1, 4]] = 0.0
        a = ctrl.act_batch(obs)
        o = obs.astype(np.float64)
        for p, cols, gap, cur, acc, clear, i0 in planes:
            X, Q = ref[id(p)]
            Y = np.zeros((n, p.C.shape[0]))
            Y[:, 0:4] = o[:, spec.slice(gap)] * clear
            Y[:, 4:8] = o[:, spec.slice(cur)] * i0
            Y[:, 8] = o[:, spec.start("acc") + acc] * ctx.gravity_m_s2
            Y = np.nan_to_num(Y, nan=0.0, posinf=0.0, neginf=0.0)
            Xu = X + (Y - X @ p.C.T) @ p.M.T
            U = np.clip(-p.a_per_A * (Xu @ p.Kx.T + Q @ p.Kq.T), p.lo, p.hi)
            Q[:] = np.clip(Q + p.dt * Y[:, 0:4], -p.qmax, p.qmax)
            X[:] = Xu @ p.Phi.T + (U / p.a_per_A) @ p.Gam.T
            np.testing.assert_allclose(a[:, cols], U.astype(np.float32), rtol=1e-5, atol=1e-6)
            x_est, q_est = p.estimate()
            # the Schur realisation sums in another order, with cancellation between the
            # large measurement-update terms: measured ≤ 1e-8 of the state's scale
            np.testing.assert_allclose(x_est, X, rtol=0, atol=1e-7 * np.abs(X).max())
            np.testing.assert_array_equal(q_est, Q)
    env.close()
