"""The constrained MPC by value: with no constraint active it is the LQR (Bellman: the
terminal cost is the LQR's Riccati solution), its QP solutions respect the current, rate and
soft gap limits, the rows of a batch are independent, and bad designs are refused."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import hyperloop_env  # noqa: F401  (registration)
from agents import make_controller
from agents.controllers.mpc import MPCController, MPCDesign


def _env(**kw):
    return gym.make("HyperloopSuspension-v0", disable_env_checker=True, **kw)


def test_first_unconstrained_move_is_the_lqr_gain() -> None:
    """The condensed QP's unconstrained first move −L₀·ξ̃ equals the LQR's −K·ξ (the
    terminal cost is the Riccati solution), for every horizon."""
    env = _env(scenario="paper-1000-straight", track_length_m=60.0)
    for ms in (1.0, 5.0, 20.0):
        c = MPCController(env, MPCDesign(horizon_ms=ms))
        m = c.matrices
        k_scaled = m.K * m.sa[None, :]
        assert c.horizon_steps == round(ms)
        np.testing.assert_allclose(
            c._first_move, -k_scaled, rtol=0, atol=1e-9 * np.abs(k_scaled).max()
        )
    env.close()


def _closed_loop(ctrl_of, steps: int, seed: int, **env_kw):  # noqa: ANN001, ANN202
    """Actions (steps, 4) of a controller flying its own env; the controller."""
    env = _env(scenario="paper-1000-straight", track_length_m=200.0, **env_kw)
    obs, _ = env.reset(seed=seed)
    ctrl = ctrl_of(env)
    out = []
    for _ in range(steps):
        a = ctrl.act(obs)
        out.append(a)
        obs, _, te, tr, _ = env.step(a)
        assert not (te or tr)
    env.close()
    return np.array(out), ctrl


def test_without_active_constraints_the_mpc_flies_as_the_lqr() -> None:
    """Loose limits on a mild track (roughness 0.05: the LQR's currents stay inside their
    limits, no QP needed): the MPC flies as the LQR, 400 steps of each in its own closed
    loop (same seed), actions equal to 1e-5 (two realisations of the same law; the
    compensator alone is open-loop unstable, so only closed loops can be compared), and it
    solved no QP."""
    kw = {"disturbances": {"roughness": 0.05}}
    loose = MPCDesign(max_rate_A_per_ms=1e4, gap_limit_fraction=1.0)
    a_mpc, mpc = _closed_loop(lambda e: MPCController(e, loose), 400, 1, **kw)
    a_lqr, _ = _closed_loop(lambda e: make_controller("lqr", e), 400, 1, **kw)
    np.testing.assert_allclose(a_mpc, a_lqr, rtol=0, atol=1e-5)
    assert mpc.stats["qp_solves"] == 0 and mpc.stats["steps"] == 400


def test_rate_limit_holds_where_the_lqr_exceeds_it() -> None:
    """A 5 A/ms current-rate limit: the LQR's commands jump by more (its own loop, default
    roughness), the MPC's never do, and its QP solves reach 'solved'."""
    i0 = 40.51110597376678  # I0 at the default parameters [A] (checked below)
    a_lqr, lqr = _closed_loop(lambda e: make_controller("lqr", e), 300, 1)
    assert lqr.ctx.nominal_current_A == pytest.approx(i0, rel=1e-12)
    jumps = np.abs(np.diff(np.vstack([np.zeros(4), a_lqr]), axis=0)) * i0
    assert jumps.max() > 5.0
    a_mpc, mpc = _closed_loop(lambda e: MPCController(e, MPCDesign(max_rate_A_per_ms=5.0)), 300, 1)
    jumps = np.abs(np.diff(np.vstack([np.zeros(4), a_mpc.astype(np.float64)]), axis=0)) * i0
    assert jumps.max() <= 5.0 + 1e-3
    assert mpc.stats["qp_solves"] > 0 and mpc.stats["qp_unsolved"] == 0


def test_qp_solution_keeps_the_predicted_gaps_inside_the_soft_limit() -> None:
    """A tight soft limit (0.4 mm): where the unconstrained optimum predicts a gap beyond it,
    the QP's solution predicts every gap within s_max + ε, ε ≥ 0, the currents inside their
    limits and the rates within Δu — checked on the QP's own prediction matrices."""
    env = _env(scenario="paper-1000-straight", track_length_m=300.0)
    obs, _ = env.reset(seed=4)
    c = MPCController(env, MPCDesign(gap_limit_fraction=0.05))
    seen = 0
    orig = c._solve

    def check(xi, st, i):  # noqa: ANN001, ANN202
        nonlocal seen
        u_prev = st.U[:, i].copy()
        u0 = orig(xi, st, i)
        z = st.ws_x[i]
        U, eps = z[: c._nu], z[c._nu :]
        gaps = c._Gsx @ xi + _gsu(c) @ U
        tol = 1e-6  # DAQP's primal feasibility tolerance
        assert c.last_status == 1, c.last_status  # DAQP: optimal
        assert (eps >= -tol).all()
        lim = c._s_max + 1e-3 * np.tile(eps, len(c.gap_check_steps))
        assert (np.abs(gaps) <= lim + tol * 1e-3).all()
        assert (U >= c._u_lo - tol).all() and (U <= c._u_hi + tol).all()
        U3 = U.reshape(c.horizon_steps, 4)
        assert np.abs(U3[0] - u_prev).max() <= c._du + tol
        assert np.abs(np.diff(U3, axis=0)).max() <= c._du + tol
        if np.abs(c._LW[c._nu :] @ xi).max() > c._s_max:
            seen += 1
        return u0

    c._solve = check
    for _ in range(300):
        obs, _, te, tr, _ = env.step(c.act(obs))
        assert not (te or tr)
    assert seen > 10
    env.close()


def _gsu(c: MPCController) -> np.ndarray:
    """The gaps' response to the inputs [m/A], as given to the solver (in mm/A)."""
    return c._Gsu_mm * 1e-3


@pytest.mark.parametrize("actuators", ["levitation", "levitation+guidance"])
def test_act_batch_rows_are_single_controllers(actuators: str) -> None:
    """act_batch row i equals a single MPC fed row i's observations bit for bit, with QPs
    solved on some rows (tight limits) and a reset of one row in between."""
    env = _env(scenario="paper-1000-curved", actuators=actuators, track_length_m=60.0)
    env.reset(seed=0)
    d = MPCDesign(max_rate_A_per_ms=3.0, gap_limit_fraction=0.2)
    batch = MPCController(env, d)
    singles = [MPCController(env, d) for _ in range(3)]
    rng = np.random.default_rng(3)
    size = env.observation_space.shape[0]
    batch.reset_batch(np.ones(3, dtype=bool))
    for k in range(40):
        obs = rng.normal(0.0, 0.2, (3, size)).astype(np.float32)
        if k == 20:
            batch.reset_batch(np.array([False, True, False]))
            singles[1].reset()
        a = batch.act_batch(obs)
        for i in range(3):
            np.testing.assert_array_equal(a[i], singles[i].act(obs[i]))
    assert batch.stats["qp_solves"] > 0
    env.close()


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("horizon_ms", 0.0),
        ("horizon_ms", float("nan")),
        ("gap_limit_fraction", 1.5),
        ("max_rate_A_per_ms", -1.0),
        ("slack_linear", 0.0),
        ("max_iter", 0),
    ],
)
def test_bad_design_is_refused_naming_the_field(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        MPCDesign(**{field: value})


def test_unknown_option_is_a_type_error() -> None:
    with pytest.raises(TypeError):
        make_controller("mpc", None, horizon=10)


# -- the preview (mpc-preview) ---------------------------------------------------------------


def test_first_move_on_the_preview_is_the_finite_preview_lqr_law() -> None:
    """The augmented problem's unconstrained first move: on ξ̃ the LQR's gain, on the
    injections w_j = Δ_{j+1} − Φ_ρ Δ_j exactly lqr-preview's Σ_j G_j Δ_j, for a random
    preview Δ (Tomizuka's gains against the augmented Riccati solution)."""
    env = _env(scenario="paper-1000-straight", track_length_m=60.0)
    c = MPCController(env, preview_weight=0.5)
    lp = make_controller("lqr-preview", env)
    m, g = c.matrices, lp.gains[0]
    N = c.preview_steps
    assert N == 58  # 16 m at 1000 km/h, 1 ms steps
    na = m.Pt.shape[0]
    k_scaled = m.K * m.sa[None, :]
    np.testing.assert_allclose(
        c._first_move[:, :na], -k_scaled, rtol=0, atol=1e-9 * np.abs(k_scaled).max()
    )
    F = m.Phi[np.ix_(g.rear_cols, g.rear_cols)]
    D = np.vstack([np.zeros(4), np.random.default_rng(0).normal(0.0, 1e-3, (N, 4))])
    w = np.concatenate([D[j + 1] - F @ D[j] for j in range(N)])
    u_mpc = c._first_move[:, na:] @ (w * c._inv_sa[na:])
    u_lqr = -sum((g.pure[j] if j < N else g.tail[N]) @ D[j] for j in range(1, N + 1))
    np.testing.assert_allclose(u_mpc, u_lqr, rtol=0, atol=1e-9 * np.abs(u_lqr).max())
    assert np.abs(u_lqr).max() > 1.0  # [A]: the preview moves the currents
    env.close()


def test_without_active_constraints_mpc_preview_flies_as_lqr_preview() -> None:
    """As the plain MPC and the LQR: loose limits, a mild track, 400 steps (the preview
    active from step 58): mpc-preview's actions equal lqr-preview's to 1e-5, no QP solved;
    preview_weight=0 is the plain MPC bit for bit."""
    kw = {"disturbances": {"roughness": 0.05}}
    loose = MPCDesign(max_rate_A_per_ms=1e4, gap_limit_fraction=1.0)
    a_mpc, mpc = _closed_loop(
        lambda e: make_controller("mpc-preview", e, design=loose), 400, 1, **kw
    )
    a_lp, _ = _closed_loop(lambda e: make_controller("lqr-preview", e), 400, 1, **kw)
    a_lqr, _ = _closed_loop(lambda e: make_controller("lqr", e), 400, 1, **kw)
    np.testing.assert_allclose(a_mpc, a_lp, rtol=0, atol=1e-5)
    assert np.abs(a_lp - a_lqr).max() > 0.05
    assert mpc.stats["qp_solves"] == 0 and mpc.preview_weight == 0.5
    a0, m0 = _closed_loop(lambda e: MPCController(e, loose, preview_weight=0.0), 100, 1, **kw)
    a1, _ = _closed_loop(lambda e: MPCController(e, loose), 100, 1, **kw)
    np.testing.assert_array_equal(a0, a1)
    assert m0.preview_steps == 0


def test_mpc_preview_batch_rows_are_single_controllers() -> None:
    """act_batch row i equals a single mpc-preview fed row i's observations bit for bit
    (recorded closed-loop observations, tight limits so that QPs are solved, one row reset
    half-way)."""
    d = MPCDesign(max_rate_A_per_ms=3.0, gap_limit_fraction=0.05)
    obs = []
    for seed in (0, 1, 2):
        env = _env(scenario="paper-1000-straight", track_length_m=100.0)
        o, _ = env.reset(seed=seed)
        ctrl = make_controller("lqr", env)
        rows = []
        for _ in range(160):
            rows.append(o)
            o, *_ = env.step(ctrl.act(o))
        obs.append(rows)
        env.close()
    obs = np.array(obs, dtype=np.float32)
    env = _env(scenario="paper-1000-straight", track_length_m=100.0)
    batch = make_controller("mpc-preview", env, design=d)
    singles = [make_controller("mpc-preview", env, design=d) for _ in range(3)]
    batch.reset_batch(np.ones(3, dtype=bool))
    for k in range(obs.shape[1]):
        if k == 80:
            batch.reset_batch(np.array([False, True, False]))
            singles[1].reset()
        a = batch.act_batch(obs[:, k])
        for i in range(3):
            np.testing.assert_array_equal(a[i], singles[i].act(obs[i, k]), err_msg=f"{k}")
    assert batch.stats["qp_solves"] > 0
    env.close()


def test_bad_preview_weight_is_refused() -> None:
    for bad in (-1.0, 3.0, float("nan"), True):
        with pytest.raises(ValueError, match="preview_weight"):
            MPCController(None, preview_weight=bad)


class _NoIdleHook:
    """The MPC without ``idle_batch`` (the engine then cannot tell it its idle rows)."""

    def __init__(self, mpc: MPCController) -> None:
        self.mpc = mpc

    def act_batch(self, obs: np.ndarray) -> np.ndarray:
        return self.mpc.act_batch(obs)

    def reset_batch(self, mask: np.ndarray) -> None:
        self.mpc.reset_batch(mask)


def test_idle_rows_skip_their_qps_and_the_runs_stay_bit_for_bit() -> None:
    """In the rollout engine a row that ran out of work idles (held, on zero currents):
    without the hook the MPC solves a QP for it at most of its steps; with ``idle_batch``
    it solves none there, and every run ends exactly as without the hook."""
    from agents.evaluation import engine
    from agents.evaluation.rollout import episode_config

    cfg = episode_config("paper-1000-straight", 0.3, None, {})
    jobs = [engine.Job(5, {"joint_steps": 0.02}), engine.Job(3, {"roughness": 0.3})]
    ends, ctrls = [], []
    for hook in (True, False):
        mpc = engine.build_controller("mpc", cfg)
        sched = engine.Jobs(jobs)
        run = engine.run(mpc if hook else _NoIdleHook(mpc), cfg, 2, sched)
        ends.append(sched.ends)
        ctrls.append(mpc)
    a, b = ends
    assert a[0].terminated and not a[1].terminated  # row 0 idles from its contact on
    for x, y in zip(a, b, strict=True):
        assert (x.terminated, x.n_steps) == (y.terminated, y.n_steps)
        np.testing.assert_array_equal(x.last, y.last)
    idle_steps = run.steps // 2 - a[0].n_steps
    with_hook, without = ctrls[0].stats, ctrls[1].stats
    assert with_hook["idle_rows"] == idle_steps and without["idle_rows"] == 0
    extra = without["qp_solves"] - with_hook["qp_solves"]
    assert extra >= 0.5 * idle_steps  # the QPs the idle row no longer needs (70 % of them)
    with pytest.raises(ValueError, match="idle_batch: mask"):
        ctrls[0].idle_batch(np.ones(3, dtype=bool))


def _checks_by_numpy(Z, U, nu, lims):  # noqa: ANN001, ANN202
    """The unconstrained optimum's limits as whole-array NumPy comparisons."""
    s_max, lo, hi, du = lims
    ok = (np.abs(Z[nu:]) <= s_max).all(axis=0)
    ok &= ((Z[:nu] >= lo) & (Z[:nu] <= hi)).all(axis=0)
    ok &= (np.abs(Z[:4] - U) <= du).all(axis=0)
    ok &= (np.abs(Z[4:nu] - Z[: nu - 4]) <= du).all(axis=0)
    return ok


def test_compiled_limit_checks_and_qp_rows_match_numpy() -> None:
    """:func:`mpc.unconstrained` on random products near every limit (and NaN): ``Z``
    equals ``LW @ xi`` to rounding, ``ok`` equals the NumPy form of the limits bit for bit,
    the first moves are ``Z[:4]``, and the rows that need a QP are the not-ok, not-idle
    ones in order."""
    from agents.controllers.mpc import unconstrained

    rng = np.random.default_rng(7)
    nu, na, B = 16, 9, 37
    lims = np.array([1.0, -3.0, 3.0, 0.5])
    n_ok = 0
    for trial in range(40):
        LW = rng.standard_normal((nu + 8, na))
        xi = rng.standard_normal((na, B)) * rng.uniform(0.02, 0.4)
        if trial % 5 == 0:
            xi[trial % na, trial % B] = np.nan
        U = rng.standard_normal((4, B)) * 0.1
        idle = rng.random(B) < 0.2
        Z, ok = np.zeros((nu + 8, B)), np.zeros(B, dtype=np.bool_)
        U0, bad = np.zeros((4, B)), np.full(B, -1, dtype=np.int64)
        n = unconstrained(LW, xi, nu, lims, U, idle, Z, ok, U0, bad)
        np.testing.assert_allclose(Z, LW @ xi, rtol=1e-12, atol=1e-12)
        want = _checks_by_numpy(Z, U, nu, lims)
        assert np.array_equal(ok, want), trial
        n_ok += int(want.sum())
        assert np.array_equal(U0, Z[:4], equal_nan=True)
        assert bad[:n].tolist() == np.flatnonzero(~(want | idle)).tolist()
    assert 0.1 < n_ok / (40 * B) < 0.9  # both outcomes, many times


def test_compiled_action_clip_is_numpys() -> None:
    """:func:`mpc.finish` writes ``np.clip(a·U0, lo, hi)`` as float32, bit for bit,
    including the bounds themselves, a signed zero at a zero bound and NaN."""
    from agents.controllers.mpc import finish

    a, lo, hi = 0.7, 0.0, 2.0
    U0 = np.array([[-1.0, -0.0, 0.0, 1.0, 2.0 / 0.7, 5.0, np.nan, 1e-30]] * 4)
    B = U0.shape[1]
    n = 3
    Q, Y, X, T, U = (np.zeros((4, B)), np.zeros((4, B)), np.zeros((n, B)), np.zeros((n, B)),
                     np.zeros((4, B)))  # fmt: skip
    out = np.full((B, 7), 9.0, dtype=np.float32)
    limits = np.array([a, lo, hi])
    Uc = U0.copy()
    finish(Uc, -10.0, 10.0, Q, Y, 1e-3, 1.0, np.eye(n), np.zeros((n, B)), X, np.zeros((n, 4)),
           T, U, limits, out, 2)  # fmt: skip
    want = np.clip(a * U0, lo, hi).T.astype(np.float32)
    assert out[:, 2:6].tobytes() == want.tobytes()
    assert (out[:, :2] == 9.0).all() and (out[:, 6:] == 9.0).all()
